// The archives that walk a struct's declared keys (core/config_schema.h), on a made-up struct:
// the strict reader (io/config_archive.h), the JSON archive, the YAML writer and the key table.
#include "rotorguard/io/config_archive.h"

#include <gtest/gtest.h>

#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/json_archive.h"
#include "rotorguard/io/key_table.h"
#include "rotorguard/io/yaml_writer.h"

namespace rotorguard::io {
namespace {

enum class Shape { kRound, kSquare };
constexpr EnumName<Shape> kShapeNames[] = {{Shape::kRound, "round"}, {Shape::kSquare, "square"}};
constexpr std::span<const EnumName<Shape>> NamesOf(const Shape*) { return kShapeNames; }

double GramsFromKilograms(double kg) { return 1e3 * kg; }
double KilogramsFromGrams(double g) { return 1e-3 * g; }

struct Leg {
  double length_m = 1.0;
  int count = 2;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("length_m", &length_m, {.meaning = "[m]", .positive = true, .required = true});
    a->Visit("count", &count, {.meaning = "legs alike", .min = 1, .max = 8});
  }
  bool operator==(const Leg&) const = default;
};

struct Method {
  std::string name = "slow";
  double rate_hz = 10.0;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("name", &name, {.meaning = "which"});
    a->Visit("rate_hz", &rate_hz, {.meaning = "[Hz]", .positive = true});
  }
};

/// Every kind of key the vehicle and scenario files use.
struct Probe {
  double gain = 0.5;
  std::string label = "probe";
  Shape shape = Shape::kRound;
  Eigen::Vector3d offset_m = Eigen::Vector3d(0.0, 0.0, 0.1);
  double mass_g = 250.0;  // written in kg
  std::vector<Leg> legs;
  Method method;  // `method: fast` is short for `method: {name: fast}`
  double tilt_rad = 0.1;
  std::optional<double> limit;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("gain", &gain, {.meaning = "a gain", .min = 0.0, .max = 1.0});
    a->Visit("label", &label, {.meaning = "a label"});
    a->Visit("shape", &shape, {.meaning = "its shape"});
    a->Visit("offset_m", &offset_m, {.meaning = "[m]"});
    a->Visit("mass_kg", ConvertedOf{&mass_g, &GramsFromKilograms, &KilogramsFromGrams},
             {.meaning = "[kg]", .positive = true});
    a->Visit("legs", &legs, {.meaning = "its legs", .min = 1});
    a->Visit("method", &method, {.meaning = "how", .shorthand = "name"});
    a->Visit("tilt_deg", DegreesOf{&tilt_rad}, {.meaning = "[deg]", .min = 0.0, .max = 90.0});
    a->Visit("limit", &limit, {.meaning = "none when absent", .positive = true});
  }
  void Validate() const {
    if (shape == Shape::kSquare && gain > 0.9) ThrowValidation("Probe", "gain", gain, "at most 0.9 for a square probe");
  }
};

Probe Read(const std::string& yaml) {
  const ConfigDocument doc = ConfigDocument::LoadString(yaml, "probe.yaml");
  Probe p;
  ReadConfig(doc.root(), &p);
  return p;
}

std::string ErrorOf(const std::string& yaml) {
  try {
    Read(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ConfigArchive, AbsentKeysKeepTheStructsDefaults) {
  const Probe p = Read("{}\n");
  const Probe d;
  EXPECT_EQ(p.gain, d.gain);
  EXPECT_EQ(p.label, d.label);
  EXPECT_EQ(p.shape, d.shape);
  EXPECT_EQ(p.offset_m, d.offset_m);
  EXPECT_EQ(p.mass_g, d.mass_g);
  EXPECT_TRUE(p.legs.empty());
  EXPECT_EQ(p.method.name, "slow");
  EXPECT_EQ(p.tilt_rad, d.tilt_rad);
  EXPECT_FALSE(p.limit.has_value());
}

TEST(ConfigArchive, EveryKindOfKeyLandsInItsFieldInItsUnit) {
  const Probe p = Read(
      "gain: 0.25\nlabel: arm\nshape: square\noffset_m: [1, 2, 3]\nmass_kg: 1.5\n"
      "legs: [{length_m: 0.3}, {length_m: 0.4, count: 3}]\nmethod: {name: fast, rate_hz: 50}\n"
      "tilt_deg: 30\nlimit: 2\n");
  EXPECT_EQ(p.gain, 0.25);
  EXPECT_EQ(p.label, "arm");
  EXPECT_EQ(p.shape, Shape::kSquare);
  EXPECT_EQ(p.offset_m, Eigen::Vector3d(1, 2, 3));
  EXPECT_DOUBLE_EQ(p.mass_g, 1500.0);
  EXPECT_EQ(p.legs, (std::vector<Leg>{{0.3, 2}, {0.4, 3}}));
  EXPECT_EQ(p.method.name, "fast");
  EXPECT_EQ(p.method.rate_hz, 50.0);
  EXPECT_DOUBLE_EQ(p.tilt_rad, M_PI / 6.0);
  EXPECT_EQ(p.limit, 2.0);
}

TEST(ConfigArchive, AShorthandIsTheBlocksKeyAlone) {
  const Probe p = Read("method: fast\n");
  EXPECT_EQ(p.method.name, "fast");
  EXPECT_EQ(p.method.rate_hz, 10.0);  // the block's other keys keep their defaults
}

TEST(ConfigArchive, ErrorsNameTheFileLineKeyAndRule) {
  EXPECT_EQ(ErrorOf("gain: 0.5\ngian: 1\n"),
            "probe.yaml:2:1: gian: unknown key 'gian'; expected one of: gain, label, shape, offset_m, mass_kg, legs, "
            "method, tilt_deg, limit");
  EXPECT_EQ(ErrorOf("gain: 2\n"), "probe.yaml:1:7: gain: '2' is out of range; expected a number in [0, 1]");
  EXPECT_EQ(ErrorOf("shape: oval\n"), "probe.yaml:1:8: shape: 'oval' is not allowed; expected one of: round, square");
  EXPECT_EQ(ErrorOf("legs: []\n"), "probe.yaml:1:7: legs: expected a non-empty list of {length_m, count}");
  EXPECT_EQ(ErrorOf("legs: [{count: 2}]\n"), "probe.yaml:1:8: legs.0: missing required key 'length_m'");
  EXPECT_EQ(ErrorOf("legs: [{length_m: 1, count: 9}]\n"),
            "probe.yaml:1:29: legs.0.count: '9' is out of range; expected an integer in [1, 8]");
  EXPECT_EQ(ErrorOf("tilt_deg: 90\n"), "probe.yaml:1:11: tilt_deg: tilt_deg = 90 is invalid; expected an angle in (0, 90) deg");
  EXPECT_EQ(ErrorOf("mass_kg: 0\n"), "probe.yaml:1:10: mass_kg: '0' is out of range; expected a positive number (> 0)");
  // The struct's own rule, reported at the key its field names.
  EXPECT_EQ(ErrorOf("shape: square\ngain: 0.95\n"),
            "probe.yaml:2:7: gain: Probe::gain = 0.95 is invalid; expected at most 0.9 for a square probe");
}

Probe Unusual() {
  Probe p;
  p.gain = 0.125;
  p.label = "a \"quoted\" label: with a colon";
  p.shape = Shape::kSquare;
  p.offset_m = Eigen::Vector3d(-1.5, 1e-7, 3.0);
  p.mass_g = 1234.5;
  p.legs = {{0.3, 2}, {0.25, 4}};
  p.method = {"fast", 25.0};
  p.tilt_rad = 0.3;
  p.limit = 7.0;
  return p;
}

void ExpectSame(const Probe& a, const Probe& b) {
  EXPECT_EQ(a.gain, b.gain);
  EXPECT_EQ(a.label, b.label);
  EXPECT_EQ(a.shape, b.shape);
  EXPECT_EQ(a.offset_m, b.offset_m);
  EXPECT_DOUBLE_EQ(a.mass_g, b.mass_g);
  EXPECT_EQ(a.legs, b.legs);
  EXPECT_EQ(a.method.name, b.method.name);
  EXPECT_EQ(a.method.rate_hz, b.method.rate_hz);
  EXPECT_DOUBLE_EQ(a.tilt_rad, b.tilt_rad);
  EXPECT_EQ(a.limit, b.limit);
}

TEST(JsonArchive, WhatItWritesReadsBackTheSame) {
  Probe original = Unusual();
  JsonWriter writer;
  original.Serialize(&writer);
  EXPECT_EQ(writer.json()["shape"], "square");
  EXPECT_DOUBLE_EQ(writer.json()["mass_kg"].get<double>(), 1.2345);  // in the file's unit
  Probe back;
  JsonReader reader(writer.json());
  back.Serialize(&reader);
  ExpectSame(back, original);
  // An unset optional is written as null and read back unset.
  original.limit.reset();
  JsonWriter unset;
  original.Serialize(&unset);
  EXPECT_TRUE(unset.json()["limit"].is_null());
}

/// The subset of the keys YamlWriter takes (the vehicle file's kinds): no block, angle or optional.
struct Part {
  std::string name = "part";
  double mass_g = 0.0;
  Shape shape = Shape::kRound;
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Identity();
  double spare = 0.0;
  std::vector<Leg> legs;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("name", &name);
    a->Visit("mass_kg", ConvertedOf{&mass_g, &GramsFromKilograms, &KilogramsFromGrams}, {.required = true});
    a->Visit("shape", &shape);
    a->Visit("offset_m", &offset_m);
    a->Visit("inertia", &inertia);
    a->Visit("spare", &spare);
    a->Visit("legs", &legs, {.min = 1});
  }
};

TEST(YamlWriter, WhatItWritesTheStrictReaderReadsBackTheSame) {
  Part p;
  p.name = "arm: left";
  p.mass_g = 0.1;  // 1e-4 kg: written in its shortest exact form
  p.shape = Shape::kSquare;
  p.offset_m = Eigen::Vector3d(0.1, -0.2, 1.0 / 3.0);
  p.inertia << 1, 0.5, 0, 0.5, 2, 0, 0, 0, 3;
  p.legs = {{0.3, 2}, {0.1, 1}};
  YamlWriter writer;
  p.Serialize(&writer);
  const std::string yaml = writer.text();
  EXPECT_EQ(yaml.find("spare"), std::string::npos) << "an optional key at zero is left out:\n" << yaml;
  EXPECT_NE(yaml.find("  - {length_m: 0.3, count: 2}\n"), std::string::npos) << yaml;
  Part back;
  back.spare = 0.0;
  ReadConfig(ConfigDocument::LoadString(yaml, "part.yaml").root(), &back);
  EXPECT_EQ(back.name, p.name);
  EXPECT_EQ(back.mass_g, p.mass_g);
  EXPECT_EQ(back.shape, p.shape);
  EXPECT_EQ(back.offset_m, p.offset_m);  // byte-exact: the shortest form that reads back the same double
  EXPECT_EQ(back.inertia, p.inertia);
  EXPECT_EQ(back.legs, p.legs);
}

TEST(KeyTable, RowsFollowTheDeclaration) {
  Probe p;
  KeyTableWriter table;
  p.Serialize(&table);
  std::vector<std::string> keys;
  for (const KeyRow& r : table.rows()) keys.push_back(r.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"gain", "label", "shape", "offset_m", "mass_kg", "legs", "legs[].length_m",
                                            "legs[].count", "method", "method.name", "method.rate_hz", "tilt_deg",
                                            "limit"}));
  const auto row = [&](const std::string& key) {
    for (const KeyRow& r : table.rows()) {
      if (r.key == key) return r;
    }
    return KeyRow{};
  };
  EXPECT_EQ(row("shape").rule, "one of `round`, `square`");
  EXPECT_EQ(row("mass_kg").value, "0.25");  // the default in the file's unit
  EXPECT_EQ(row("legs[].length_m").value, "") << "a required key has no default";
  EXPECT_NE(row("legs[].length_m").rule.find("**required**"), std::string::npos);
  EXPECT_EQ(row("tilt_deg").rule, "in (0, 90) deg");
}

/// Keys with upper bounds, as options structs declare them: a speed in (0, 50], a position each of
/// whose coordinates lies in [-10, 10], a pair in [0, 5], a count, and a block without a Validate().
struct Bounded {
  struct Inner {
    double gain = 1.0;
    template <typename Archive>
    void Serialize(Archive* a) {
      a->Visit("gain", &gain, {.meaning = "a gain", .min = 0.0, .max = 2.0});
    }
  };
  double speed_m_s = 1.0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  double lo = 1.0, hi = 2.0;
  int count = 3;
  bool flag = false;
  Inner inner;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("speed_m_s", &speed_m_s, {.meaning = "[m/s]", .max = 50.0, .positive = true});
    a->Visit("position_m", &position_m, {.meaning = "[m]", .min = -10.0, .max = 10.0});
    a->Visit("band_m", PairOf{&lo, &hi}, {.meaning = "[m]", .min = 0.0, .max = 5.0});
    a->Visit("count", &count, {.meaning = "how many", .min = 1, .max = 8});
    a->Visit("flag", &flag, {.meaning = "a switch"});
    a->Visit("inner", &inner, {.meaning = "a block"});
  }
};

std::string BoundedError(const std::string& yaml) {
  try {
    Bounded b;
    ReadConfig(ConfigDocument::LoadString(yaml, "bounded.yaml").root(), &b);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string RangeError(const Bounded& b) {
  try {
    CheckDeclaredRanges("Bounded", b);
  } catch (const ValidationError& e) {
    return e.field() + ": " + e.what();
  }
  return "(no error)";
}

// A positive number with an upper bound takes (0, max]: both ends' neighbours are told apart, and
// the error names the file, line, column, key, value and range.
TEST(ConfigArchive, APositiveKeyWithAMaximumTakesZeroExclusiveToTheMaximumInclusive) {
  EXPECT_EQ(BoundedError("speed_m_s: 50\n"), "(no error)");
  EXPECT_EQ(BoundedError("speed_m_s: 1e-9\n"), "(no error)");
  EXPECT_EQ(BoundedError("speed_m_s: 1e9\n"),
            "bounded.yaml:1:12: speed_m_s: '1e9' is out of range; expected a number in (0, 50]");
  EXPECT_EQ(BoundedError("speed_m_s: 50.001\n"),
            "bounded.yaml:1:12: speed_m_s: '50.001' is out of range; expected a number in (0, 50]");
  EXPECT_EQ(BoundedError("speed_m_s: 0\n"),
            "bounded.yaml:1:12: speed_m_s: '0' is out of range; expected a number in (0, 50]");
}

// A vector's, a pair's and a nested block's numbers are each checked, the error at the item.
TEST(ConfigArchive, EachNumberOfAListLiesInTheKeysRange) {
  EXPECT_EQ(BoundedError("position_m: [-10, 0, 10]\nband_m: [0, 5]\n"), "(no error)");
  EXPECT_EQ(BoundedError("position_m: [0, 0, 10000]\n"),
            "bounded.yaml:1:20: position_m.2: '10000' is out of range; expected a number in [-10, 10]");
  EXPECT_EQ(BoundedError("band_m: [-1, 2]\n"),
            "bounded.yaml:1:10: band_m.0: '-1' is out of range; expected a number in [0, 5]");
  EXPECT_EQ(BoundedError("inner: {gain: 3}\n"),
            "bounded.yaml:1:15: inner.gain: '3' is out of range; expected a number in [0, 2]");
}

// Validate()'s check of values set in code (CheckDeclaredRanges) enforces the ranges the loader
// does, named by the key's path.
TEST(DeclaredRanges, ValuesSetInCodeMeetTheRangesTheLoaderEnforces) {
  EXPECT_EQ(RangeError(Bounded{}), "(no error)");
  Bounded b;
  b.speed_m_s = 1e9;
  EXPECT_EQ(RangeError(b), "speed_m_s: Bounded::speed_m_s = 1000000000 is invalid; expected a number in (0, 50]");
  b = {};
  b.speed_m_s = 0.0;
  EXPECT_NE(RangeError(b), "(no error)");
  b = {};
  b.speed_m_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(RangeError(b), "(no error)") << "NaN is in no range";
  b = {};
  b.position_m.y() = -11.0;
  EXPECT_EQ(RangeError(b), "position_m.1: Bounded::position_m.1 = -11 is invalid; expected a number in [-10, 10]");
  b = {};
  b.hi = 6.0;
  EXPECT_EQ(RangeError(b), "band_m.1: Bounded::band_m.1 = 6 is invalid; expected a number in [0, 5]");
  b = {};
  b.count = 9;
  EXPECT_EQ(RangeError(b), "count: Bounded::count = 9 is invalid; expected an integer in [1, 8]");
  b = {};
  b.inner.gain = -0.5;
  EXPECT_EQ(RangeError(b), "inner.gain: Bounded::inner.gain = -0.5 is invalid; expected a number in [0, 2]");
}

TEST(KeyTable, RulesStateTheRangesAndNumbersAreMarked) {
  Bounded b;
  KeyTableWriter table;
  b.Serialize(&table);
  std::vector<std::string> rules, numeric;
  for (const KeyRow& r : table.rows()) {
    rules.push_back(r.rule);
    if (r.numeric()) numeric.push_back(r.key);
  }
  EXPECT_EQ(rules,
            (std::vector<std::string>{"in (0, 50]", "[x, y, z], each in [-10, 10]", "two numbers, each in [0, 5]",
                                      "an integer in [1, 8]", "true or false", "in [0, 2]"}));
  EXPECT_EQ(numeric, (std::vector<std::string>{"speed_m_s", "position_m", "band_m", "count", "inner.gain"}));
}

// An angle's bounds read as multiples of π.
TEST(KeyTable, AnglesBoundsAreWrittenInPi) {
  EXPECT_EQ(DeclaredRangeText({.min = -kTwoPi, .max = kTwoPi}), "in [-2π, 2π]");
  EXPECT_EQ(DeclaredRangeText({.max = std::numbers::pi / 2.0, .positive = true}), "in (0, π/2]");
  EXPECT_EQ(DeclaredRangeText({.min = -1.5 * std::numbers::pi, .max = std::numbers::pi}), "in [-3π/2, π]");
  EXPECT_EQ(DeclaredRangeText({.min = 0.0, .max = 1.5}), "in [0, 1.5]");
  EXPECT_EQ(DeclaredRangeText({}), "");
}

}  // namespace
}  // namespace rotorguard::io

#include "rotorguard/io/config_node.h"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "test_util.h"

namespace rotorguard::io {
namespace {

using ::rotorguard::testing::MatricesNear;

constexpr const char* kFile = "t.yaml";

ConfigDocument Load(const std::string& text) { return ConfigDocument::LoadString(text, kFile); }

/// Runs `fn`, which must throw ConfigError, and returns the error for field checks.
template <typename F>
ConfigError CatchConfigError(F&& fn) {
  try {
    fn();
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "expected a ConfigError";
  return ConfigError("", 0, 0, "", "");
}

// ---------------------------------------------------------------------------------------------
// yaml-cpp behaviour this layer exists to fix. If these start failing after a yaml-cpp upgrade,
// the layer may be simplified, not broken.

TEST(YamlCppAssumptions, MapIterationYieldsDuplicateKeysButLookupKeepsTheFirst) {
  const YAML::Node node = YAML::Load("x: 1\ny: 2\nx: 3\n");
  std::vector<std::string> keys;
  for (const auto& pair : node) keys.push_back(pair.first.as<std::string>());
  EXPECT_EQ(keys, (std::vector<std::string>{"x", "y", "x"}));
  EXPECT_EQ(node["x"].as<int>(), 1);
}

TEST(YamlCppAssumptions, AsDoubleAcceptsDotNanButRejectsBareNanAndOverflow) {
  EXPECT_TRUE(std::isnan(YAML::Load(".nan").as<double>()));
  EXPECT_TRUE(std::isinf(YAML::Load("-.inf").as<double>()));
  EXPECT_THROW(YAML::Load("nan").as<double>(), YAML::BadConversion);
  EXPECT_THROW(YAML::Load("1e999").as<double>(), YAML::BadConversion);
}

// ---------------------------------------------------------------------------------------------
// Errors

TEST(ConfigError, WhatHasFileLineColumnKeyPathAndMessage) {
  const ConfigError err("a.yaml", 3, 5, "sensors.imu.rate_hz", "bad");
  EXPECT_STREQ(err.what(), "a.yaml:3:5: sensors.imu.rate_hz: bad");
  EXPECT_EQ(err.file(), "a.yaml");
  EXPECT_EQ(err.line(), 3);
  EXPECT_EQ(err.column(), 5);
  EXPECT_EQ(err.key_path(), "sensors.imu.rate_hz");
  EXPECT_EQ(err.message(), "bad");
}

TEST(ConfigError, WhatOmitsUnknownLineColumnAndEmptyKeyPath) {
  EXPECT_STREQ(ConfigError("--set", 0, 0, "a.b", "bad").what(), "--set: a.b: bad");
  EXPECT_STREQ(ConfigError("a.yaml", 1, 0, "", "bad").what(), "a.yaml:1: bad");
  EXPECT_STREQ(ConfigError("a.yaml", 0, 7, "", "bad").what(), "a.yaml: bad");
}

// ---------------------------------------------------------------------------------------------
// Files

class TempDir : public rotorguard::testing::TempFolderTest {
 protected:
  void TearDown() override {
    std::error_code ec;
    std::filesystem::permissions(dir_ / "secret.yaml", std::filesystem::perms::owner_all, ec);
    TempFolderTest::TearDown();
  }
};

TEST_F(TempDir, LoadFileMissingThrowsInputFileError) {
  const std::string path = (dir_ / "missing.yaml").string();
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadFile(path), InputFileError,
                       path + ": cannot read input file: no such file");
  try {
    ConfigDocument::LoadFile(path);
  } catch (const InputFileError& e) {
    EXPECT_EQ(e.path(), path);
    EXPECT_EQ(e.reason(), "no such file");
  }
}

TEST_F(TempDir, LoadFileDirectoryThrowsInputFileError) {
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadFile(dir_.string()), InputFileError, "is a directory");
}

TEST_F(TempDir, LoadFileRefusesADeviceThatCouldBeReadForever) {
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadFile("/dev/zero"), InputFileError,
                       "/dev/zero: cannot read input file: is not a regular file");
}

TEST_F(TempDir, LoadFileUnreadableThrowsInputFileError) {
  if (::geteuid() == 0) GTEST_SKIP() << "root can read any file";
  const std::string path = Write("secret.yaml", "a: 1\n");
  std::filesystem::permissions(path, std::filesystem::perms::none);
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadFile(path), InputFileError, "permission denied");
}

// Found by fuzzing (tests/fuzz, config): a byte that is not UTF-8 passed the loader, and `run` then
// stopped writing summary.json, whose JSON must be UTF-8.
TEST(ConfigDocumentUtf8, ABrokenByteIsRefusedWithItsLineAndColumn) {
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadString("a: 1\nname: \"h\x84v\"\n", "s.yaml"), ConfigError,
                       "s.yaml:2:9: byte 0x84 is not valid UTF-8; expected UTF-8 text");
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadString("\xC0\x80: 1\n", "s.yaml"), ConfigError, "s.yaml:1:1: byte 0xC0");
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadString("a: \"\xED\xA0\x80\"\n", "s.yaml"), ConfigError,
                       "0xED");  // surrogate
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadString("a: \"\xF4\x90\x80\x80\"\n", "s.yaml"), ConfigError, "0xF4");
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadString("a: \"\xE2\x82\"\n", "s.yaml"), ConfigError, "0xE2");  // cut
  // Well-formed multi-byte text is fine: ω (2 bytes), ≥ (3), 𝜔 (4).
  EXPECT_NO_THROW(ConfigDocument::LoadString("a: \"\xCF\x89 \xE2\x89\xA5 \xF0\x9D\x9C\x94\"\n", "s.yaml"));
  ConfigDocument d = ConfigDocument::LoadString("a: 1\n", "s.yaml");
  RG_EXPECT_THROW_WITH(d.ApplyOverride("a", "\xFF"), ConfigError, "--set: a: byte 0xFF is not valid UTF-8");
}

TEST_F(TempDir, LoadFileReadsAndReportsThatFilesName) {
  const std::string path = Write("vehicle.yaml", "mass_kg: 1.5\nmasss_kg: 2\n");
  const ConfigDocument doc = ConfigDocument::LoadFile(path);
  EXPECT_EQ(doc.file(), path);
  const ConfigNode root = doc.root();
  EXPECT_DOUBLE_EQ(root.Required("mass_kg").AsDouble(), 1.5);
  EXPECT_EQ(root.Required("mass_kg").Location(), path + ":1:10");
  RG_EXPECT_THROW_WITH(root.RejectUnknownKeys(), ConfigError,
                       path + ":2:1: masss_kg: unknown key 'masss_kg'; expected one of: mass_kg");
}

TEST_F(TempDir, LoadFileMalformedReportsThatFilesName) {
  const std::string path = Write("bad.yaml", "a: 1\nb: [1, 2\n");
  const ConfigError err = CatchConfigError([&] { ConfigDocument::LoadFile(path); });
  EXPECT_EQ(err.file(), path);
  EXPECT_NE(std::string(err.what()).find(path + ":3:1: malformed YAML"), std::string::npos)
      << err.what();
}

TEST_F(TempDir, LoadFileEmptyIsAConfigError) {
  const std::string path = Write("empty.yaml", "");
  RG_EXPECT_THROW_WITH(ConfigDocument::LoadFile(path), ConfigError,
                       path + ":1: file is empty; expected a YAML map");
}

// ---------------------------------------------------------------------------------------------
// Document-level rules

TEST(ConfigDocument, EmptyDocumentsAreRejectedAtLineOne) {
  for (const std::string text : {"", "\n\n   \n", "# only a comment\n# and another\n", "---\n",
                                 "---\n...\n", "~\n"}) {
    const ConfigError err = CatchConfigError([&] { Load(text); });
    EXPECT_STREQ(err.what(), "t.yaml:1: file is empty; expected a YAML map") << "text: " << text;
    EXPECT_EQ(err.line(), 1);
  }
}

TEST(ConfigDocument, TopLevelMustBeAMap) {
  RG_EXPECT_THROW_WITH(Load("# header\n- 1\n- 2\n"), ConfigError,
                       "t.yaml:2:1: the top level is a sequence; expected a YAML map");
  RG_EXPECT_THROW_WITH(Load("42\n"), ConfigError,
                       "t.yaml:1:1: the top level is the scalar '42'; expected a YAML map");
}

TEST(ConfigDocument, MalformedYamlReportsYamlCppsLine) {
  const ConfigError err = CatchConfigError([] { Load("a: 1\n a: 2\n"); });
  EXPECT_EQ(err.line(), 2);
  EXPECT_EQ(err.column(), 3);
  EXPECT_STREQ(err.what(), "t.yaml:2:3: malformed YAML: illegal map value");

  RG_EXPECT_THROW_WITH(Load("a: 1\nb: \"\\q\"\n"), ConfigError,
                       "t.yaml:2:7: malformed YAML: unknown escape character: q");
  RG_EXPECT_THROW_WITH(Load("a: 1\nkey: - 1\n"), ConfigError,
                       "t.yaml:2:6: malformed YAML: illegal block entry");
  RG_EXPECT_THROW_WITH(Load("a: *nowhere\n"), ConfigError,
                       "t.yaml:1:4: malformed YAML: the referenced anchor is not defined");
}

TEST(ConfigDocument, StrayCommaIsAnErrorNotAHang) {
  // yaml-cpp 0.7 reports an endless run of empty documents at a stray top-level ','.
  RG_EXPECT_THROW_WITH(Load(","), ConfigError, "t.yaml:1:1: malformed YAML: unexpected ','");
  RG_EXPECT_THROW_WITH(Load("- 1\n,\n"), ConfigError,
                       "t.yaml:2:1: malformed YAML: unexpected ','");
  RG_EXPECT_THROW_WITH(Load("a: 1\n...\n,\n"), ConfigError,
                       "t.yaml:3:1: malformed YAML: unexpected ','");
}

TEST(ConfigDocument, DeepNestingIsAnErrorNotACrash) {
  RG_EXPECT_THROW_WITH(Load("a: " + std::string(100000, '[')), ConfigError,
                       "malformed YAML: nesting is deeper than");
}

TEST(ConfigDocument, SecondDocumentIsRejected) {
  RG_EXPECT_THROW_WITH(Load("a: 1\n---\nb: 2\n"), ConfigError,
                       "t.yaml:2:1: a second YAML document starts here; expected exactly one");
}

TEST(ConfigDocument, DuplicateTopLevelKeyReportedAtSecondOccurrence) {
  const ConfigError err = CatchConfigError([] { Load("a: 1\nb: 2\na: 3\n"); });
  EXPECT_STREQ(err.what(), "t.yaml:3:1: a: duplicate key 'a' (first at line 1)");
  EXPECT_EQ(err.line(), 3);
  EXPECT_EQ(err.key_path(), "a");
}

TEST(ConfigDocument, DuplicateKeyInMapInsideSequenceIsFound) {
  const std::string text =
      "faults:\n"
      "  - kind: motor\n"
      "    onset:\n"
      "      at_time_s: 1.0\n"
      "  - kind: motor\n"
      "    onset:\n"
      "      at_time_s: 1.0\n"
      "      severity: 0.5\n"
      "      at_time_s: 2.0\n";
  RG_EXPECT_THROW_WITH(
      Load(text), ConfigError,
      "t.yaml:9:7: faults.1.onset.at_time_s: duplicate key 'at_time_s' (first at line 7)");
}

TEST(ConfigDocument, DuplicateKeyInFlowMapIsFound) {
  RG_EXPECT_THROW_WITH(Load("a: 1\nb: {c: 2, c: 3}\n"), ConfigError,
                       "t.yaml:2:11: b.c: duplicate key 'c' (first at line 2)");
}

TEST(ConfigDocument, NonScalarKeysAreRejected) {
  RG_EXPECT_THROW_WITH(Load("a: 1\n? [x, y]\n: 2\n"), ConfigError,
                       "t.yaml:2:3: a map key must be a name, not a sequence");
  RG_EXPECT_THROW_WITH(Load("a: 1\n~: 2\n"), ConfigError,
                       "t.yaml:2:1: a map key must be a name, not null");
}

TEST(ConfigDocument, AliasesAreIndependentCopies) {
  ConfigDocument doc = Load("base: &b {x: 1, y: 2}\nother: *b\n");
  doc.ApplyOverride("other.x", "5");
  const ConfigNode root = doc.root();
  EXPECT_DOUBLE_EQ(root.Required("base").Required("x").AsDouble(), 1.0);
  EXPECT_DOUBLE_EQ(root.Required("other").Required("x").AsDouble(), 5.0);
  // Reading "other" must not count as reading "base".
  RG_EXPECT_THROW_WITH(root.Required("base").RejectUnknownKeys(), ConfigError,
                       "t.yaml:1:17: base.y: unknown key 'y'; expected one of: x");
  EXPECT_EQ(root.Required("other").Location(), "t.yaml:2:8");
}

TEST(ConfigDocument, RecursiveAliasIsAnError) {
  RG_EXPECT_THROW_WITH(Load("a: &x [1, *x]\n"), ConfigError,
                       "t.yaml:1:11: a.1: this alias refers to a node that contains it");
}

TEST(ConfigDocument, AliasBombIsAnErrorNotAnOutOfMemory) {
  std::string text = "l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 10; ++i) {
    text += fmt::format("l{}: &l{} [", i, i);
    for (int j = 0; j < 10; ++j) text += fmt::format("{}*l{}", j == 0 ? "" : ", ", i - 1);
    text += "]\n";
  }
  RG_EXPECT_THROW_WITH(Load(text), ConfigError, "aliases expand to more than");
}

TEST(ConfigDocument, NodesOutliveTheDocument) {
  const ConfigNode root = Load("a: 1.5\n").root();
  EXPECT_DOUBLE_EQ(root.Required("a").AsDouble(), 1.5);
}

TEST(ConfigDocument, MoveKeepsTheDocument) {
  ConfigDocument a = Load("a: 1\n");
  ConfigDocument b = std::move(a);
  EXPECT_EQ(b.file(), "t.yaml");
  EXPECT_EQ(b.root().Required("a").AsInt(), 1);
}

// ---------------------------------------------------------------------------------------------
// Maps

TEST(ConfigNodeMap, RequiredOptionalHasKeys) {
  const ConfigDocument doc = Load("vehicle:\n  mass_kg: 1.5\n  arm_m: 0.2\n  drag: ~\nname: x\n");
  const ConfigNode root = doc.root();
  EXPECT_TRUE(root.IsMap());
  EXPECT_EQ(root.key_path(), "");
  EXPECT_EQ(root.Location(), "t.yaml:1:1");
  const ConfigNode vehicle = root.Required("vehicle");
  EXPECT_EQ(vehicle.key_path(), "vehicle");
  EXPECT_EQ(vehicle.Keys(), (std::vector<std::string>{"mass_kg", "arm_m", "drag"}));
  EXPECT_TRUE(vehicle.Has("arm_m"));
  EXPECT_FALSE(vehicle.Has("rotors"));
  EXPECT_EQ(vehicle.Required("mass_kg").key_path(), "vehicle.mass_kg");
  EXPECT_EQ(vehicle.Required("mass_kg").Location(), "t.yaml:2:12");
  ASSERT_TRUE(vehicle.Optional("drag").has_value());
  EXPECT_TRUE(vehicle.Optional("drag")->IsNull());
  EXPECT_FALSE(vehicle.Optional("missing").has_value());
  EXPECT_TRUE(root.Required("name").IsScalar());
  EXPECT_NO_THROW(vehicle.RejectUnknownKeys());
}

TEST(ConfigNodeMap, MissingRequiredKeyAtTheMapsLocation) {
  const ConfigDocument doc = Load("# vehicle\nvehicle:\n  arm_m: 0.2\n");
  const ConfigError err = CatchConfigError([&] { doc.root().Required("vehicle").Required("mass_kg"); });
  EXPECT_STREQ(err.what(), "t.yaml:3:3: vehicle: missing required key 'mass_kg'");
  EXPECT_EQ(err.line(), 3);
  RG_EXPECT_THROW_WITH(doc.root().Required("sensors"), ConfigError,
                       "t.yaml:2:1: missing required key 'sensors'");
}

TEST(ConfigNodeMap, MapAccessOnANonMapIsATypeError) {
  const ConfigDocument doc = Load("a: 5\nb: [1, 2]\nc:\n");
  const ConfigNode root = doc.root();
  RG_EXPECT_THROW_WITH(root.Required("a").Required("x"), ConfigError,
                       "t.yaml:1:4: a: expected a map, got the scalar '5'");
  RG_EXPECT_THROW_WITH(root.Required("b").Has("x"), ConfigError,
                       "t.yaml:2:4: b: expected a map, got a sequence");
  RG_EXPECT_THROW_WITH(root.Required("c").Optional("x"), ConfigError,
                       "t.yaml:3:1: c: expected a map, got null");
  RG_EXPECT_THROW_WITH(root.Required("a").Keys(), ConfigError, "expected a map");
  RG_EXPECT_THROW_WITH(root.Required("a").RejectUnknownKeys(), ConfigError, "expected a map");
}

TEST(ConfigNodeMap, RejectUnknownKeysNamesTheTypoAndTheExpectedKeys) {
  const ConfigDocument doc = Load("mass_kg: 1\nmasss_kg: 2\n");
  const ConfigNode root = doc.root();
  root.Required("mass_kg");
  root.Optional("arm_length_m");
  EXPECT_FALSE(root.Has("drag"));
  const ConfigError err = CatchConfigError([&] { root.RejectUnknownKeys(); });
  EXPECT_STREQ(err.what(),
               "t.yaml:2:1: masss_kg: unknown key 'masss_kg'; expected one of: mass_kg, "
               "arm_length_m, drag");
  EXPECT_EQ(err.key_path(), "masss_kg");
}

TEST(ConfigNodeMap, RejectUnknownKeysNested) {
  const ConfigDocument doc = Load("sensors:\n  imu:\n    rate_hz: 200\n    noise: 1\n");
  const ConfigNode imu = doc.root().Required("sensors").Required("imu");
  imu.Required("rate_hz");
  RG_EXPECT_THROW_WITH(imu.RejectUnknownKeys(), ConfigError,
                       "t.yaml:4:5: sensors.imu.noise: unknown key 'noise'; expected one of: "
                       "rate_hz");
}

TEST(ConfigNodeMap, RejectUnknownKeysWhenNothingWasAsked) {
  const ConfigDocument doc = Load("a: 1\n");
  RG_EXPECT_THROW_WITH(doc.root().RejectUnknownKeys(), ConfigError,
                       "t.yaml:1:1: a: unknown key 'a'; no keys are expected here");
}

TEST(ConfigNodeMap, ViewsOfTheSameMapShareUsedKeys) {
  const ConfigDocument doc = Load("v:\n  a: 1\n  b: 2\n");
  doc.root().Required("v").Required("a");
  doc.root().Required("v").Has("b");
  EXPECT_NO_THROW(doc.root().Required("v").RejectUnknownKeys());
  const ConfigNode copy = doc.root();
  EXPECT_NO_THROW(copy.Optional("v"));
  EXPECT_NO_THROW(doc.root().RejectUnknownKeys());
}

// ---------------------------------------------------------------------------------------------
// Sequences

TEST(ConfigNodeSequence, SizeAndAt) {
  const ConfigDocument doc = Load("rotors:\n  - {thrust: 1}\n  - {thrust: 2}\n");
  const ConfigNode rotors = doc.root().Required("rotors");
  EXPECT_TRUE(rotors.IsSequence());
  ASSERT_EQ(rotors.size(), 2u);
  EXPECT_EQ(rotors.At(1).key_path(), "rotors.1");
  EXPECT_EQ(rotors.At(1).Required("thrust").key_path(), "rotors.1.thrust");
  EXPECT_DOUBLE_EQ(rotors.At(1).Required("thrust").AsDouble(), 2.0);
  EXPECT_EQ(rotors.At(1).Location(), "t.yaml:3:5");
  RG_EXPECT_THROW_WITH(rotors.At(2), ConfigError,
                       "t.yaml:2:3: rotors: index 2 is out of range; the sequence has 2 items");
  RG_EXPECT_THROW_WITH(doc.root().size(), ConfigError,
                       "t.yaml:1:1: expected a sequence, got a map");
}

// ---------------------------------------------------------------------------------------------
// Numbers

TEST(ConfigNodeNumber, AsDoubleAcceptsDecimalAndExponentForms) {
  const ConfigDocument doc = Load(
      "a: 1.5\nb: -2\nc: 1e3\nd: .5\ne: +1.5\nf: -0\ng: 2.\nh: 1.25E-2\ni: 1e-999\n"
      "j: 1.7976931348623157e308\n");
  const ConfigNode r = doc.root();
  EXPECT_DOUBLE_EQ(r.Required("a").AsDouble(), 1.5);
  EXPECT_DOUBLE_EQ(r.Required("b").AsDouble(), -2.0);
  EXPECT_DOUBLE_EQ(r.Required("c").AsDouble(), 1000.0);
  EXPECT_DOUBLE_EQ(r.Required("d").AsDouble(), 0.5);
  EXPECT_DOUBLE_EQ(r.Required("e").AsDouble(), 1.5);
  EXPECT_DOUBLE_EQ(r.Required("f").AsDouble(), 0.0);
  EXPECT_DOUBLE_EQ(r.Required("g").AsDouble(), 2.0);
  EXPECT_DOUBLE_EQ(r.Required("h").AsDouble(), 0.0125);
  EXPECT_DOUBLE_EQ(r.Required("i").AsDouble(), 0.0);  // underflow is finite: reads as zero
  EXPECT_DOUBLE_EQ(r.Required("j").AsDouble(), std::numeric_limits<double>::max());
}

TEST(ConfigNodeNumber, NonFiniteIsRejectedAsNotFinite) {
  for (const std::string text : {".nan", ".NaN", ".NAN", "nan", "NaN", ".inf", ".Inf", "-.inf",
                                 "+.inf", "inf", "-inf", "Infinity", "-.INF"}) {
    const ConfigDocument doc = Load("ok: 1\nx: " + text + "\n");
    const ConfigError err = CatchConfigError([&] { doc.root().Required("x").AsDouble(); });
    EXPECT_EQ(std::string(err.what()),
              "t.yaml:2:4: x: '" + text + "' is not finite; expected a finite number");
    EXPECT_EQ(err.line(), 2);
    EXPECT_EQ(err.key_path(), "x");
  }
}

TEST(ConfigNodeNumber, OverflowIsRejectedAsNotFinite) {
  for (const std::string text : {"1e999", "-1e999", "1.8e308", "123456789e305"}) {
    const ConfigDocument doc = Load("ok: 1\nx: " + text + "\n");
    RG_EXPECT_THROW_WITH(doc.root().Required("x").AsDouble(), ConfigError,
                         "t.yaml:2:4: x: '" + text + "' is not finite (it overflows a double)");
  }
}

TEST(ConfigNodeNumber, UnitStringsAndWordsAreNotNumbers) {
  for (const std::string text : {"1.5kg", "1.5 kg", "abc", "1_000", "0x10", "1e", "--1", "1.2.3",
                                 "e5", ".", "nan(1)", "1,5"}) {
    const ConfigDocument doc = Load("ok: 1\nmass_kg: " + text + "\n");
    RG_EXPECT_THROW_WITH(
        doc.root().Required("mass_kg").AsDouble(), ConfigError,
        "t.yaml:2:10: mass_kg: '" + text + "' is not a number; expected a finite number");
  }
}

TEST(ConfigNodeNumber, WrongTypesAreTypeErrors) {
  const ConfigDocument doc =
      Load("m:\n  a: 1\ns: [1, 2]\nq: \"1.5\"\nt: !!float 1.5\nn:\n\nz: 1\n");
  const ConfigNode r = doc.root();
  RG_EXPECT_THROW_WITH(r.Required("m").AsDouble(), ConfigError,
                       "t.yaml:2:3: m: expected a finite number, got a map");
  RG_EXPECT_THROW_WITH(r.Required("s").AsDouble(), ConfigError,
                       "t.yaml:3:4: s: expected a finite number, got a sequence");
  RG_EXPECT_THROW_WITH(r.Required("q").AsDouble(), ConfigError,
                       "t.yaml:4:4: q: expected a finite number, got the quoted string '1.5'");
  RG_EXPECT_THROW_WITH(r.Required("t").AsDouble(), ConfigError,
                       "t.yaml:5:4: t: expected a finite number, got the scalar '1.5' tagged "
                       "'!!float'");
  // An empty value is located at its key, not at the next token two lines below.
  RG_EXPECT_THROW_WITH(r.Required("n").AsDouble(), ConfigError,
                       "t.yaml:6:1: n: expected a finite number, got null (an empty value)");
}

TEST(ConfigNodeNumber, RangeChecks) {
  const ConfigDocument doc = Load("zero: 0\none: 1\nneg: -0.5\nbig: 2.5\n");
  const ConfigNode r = doc.root();
  EXPECT_DOUBLE_EQ(r.Required("zero").AsDoubleIn(0.0, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(r.Required("one").AsDoubleIn(0.0, 1.0), 1.0);
  RG_EXPECT_THROW_WITH(r.Required("big").AsDoubleIn(0.0, 1.0), ConfigError,
                       "t.yaml:4:6: big: '2.5' is out of range; expected a number in [0, 1]");
  RG_EXPECT_THROW_WITH(r.Required("neg").AsDoubleIn(0.0, 1.0), ConfigError,
                       "expected a number in [0, 1]");
  EXPECT_DOUBLE_EQ(r.Required("one").AsPositive(), 1.0);
  RG_EXPECT_THROW_WITH(r.Required("zero").AsPositive(), ConfigError,
                       "t.yaml:1:7: zero: '0' is out of range; expected a positive number (> 0)");
  EXPECT_DOUBLE_EQ(r.Required("zero").AsNonNegative(), 0.0);
  RG_EXPECT_THROW_WITH(r.Required("neg").AsNonNegative(), ConfigError,
                       "t.yaml:3:6: neg: '-0.5' is out of range; expected a non-negative number");
  // (0, hi]: the upper end belongs to it, zero does not.
  EXPECT_DOUBLE_EQ(r.Required("one").AsNumberIn({.max = 1.0, .positive = true}), 1.0);
  RG_EXPECT_THROW_WITH(r.Required("zero").AsNumberIn({.max = 1.0, .positive = true}), ConfigError,
                       "t.yaml:1:7: zero: '0' is out of range; expected a number in (0, 1]");
  RG_EXPECT_THROW_WITH(r.Required("big").AsNumberIn({.max = 2.0, .positive = true}), ConfigError,
                       "t.yaml:4:6: big: '2.5' is out of range; expected a number in (0, 2]");
  // An open upper end: [0, 1) takes zero and refuses one; (0, 1) refuses both.
  EXPECT_DOUBLE_EQ(r.Required("zero").AsNumberIn({.min = 0.0, .max = 1.0, .open_max = true}), 0.0);
  RG_EXPECT_THROW_WITH(r.Required("one").AsNumberIn({.min = 0.0, .max = 1.0, .open_max = true}), ConfigError,
                       "t.yaml:2:6: one: '1' is out of range; expected a number in [0, 1)");
  RG_EXPECT_THROW_WITH(r.Required("one").AsNumberIn({.max = 1.0, .positive = true, .open_max = true}), ConfigError,
                       "t.yaml:2:6: one: '1' is out of range; expected a number in (0, 1)");
  RG_EXPECT_THROW_WITH(r.Required("zero").AsNumberIn({.max = 1.0, .positive = true, .open_max = true}), ConfigError,
                       "expected a number in (0, 1)");
}

TEST(ConfigNodeNumber, RangeAccessorsStillRejectNonFinite) {
  const ConfigDocument doc = Load("x: .inf\n");
  RG_EXPECT_THROW_WITH(doc.root().Required("x").AsPositive(), ConfigError,
                       "t.yaml:1:4: x: '.inf' is not finite; expected a positive number");
  RG_EXPECT_THROW_WITH(doc.root().Required("x").AsDoubleIn(0, 1e308), ConfigError,
                       "is not finite");
  RG_EXPECT_THROW_WITH(doc.root().Required("x").AsNumberIn({.max = 1e308, .positive = true}), ConfigError,
                       "t.yaml:1:4: x: '.inf' is not finite; expected a number in (0, 1e+308]");
}

TEST(ConfigNodeNumber, AsInt) {
  const ConfigDocument doc = Load(
      "a: 42\nb: -7\nc: 0x1F\nd: +3\nmax: 9223372036854775807\nmin: -9223372036854775808\n"
      "f: 1.5\ng: abc\nh: 1e3\ni: 9223372036854775808\nj: .nan\n");
  const ConfigNode r = doc.root();
  EXPECT_EQ(r.Required("a").AsInt(), 42);
  EXPECT_EQ(r.Required("b").AsInt(), -7);
  EXPECT_EQ(r.Required("c").AsInt(), 31);
  EXPECT_EQ(r.Required("d").AsInt(), 3);
  EXPECT_EQ(r.Required("max").AsInt(), std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(r.Required("min").AsInt(), std::numeric_limits<std::int64_t>::min());
  RG_EXPECT_THROW_WITH(r.Required("f").AsInt(), ConfigError,
                       "t.yaml:7:4: f: '1.5' is not an integer; expected an integer");
  RG_EXPECT_THROW_WITH(r.Required("g").AsInt(), ConfigError,
                       "t.yaml:8:4: g: 'abc' is not an integer");
  RG_EXPECT_THROW_WITH(r.Required("h").AsInt(), ConfigError,
                       "t.yaml:9:4: h: '1e3' is not an integer");
  RG_EXPECT_THROW_WITH(r.Required("i").AsInt(), ConfigError,
                       "t.yaml:10:4: i: '9223372036854775808' does not fit a 64-bit integer");
  RG_EXPECT_THROW_WITH(r.Required("j").AsInt(), ConfigError, "'.nan' is not an integer");
  EXPECT_EQ(r.Required("a").AsIntIn(1, 42), 42);
  RG_EXPECT_THROW_WITH(r.Required("b").AsIntIn(0, 10), ConfigError,
                       "t.yaml:2:4: b: '-7' is out of range; expected an integer in [0, 10]");
}

TEST(ConfigNodeNumber, AsUint64) {
  const ConfigDocument doc = Load(
      "a: 18446744073709551615\nb: 0xFFFFFFFFFFFFFFFF\nc: 0\nd: -1\ne: 18446744073709551616\n"
      "f: 12.0\n");
  const ConfigNode r = doc.root();
  EXPECT_EQ(r.Required("a").AsUint64(), std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(r.Required("b").AsUint64(), std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(r.Required("c").AsUint64(), 0u);
  RG_EXPECT_THROW_WITH(r.Required("d").AsUint64(), ConfigError,
                       "t.yaml:4:4: d: '-1' is negative; expected a non-negative integer");
  RG_EXPECT_THROW_WITH(r.Required("e").AsUint64(), ConfigError,
                       "t.yaml:5:4: e: '18446744073709551616' is out of range");
  RG_EXPECT_THROW_WITH(r.Required("f").AsUint64(), ConfigError,
                       "t.yaml:6:4: f: '12.0' is not an integer");
}

// ---------------------------------------------------------------------------------------------
// Other scalars

TEST(ConfigNodeScalar, AsBoolTrueFalseOnly) {
  const ConfigDocument doc =
      Load("a: true\nb: false\nc: True\nd: FALSE\ne: yes\nf: on\ng: 1\nh: \"true\"\n");
  const ConfigNode r = doc.root();
  EXPECT_TRUE(r.Required("a").AsBool());
  EXPECT_FALSE(r.Required("b").AsBool());
  EXPECT_TRUE(r.Required("c").AsBool());
  EXPECT_FALSE(r.Required("d").AsBool());
  RG_EXPECT_THROW_WITH(r.Required("e").AsBool(), ConfigError,
                       "t.yaml:5:4: e: 'yes' is not a boolean; expected true or false");
  RG_EXPECT_THROW_WITH(r.Required("f").AsBool(), ConfigError, "t.yaml:6:4: f: 'on' is not");
  RG_EXPECT_THROW_WITH(r.Required("g").AsBool(), ConfigError, "t.yaml:7:4: g: '1' is not");
  RG_EXPECT_THROW_WITH(r.Required("h").AsBool(), ConfigError,
                       "t.yaml:8:4: h: expected true or false, got the quoted string 'true'");
}

TEST(ConfigNodeScalar, AsStringAnyScalar) {
  const ConfigDocument doc = Load("a: hello world\nb: 1.5\nc: 'quoted: yes'\nd: [1]\ne:\n");
  const ConfigNode r = doc.root();
  EXPECT_EQ(r.Required("a").AsString(), "hello world");
  EXPECT_EQ(r.Required("b").AsString(), "1.5");
  EXPECT_EQ(r.Required("c").AsString(), "quoted: yes");
  RG_EXPECT_THROW_WITH(r.Required("d").AsString(), ConfigError,
                       "t.yaml:4:4: d: expected a string, got a sequence");
  RG_EXPECT_THROW_WITH(r.Required("e").AsString(), ConfigError,
                       "t.yaml:5:1: e: expected a string, got null");
}

TEST(ConfigNodeScalar, AsEnum) {
  const ConfigDocument doc = Load("frame: quad\nother: hexa\nm: {}\n");
  const ConfigNode r = doc.root();
  EXPECT_EQ(r.Required("frame").AsEnum({"quad", "hex"}), "quad");
  RG_EXPECT_THROW_WITH(r.Required("other").AsEnum({"quad", "hex"}), ConfigError,
                       "t.yaml:2:8: other: 'hexa' is not allowed; expected one of: quad, hex");
  RG_EXPECT_THROW_WITH(r.Required("m").AsEnum({"quad", "hex"}), ConfigError,
                       "t.yaml:3:4: m: expected one of: quad, hex, got a map");
}

TEST(ConfigNodeScalar, LongAndMultilineValuesAreShortenedInMessages) {
  const ConfigDocument doc = Load("x: |\n  line one\n  line two\n");
  RG_EXPECT_THROW_WITH(doc.root().Required("x").AsBool(), ConfigError,
                       "got the quoted string 'line one\\nline two\\n'");
  const ConfigDocument long_doc = Load("x: " + std::string(200, 'a') + "\n");
  RG_EXPECT_THROW_WITH(long_doc.root().Required("x").AsDouble(), ConfigError,
                       "'" + std::string(60, 'a') + "...' is not a number");
}

// ---------------------------------------------------------------------------------------------
// Lists and vectors

TEST(ConfigNodeList, AsVector3) {
  const ConfigDocument doc =
      Load("p: [1, -2.5, 3e1]\nshort: [1, 2]\nbad: [1, .nan, 3]\ns: 5\nblock:\n  - 1\n  - 2\n"
           "  - x\n");
  const ConfigNode r = doc.root();
  EXPECT_TRUE(MatricesNear(r.Required("p").AsVector3(), Eigen::Vector3d(1, -2.5, 30), 0.0));
  RG_EXPECT_THROW_WITH(r.Required("short").AsVector3(), ConfigError,
                       "t.yaml:2:8: short: expected a list of 3 numbers, got 2 items");
  RG_EXPECT_THROW_WITH(r.Required("bad").AsVector3(), ConfigError,
                       "t.yaml:3:10: bad.1: '.nan' is not finite; expected a finite number");
  RG_EXPECT_THROW_WITH(r.Required("s").AsVector3(), ConfigError,
                       "t.yaml:4:4: s: expected a list of 3 numbers, got the scalar '5'");
  RG_EXPECT_THROW_WITH(r.Required("block").AsVector3(), ConfigError,
                       "t.yaml:8:5: block.2: 'x' is not a number");
}

TEST(ConfigNodeList, AsDoubleList) {
  const ConfigDocument doc = Load("a: [1, 2, 3, 4]\nb: []\nc: [1]\n");
  const ConfigNode r = doc.root();
  EXPECT_EQ(r.Required("a").AsDoubleList(), (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(r.Required("a").AsDoubleList(4), (std::vector<double>{1, 2, 3, 4}));
  EXPECT_TRUE(r.Required("b").AsDoubleList().empty());
  RG_EXPECT_THROW_WITH(r.Required("c").AsDoubleList(2), ConfigError,
                       "t.yaml:3:4: c: expected a list of 2 numbers, got 1 item");
  RG_EXPECT_THROW_WITH(r.Required("b").AsDoubleList(1), ConfigError, "got 0 items");
}

// ---------------------------------------------------------------------------------------------
// Fail / FailAt

TEST(ConfigNodeFail, FailIsAtTheNode) {
  const ConfigDocument doc = Load("v:\n  mass_kg: 3\n");
  RG_EXPECT_THROW_WITH(doc.root().Required("v").Required("mass_kg").Fail("too heavy"),
                       ConfigError, "t.yaml:2:12: v.mass_kg: too heavy");
}

TEST(ConfigNodeFail, FailAtLocatesTheDescendantWhenPresent) {
  const ConfigDocument doc =
      Load("vehicle:\n  rotors:\n    - {max_thrust_n: 5}\n    - {max_thrust_n: 6}\n"
           "    - {max_thrust_n: 7}\n");
  const ConfigNode vehicle = doc.root().Required("vehicle");
  const ConfigError err =
      CatchConfigError([&] { vehicle.FailAt("rotors.2.max_thrust_n", "exceeds the motor"); });
  EXPECT_STREQ(err.what(), "t.yaml:5:22: vehicle.rotors.2.max_thrust_n: exceeds the motor");
  // Absent descendant: located at the deepest existing ancestor, key path still the field.
  RG_EXPECT_THROW_WITH(vehicle.FailAt("rotors.7.max_thrust_n", "bad"), ConfigError,
                       "t.yaml:3:5: vehicle.rotors.7.max_thrust_n: bad");
  RG_EXPECT_THROW_WITH(vehicle.FailAt("inertia", "bad"), ConfigError,
                       "t.yaml:2:3: vehicle.inertia: bad");
  RG_EXPECT_THROW_WITH(doc.root().FailAt("", "bad"), ConfigError, "t.yaml:1:1: bad");
}

// ---------------------------------------------------------------------------------------------
// Overrides

constexpr const char* kScenario =
    "vehicle:\n"
    "  mass_kg: 1.5\n"
    "  arm_m: 0.2\n"
    "faults:\n"
    "  - kind: motor\n"
    "    onset:\n"
    "      at_time_s: 1.0\n"
    "  - kind: imu\n"
    "    onset:\n"
    "      at_time_s: 2.0\n";

TEST(ConfigOverride, ReplacesAnExistingScalar) {
  ConfigDocument doc = Load(kScenario);
  doc.ApplyOverride("vehicle.mass_kg", "2.25");
  const ConfigNode mass = doc.root().Required("vehicle").Required("mass_kg");
  EXPECT_DOUBLE_EQ(mass.AsDouble(), 2.25);
  EXPECT_EQ(mass.Location(), "--set");
  EXPECT_EQ(mass.key_path(), "vehicle.mass_kg");
  // Untouched siblings keep their file location.
  EXPECT_EQ(doc.root().Required("vehicle").Required("arm_m").Location(), "t.yaml:3:10");
}

TEST(ConfigOverride, IndexesSequences) {
  ConfigDocument doc = Load(kScenario);
  doc.ApplyOverride("faults.1.onset.at_time_s", "7.5");
  doc.ApplyOverride("faults.0.kind", "rotor");
  const ConfigNode faults = doc.root().Required("faults");
  EXPECT_DOUBLE_EQ(faults.At(1).Required("onset").Required("at_time_s").AsDouble(), 7.5);
  EXPECT_DOUBLE_EQ(faults.At(0).Required("onset").Required("at_time_s").AsDouble(), 1.0);
  EXPECT_EQ(faults.At(0).Required("kind").AsString(), "rotor");
}

TEST(ConfigOverride, ReplacesASubtreeWithParsedYaml) {
  ConfigDocument doc = Load(kScenario);
  doc.ApplyOverride("faults.0.onset", "{at_time_s: 3, extra: 1}");
  const ConfigNode onset = doc.root().Required("faults").At(0).Required("onset");
  EXPECT_DOUBLE_EQ(onset.Required("at_time_s").AsDouble(), 3.0);
  RG_EXPECT_THROW_WITH(onset.RejectUnknownKeys(), ConfigError,
                       "--set: faults.0.onset.extra: unknown key 'extra'; expected one of: "
                       "at_time_s");
  doc.ApplyOverrideAssignment("vehicle=[1, 2]");
  EXPECT_TRUE(doc.root().Required("vehicle").IsSequence());
}

TEST(ConfigOverride, LaterTypeErrorSaysSet) {
  ConfigDocument doc = Load(kScenario);
  doc.ApplyOverride("vehicle.mass_kg", "heavy");
  const ConfigError err =
      CatchConfigError([&] { doc.root().Required("vehicle").Required("mass_kg").AsDouble(); });
  EXPECT_STREQ(err.what(),
               "--set: vehicle.mass_kg: 'heavy' is not a number; expected a finite number");
  EXPECT_EQ(err.file(), "--set");
  EXPECT_EQ(err.line(), 0);
  doc.ApplyOverride("vehicle.arm_m", ".nan");
  RG_EXPECT_THROW_WITH(doc.root().Required("vehicle").Required("arm_m").AsPositive(), ConfigError,
                       "--set: vehicle.arm_m: '.nan' is not finite");
  doc.ApplyOverride("vehicle.arm_m", "");
  RG_EXPECT_THROW_WITH(doc.root().Required("vehicle").Required("arm_m").AsDouble(), ConfigError,
                       "--set: vehicle.arm_m: expected a finite number, got null");
}

// A key the file does not write is added, with the rest of its path (any declared key can be set
// from the command line); the schema then refuses one it does not declare, naming --set and the
// keys it expects. A path through a scalar or past a sequence's end stays an error that changes
// nothing.
TEST(ConfigOverride, AMissingKeyIsAddedAndAnUndeclaredOneIsRefusedByTheSchema) {
  ConfigDocument doc = Load(kScenario);
  doc.ApplyOverride("sensors.imu.rate_hz", "250");
  EXPECT_DOUBLE_EQ(doc.root().Required("sensors").Required("imu").Required("rate_hz").AsDouble(), 250.0);
  doc.ApplyOverride("vehicle.masss_kg", "2");
  const ConfigNode vehicle = doc.root().Required("vehicle");
  vehicle.Required("mass_kg");
  vehicle.Required("arm_m");
  const ConfigError err = CatchConfigError([&] { vehicle.RejectUnknownKeys(); });
  EXPECT_STREQ(err.what(), "--set: vehicle.masss_kg: unknown key 'masss_kg'; expected one of: mass_kg, arm_m");
  EXPECT_EQ(err.file(), "--set");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("faults.2.kind", "imu"), ConfigError,
                       "--set: faults.2.kind: no item '2' in the sequence under 'faults'; "
                       "existing indices: 0 to 1");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("faults.first.kind", "imu"), ConfigError,
                       "no item 'first' in the sequence under 'faults'");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("vehicle.mass_kg.value", "1"), ConfigError,
                       "--set: vehicle.mass_kg.value: no key 'value' under 'vehicle.mass_kg': "
                       "that is the scalar '1.5', not a map or sequence");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("", "1"), ConfigError, "--set: empty key path");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("vehicle..mass_kg", "1"), ConfigError,
                       "--set: vehicle..mass_kg: malformed key path");
  // Nothing was changed by the failed overrides.
  EXPECT_DOUBLE_EQ(doc.root().Required("vehicle").Required("mass_kg").AsDouble(), 1.5);
}

TEST(ConfigOverride, MalformedValueIsAnErrorAndChangesNothing) {
  ConfigDocument doc = Load(kScenario);
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("vehicle.mass_kg", "[1, 2"), ConfigError,
                       "--set: vehicle.mass_kg: malformed YAML: end of sequence flow not found");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("vehicle", "{a: 1, a: 2}"), ConfigError,
                       "--set: vehicle.a: duplicate key 'a'");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("vehicle.mass_kg", ","), ConfigError,
                       "--set: vehicle.mass_kg: malformed YAML: unexpected ','");
  RG_EXPECT_THROW_WITH(doc.ApplyOverride("vehicle.mass_kg", "1\n---\n2"), ConfigError,
                       "--set: vehicle.mass_kg: a second YAML document starts here");
  EXPECT_DOUBLE_EQ(doc.root().Required("vehicle").Required("mass_kg").AsDouble(), 1.5);
}

TEST(ConfigOverride, AssignmentSyntax) {
  ConfigDocument doc = Load(kScenario);
  doc.ApplyOverrideAssignment("vehicle.mass_kg=3=4");
  EXPECT_EQ(doc.root().Required("vehicle").Required("mass_kg").AsString(), "3=4");
  RG_EXPECT_THROW_WITH(doc.ApplyOverrideAssignment("vehicle.mass_kg"), ConfigError,
                       "--set: 'vehicle.mass_kg' is not an override; expected KEY.PATH=VALUE");
  RG_EXPECT_THROW_WITH(doc.ApplyOverrideAssignment("=3"), ConfigError, "is not an override");
}

TEST(ConfigOverride, ViewsTakenBeforeAnOverrideSeeTheNewValueThroughTheirParent) {
  ConfigDocument doc = Load(kScenario);
  const ConfigNode vehicle = doc.root().Required("vehicle");
  doc.ApplyOverride("vehicle.mass_kg", "9");
  EXPECT_DOUBLE_EQ(vehicle.Required("mass_kg").AsDouble(), 9.0);
}

// ---------------------------------------------------------------------------------------------
// Robustness: mutated documents load or fail with ConfigError, and reading whatever loaded fails
// only with ConfigError. Nothing else escapes, nothing crashes.

void ReadEverything(const ConfigNode& node, int depth) {
  if (depth > 50) return;
  const auto swallow = [](const auto& fn) {
    try {
      fn();
    } catch (const ConfigError&) {
    }
  };
  swallow([&] { node.AsDouble(); });
  swallow([&] { node.AsInt(); });
  swallow([&] { node.AsUint64(); });
  swallow([&] { node.AsBool(); });
  swallow([&] { node.AsString(); });
  swallow([&] { node.AsVector3(); });
  swallow([&] { node.AsDoubleList(); });
  swallow([&] { node.AsEnum({"a", "b"}); });
  swallow([&] { node.FailAt("x.0.y", "m"); });
  if (node.IsMap()) {
    for (const std::string& key : node.Keys()) ReadEverything(node.Required(key), depth + 1);
    swallow([&] { node.RejectUnknownKeys(); });
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) ReadEverything(node.At(i), depth + 1);
  }
}

TEST(ConfigRobustness, MutatedInputsOnlyEverThrowConfigError) {
  const std::string base = std::string(kScenario) +
                           "anchors: &a {x: [1, 2, {y: \"q\"}]}\n"
                           "again: *a\n"
                           "text: |\n  multi\n  line\n"
                           "flow: {a: [1, .inf], b: 'it''s'}\n";
  const std::string alphabet = ":-[]{},&*!|>'\"#%@`?~.\n\t 0a\x01\xff";
  std::mt19937 rng(12345);
  int loaded = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    std::string text = base;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int k = 0; k < edits; ++k) {
      const std::size_t pos = rng() % (text.size() + 1);
      const char c = alphabet[rng() % alphabet.size()];
      switch (rng() % 3) {
        case 0:
          text.insert(text.begin() + static_cast<std::ptrdiff_t>(pos), c);
          break;
        case 1:
          if (pos < text.size()) text[pos] = c;
          break;
        default:
          if (pos < text.size()) text.erase(pos, 1 + rng() % 8);
          break;
      }
    }
    try {
      ConfigDocument doc = Load(text);
      ++loaded;
      ReadEverything(doc.root(), 0);
      try {
        doc.ApplyOverride("faults.1.onset.at_time_s", text.substr(0, rng() % 40));
      } catch (const ConfigError&) {
      }
    } catch (const ConfigError& err) {
      EXPECT_EQ(err.file(), "t.yaml");
    }
  }
  EXPECT_GT(loaded, 0);
}

}  // namespace
}  // namespace rotorguard::io

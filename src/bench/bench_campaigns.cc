#include "rotorguard/bench/bench_campaigns.h"

#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "rotorguard/bench/ftc_bench.h"
#include "rotorguard/bench/mars_bench.h"
#include "rotorguard/bench/nav_bench.h"
#include "rotorguard/bench/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"

namespace rotorguard::bench {

namespace fs = std::filesystem;

BenchReport BenchResult(const nlohmann::json& bench, const std::vector<nlohmann::json>& records) {
  const std::string name = bench.value("name", "");
  const nlohmann::json& options = bench.at("options");
  BenchReport r;
  if (name == "ftc") {
    r.result = FtcResult(options, records);
    r.markdown = FtcMarkdown(r.result);
  } else if (name == "nav") {
    r.result = NavResult(options, records);
    r.markdown = NavMarkdown(r.result);
  } else if (name == "mars") {
    r.result = MarsResult(options, records);
    r.markdown = MarsMarkdown(r.result);
  } else {
    throw std::invalid_argument(fmt::format("benchmark '{}' is unknown; expected ftc, nav or mars", name));
  }
  return r;
}

void WriteBenchFiles(const BenchReport& report, const std::string& dir) {
  io::WriteFileAtomically((fs::path(dir) / "bench.json").string(), report.result.dump(2) + "\n");
  io::WriteFileAtomically((fs::path(dir) / "bench.md").string(), report.markdown);
}

namespace {

/// The words of a list key, each one of `allowed`.
std::vector<std::string> WordList(const io::ConfigNode& node, const std::vector<std::string>& allowed) {
  if (!node.IsSequence() || node.size() == 0) node.Fail("expected a non-empty list");
  std::vector<std::string> words;
  for (std::size_t i = 0; i < node.size(); ++i) words.push_back(node.At(i).AsEnum(allowed));
  return words;
}

/// Options' ranges are checked by the benchmark (std::invalid_argument naming the field); here the
/// failure is moved to the spec's key, with its file and line.
template <typename Make>
Campaign Checked(const io::ConfigNode& root, Make make) {
  try {
    return make();
  } catch (const std::invalid_argument& e) {
    root.Fail(e.what());
  }
}

}  // namespace

Campaign LoadCampaign(const std::string& path) {
  const io::ConfigDocument doc = io::ConfigDocument::LoadFile(path);
  const io::ConfigNode root = doc.root();
  if (!root.Has("bench")) return ScenarioCampaign(LoadCampaignSpec(path));
  const std::string name = root.Required("name").AsString();
  if (!IsValidCampaignName(name)) {
    root.FailAt("name", fmt::format("'{}' is invalid; expected letters, digits, '_', '.' or '-' (it names files and "
                                    "Slurm jobs)", name));
  }
  const std::string bench = root.Required("bench").AsEnum({"ftc", "nav", "mars"});
  const auto file = [&](const char* key) {  // a path relative to the spec's folder
    return (fs::path(path).parent_path() / root.Required(key).AsString()).lexically_normal().string();
  };
  // A file that cannot be read is reported at the key that names it.
  const auto load = [&](const char* key, auto loader) {
    try {
      return loader(file(key));
    } catch (const io::InputFileError& e) {
      root.FailAt(key, e.what());
    }
  };
  const auto scenario = [&](const char* key) { return load(key, [](const std::string& p) { return LoadScenario(p); }); };
  const std::uint64_t seed = root.Has("seed") ? root.Required("seed").AsUint64() : 1;
  Campaign c;
  if (bench == "ftc") {
    FtcBenchOptions o;
    o.trials = static_cast<int>(root.Required("trials").AsIntIn(1, 1'000'000));
    o.seed = seed;
    if (root.Has("methods")) o.methods = WordList(root.Required("methods"), FtcMethods());
    o.vehicle = load("vehicle", [](const std::string& p) { return LoadVehicle(p); });
    c = Checked(root, [&] { return FtcCampaign(o); });
  } else if (bench == "nav") {
    NavBenchOptions o;
    o.trials = static_cast<int>(root.Required("trials").AsIntIn(1, 100'000));
    o.seed = seed;
    if (root.Has("kinds")) o.kinds = WordList(root.Required("kinds"), {"forest", "room"});
    o.base = scenario("base");
    c = Checked(root, [&] { return NavCampaign(o); });
  } else {
    MarsBenchOptions o;
    o.trials = static_cast<int>(root.Required("trials").AsIntIn(1, 10'000));
    o.seed = seed;
    if (root.Has("alloc_samples")) o.alloc_samples = static_cast<int>(root.Required("alloc_samples").AsIntIn(100, 10'000'000));
    o.spiral = scenario("spiral");
    o.nine_units = load("nine_units", [](const std::string& p) { return LoadAssembly(p); });
    if (root.Has("reconfigure")) o.reconfigure = scenario("reconfigure");
    if (root.Has("plan_4x1") != root.Has("plan_3x2")) {
      root.Fail("expected both plan_4x1 and plan_3x2 (Table II's two scenes) or neither");
    }
    if (root.Has("plan_4x1")) {
      o.plan_4x1 = scenario("plan_4x1");
      o.plan_3x2 = scenario("plan_3x2");
    }
    c = Checked(root, [&] { return MarsCampaign(o); });
  }
  root.RejectUnknownKeys();
  c.name = name;
  c.file = path;
  return c;
}

}  // namespace rotorguard::bench

#include "rotorguard/campaign_kinds/registry.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "rotorguard/campaign_kinds/flatness_bench.h"
#include "rotorguard/campaign_kinds/ftc_bench.h"
#include "rotorguard/campaign_kinds/mars_bench.h"
#include "rotorguard/campaign_kinds/nav_bench.h"
#include "rotorguard/campaign_kinds/scenario_sweep.h"
#include "rotorguard/campaign/campaign.h"
#include "rotorguard/campaign/registry.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::benchmarks {

namespace fs = std::filesystem;
using campaign::Campaign;

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
campaign::Campaign Checked(const io::ConfigNode& root, Make make) {
  try {
    return make();
  } catch (const std::invalid_argument& e) {
    root.Fail(e.what());
  }
}

/// A spec's helpers: paths relative to its folder, a file that cannot be read reported at the key
/// that names it.
class SpecFiles {
 public:
  SpecFiles(const io::ConfigNode& root, const std::string& path) : root_(root), path_(path) {}

  template <typename Loader>
  auto Load(const char* key, Loader loader) const {
    try {
      return loader((fs::path(path_).parent_path() / root_.Required(key).AsString()).lexically_normal().string());
    } catch (const io::InputFileError& e) {
      root_.FailAt(key, e.what());
    }
  }
  harness::Scenario ScenarioAt(const char* key) const {
    return Load(key, [](const std::string& p) { return harness::LoadScenario(p); });
  }

 private:
  io::ConfigNode root_;
  std::string path_;
};

/// The keys every benchmark's spec has, read before its own (unknown-key messages list the keys in
/// the order they were read): seed, trials and the world they fly (`truth`, as --truth).
template <typename Options>
Options SeedAndTrials(const io::ConfigNode& root, int max_trials) {
  Options o;
  o.seed = root.Has("seed") ? root.Required("seed").AsUint64() : 1;
  o.trials = static_cast<int>(root.Required("trials").AsIntIn(1, max_trials));
  if (root.Has("truth")) {
    o.truth = *FromName<sim::TruthPreset>(root.Required("truth").AsEnum(NameList<sim::TruthPreset>()));
  }
  return o;
}

/// The spec's `estimator` (odometry or lio) into `estimator`, when given.
void EstimatorKey(const io::ConfigNode& root, stack::EstimatorKind* estimator) {
  if (root.Has("estimator")) {
    *estimator = *FromName<stack::EstimatorKind>(root.Required("estimator").AsEnum(NameList<stack::EstimatorKind>()));
  }
}

campaign::Campaign LoadFtc(const io::ConfigNode& root, const std::string& path) {
  const SpecFiles files(root, path);
  FtcBenchOptions o = SeedAndTrials<FtcBenchOptions>(root, 1'000'000);
  if (root.Has("methods")) o.methods = WordList(root.Required("methods"), FtcMethods());
  if (root.Has("cells")) o.cells = WordList(root.Required("cells"), FtcCells());
  EstimatorKey(root, &o.estimator);
  o.vehicle = files.Load("vehicle", [](const std::string& p) { return harness::LoadVehicle(p); });
  if (auto fdd = files.Load("vehicle", [](const std::string& p) { return harness::LoadVehicleFdd(p); })) {
    o.fdd = fdd->first;
  }
  return Checked(root, [&] { return FtcCampaign(o); });
}

campaign::Campaign LoadNav(const io::ConfigNode& root, const std::string& path) {
  const SpecFiles files(root, path);
  NavBenchOptions o = SeedAndTrials<NavBenchOptions>(root, 100'000);
  if (root.Has("kinds")) o.kinds = WordList(root.Required("kinds"), {"forest", "room"});
  EstimatorKey(root, &o.estimator);
  o.base = files.ScenarioAt("base");
  return Checked(root, [&] { return NavCampaign(o); });
}

campaign::Campaign LoadMars(const io::ConfigNode& root, const std::string& path) {
  const SpecFiles files(root, path);
  MarsBenchOptions o = SeedAndTrials<MarsBenchOptions>(root, 10'000);
  if (root.Has("alloc_samples"))
    o.alloc_samples = static_cast<int>(root.Required("alloc_samples").AsIntIn(100, 10'000'000));
  o.spiral = files.ScenarioAt("spiral");
  o.nine_units = files.Load("nine_units", [](const std::string& p) { return harness::LoadAssembly(p); });
  if (root.Has("reconfigure")) o.reconfigure = files.ScenarioAt("reconfigure");
  if (root.Has("plan_4x1") != root.Has("plan_3x2")) {
    root.Fail("expected both plan_4x1 and plan_3x2 (Table II's two scenes) or neither");
  }
  if (root.Has("plan_4x1")) {
    o.plan_4x1 = files.ScenarioAt("plan_4x1");
    o.plan_3x2 = files.ScenarioAt("plan_3x2");
  }
  return Checked(root, [&] { return MarsCampaign(o); });
}

campaign::Campaign LoadFlatness(const io::ConfigNode& root, const std::string& path) {
  const SpecFiles files(root, path);
  FlatnessBenchOptions o = SeedAndTrials<FlatnessBenchOptions>(root, 10'000);
  o.fig2 = files.ScenarioAt("fig2");
  return Checked(root, [&] { return FlatnessCampaign(o); });
}

campaign::CampaignRegistry MakeKinds() {
  campaign::CampaignRegistry kinds;
  kinds.Add({"",
             [](const io::ConfigNode& root, const std::string& path) {
               return ScenarioCampaign(LoadCampaignSpec(root, path));
             },
             {}});
  kinds.Add({"ftc", LoadFtc, [](const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
               const nlohmann::json r = FtcResult(options, records);
               return campaign::BenchReport{r, FtcMarkdown(r)};
             }});
  kinds.Add({"nav", LoadNav, [](const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
               const nlohmann::json r = NavResult(options, records);
               return campaign::BenchReport{r, NavMarkdown(r)};
             }});
  kinds.Add({"mars", LoadMars, [](const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
               const nlohmann::json r = MarsResult(options, records);
               return campaign::BenchReport{r, MarsMarkdown(r)};
             }});
  kinds.Add({"flatness", LoadFlatness, [](const nlohmann::json& options, const std::vector<nlohmann::json>& records) {
               const nlohmann::json r = FlatnessResult(options, records);
               return campaign::BenchReport{r, FlatnessMarkdown(r)};
             }});
  return kinds;
}

}  // namespace

const campaign::CampaignRegistry& CampaignKinds() {
  static const campaign::CampaignRegistry kinds = MakeKinds();
  return kinds;
}

}  // namespace rotorguard::benchmarks

// rotorguard fdd-calibrate RUNS...: sweep the composite FDD's thresholds over saved runs.
#include <fmt/format.h>

#include <filesystem>

#include "cli.h"
#include "rotorguard/benchmarks/fdd_calibration.h"
#include "rotorguard/io/files.h"

namespace rotorguard::cli {

namespace fs = std::filesystem;

namespace {

class FddCalibrateCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* calibrate = app->add_subcommand(
        "fdd-calibrate",
        "Replay saved runs (folders written by 'rotorguard run --out DIR', fault-free and faulty) through the\n"
        "composite FDD offline while each threshold sweeps (gamma_M, gamma_P, take-off): detection latency,\n"
        "misses and false alarms per value, the margin to the fault-free extremes (of the runs and of the\n"
        "flights of --healthy campaigns), and a suggested value with the latency its margin costs.");
    calibrate->add_option("runs", dirs_, "Run folders (each with sensors.csv, vehicle.yaml, summary.json)");
    calibrate->add_option("--healthy", campaigns_,
                          "Campaign folders ('rotorguard campaign run --out DIR') whose flights' recorded\n"
                          "fdd.healthy_extremes and fdd.false_alarm join the fault-free extremes. Repeatable");
    calibrate->add_option("--margin", margin_text_,
                          "Required margin to the fault-free extreme of each index (default 1.5, > 1)");
    calibrate->add_option("--out", out_, "Folder for calibration.json and calibration.md");
    calibrate->add_flag("--json", json_, "Print JSON instead of Markdown");
    calibrate->add_option("--write", write_,
                          "Write the thresholds, with the suggested values, to this YAML file; a vehicle file\n"
                          "names it with its key `fdd: FILE`");
    return calibrate;
  }

  int Execute() override {
    benchmarks::FddCalibrationOptions o;
    o.margin = ParseFinite("--margin", margin_text_, 1.0 + 1e-9, 1e6);
    if (dirs_.empty() && campaigns_.empty()) throw UsageError("give run folders, --healthy campaign folders, or both");
    std::vector<benchmarks::CalibrationLog> logs;
    for (const std::string& d : dirs_) logs.push_back(benchmarks::LoadCalibrationLog(d));
    std::vector<benchmarks::CampaignFlights> campaigns;
    for (const std::string& d : campaigns_) campaigns.push_back(benchmarks::LoadCampaignFlights(d));
    std::string note;
    o.fdd = benchmarks::RecordedFddOptions(logs, &note);
    if (!note.empty()) fmt::print(stderr, "note: {}\n", note);
    const nlohmann::json r = benchmarks::CalibrateCompositeFdd(logs, campaigns, o);
    const std::string md = benchmarks::CalibrationMarkdown(r);
    if (!out_.empty()) {
      CreateOutputFolder(out_);
      io::WriteFileAtomically((fs::path(out_) / "calibration.json").string(), r.dump(2) + "\n");
      io::WriteFileAtomically((fs::path(out_) / "calibration.md").string(), md);
    }
    if (!write_.empty()) io::WriteFileAtomically(write_, benchmarks::CalibratedFddYaml(r, o.fdd));
    fmt::print("{}", json_ ? r.dump(2) + "\n" : md);
    if (!write_.empty()) fmt::print(stderr, "thresholds written to {}\n", write_);
    return kOk;
  }

 private:
  std::vector<std::string> dirs_, campaigns_;
  std::string margin_text_ = "1.5", out_, write_;
  bool json_ = false;
};

}  // namespace

std::unique_ptr<Command> MakeFddCalibrateCommand() { return std::make_unique<FddCalibrateCommand>(); }

}  // namespace rotorguard::cli

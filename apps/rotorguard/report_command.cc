// rotorguard report DIR: rebuild a saved run's report.html.
#include <fmt/format.h>

#include <filesystem>

#include "cli.h"
#include "rotorguard/record/flight_log.h"
#include "rotorguard/record/report.h"

namespace rotorguard::cli {

namespace {

class ReportCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* report = app->add_subcommand("report",
                                           "Rebuild DIR/report.html from a saved run (summary.json with log.csv and\n"
                                           "scene.json, or flight.mcap). Exit 3 when a file is missing or damaged.");
    report->add_option("dir", dir_, "Run folder written by 'rotorguard run --out DIR'")->required();
    report->add_option("--out", out_, "Report file (default DIR/report.html)");
    return report;
  }

  int Execute() override {
    const record::FlightLog log = record::ReadFlightLog(dir_);
    const std::string path = out_.empty() ? (std::filesystem::path(dir_) / "report.html").string() : out_;
    record::WriteFlightReport(log, path);
    fmt::print("{}\n", path);
    return kOk;
  }

 private:
  std::string dir_, out_;
};

}  // namespace

std::unique_ptr<Command> MakeReportCommand() { return std::make_unique<ReportCommand>(); }

}  // namespace rotorguard::cli

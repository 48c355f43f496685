// rotorguard validate FILE: check a config file without using it.
#include <fmt/format.h>

#include "cli.h"
#include "rotorguard/benchmarks/config_files.h"

namespace rotorguard::cli {

namespace {

class ValidateCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* validate = app->add_subcommand("validate",
                                             "Check a scenario, vehicle, assembly, campaign or FDD-threshold file without flying it.\n"
                                             "Exit 0 when valid, 2 when invalid, 3 when unreadable.");
    validate->add_option("file", path_, "Scenario, vehicle, assembly, campaign or FDD-threshold file (YAML)")->required();
    return validate;
  }

  int Execute() override {
    const benchmarks::ValidationReport r = benchmarks::ValidateConfigFile(path_);
    fmt::print("{}: valid {} ({})\n", path_, r.kind, r.summary);
    return kOk;
  }

 private:
  std::string path_;
};

}  // namespace

std::unique_ptr<Command> MakeValidateCommand() { return std::make_unique<ValidateCommand>(); }

}  // namespace rotorguard::cli

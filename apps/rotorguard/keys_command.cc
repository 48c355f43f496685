// rotorguard keys: every key a scenario file accepts, with its default, what it accepts and its meaning.
#include <fmt/format.h>

#include "rotorguard/harness/scenario_keys.h"
#include "cli.h"

namespace rotorguard::cli {

namespace {

class KeysCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    CLI::App* keys = app->add_subcommand(
        "keys",
        "Print every key a scenario file accepts, block by block, with its default, the values\n"
        "it accepts and its meaning (Markdown: the key tables of docs/scenarios.md).");
    keys->add_flag("--vehicle", vehicle_, "The keys of a vehicle file instead");
    return keys;
  }

  int Execute() override {
    fmt::print("{}", vehicle_ ? harness::VehicleKeyTable() : harness::ScenarioKeyTables());
    return kOk;
  }

 private:
  bool vehicle_ = false;
};

}  // namespace

std::unique_ptr<Command> MakeKeysCommand() { return std::make_unique<KeysCommand>(); }

}  // namespace rotorguard::cli

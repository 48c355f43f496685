// rotorguard keys: every key a scenario file accepts, with its default, what it accepts and its meaning.
#include <fmt/format.h>

#include "cli.h"
#include "rotorguard/harness/scenario_keys.h"

namespace rotorguard::cli {

namespace {

class KeysCommand final : public Command {
 public:
  CLI::App* Register(CLI::App* app) override {
    return app->add_subcommand("keys",
                               "Print every key a scenario file accepts, block by block, with its default, the values\n"
                               "it accepts and its meaning (Markdown: the key tables of docs/scenarios.md).");
  }

  int Execute() override {
    fmt::print("{}", harness::ScenarioKeyTables());
    return kOk;
  }
};

}  // namespace

std::unique_ptr<Command> MakeKeysCommand() { return std::make_unique<KeysCommand>(); }

}  // namespace rotorguard::cli

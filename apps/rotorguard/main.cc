// rotorguard: the command-line interface. Each command lives in its own file (run, report,
// validate, keys, fdd-calibrate, bench, campaign) and parses, calls the libraries and prints; here the
// commands are registered, the chosen one runs, and its errors become the documented exit codes
// (docs/cli.md): 0 success; 1 the run failed; 2 usage or invalid config; 3 an input file is
// unreadable or damaged; 4 an infeasible request.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <exception>
#include <memory>
#include <vector>

#include "cli.h"
#include "rotorguard/buildinfo/build_info.h"

int main(int argc, char** argv) {
  namespace cli = rotorguard::cli;
  CLI::App app{
      "rotorguard: multirotor flight stack and simulator that keeps flying after rotor failures.\n"
      "Exit codes: 0 success; 1 the run failed (crash); 2 usage or invalid config;\n"
      "3 an input file is unreadable; 4 an infeasible request.",
      "rotorguard"};
  app.set_version_flag("--version", rotorguard::buildinfo::ProgramVersion());  // the release and its revision
  app.require_subcommand(1);

  std::vector<std::unique_ptr<cli::Command>> commands;
  commands.push_back(cli::MakeRunCommand());
  commands.push_back(cli::MakeSitlCommand());
  commands.push_back(cli::MakeNodeCommand());
  commands.push_back(cli::MakeReplayCommand());
  commands.push_back(cli::MakeReportCommand());
  commands.push_back(cli::MakeValidateCommand());
  commands.push_back(cli::MakeKeysCommand());
  commands.push_back(cli::MakeFddCalibrateCommand());
  commands.push_back(cli::MakeBenchCommand());
  commands.push_back(cli::MakeCampaignCommand());
  std::vector<CLI::App*> subcommands;
  for (const auto& c : commands) subcommands.push_back(c->Register(&app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return cli::kUsage;
  }

  for (std::size_t i = 0; i < commands.size(); ++i) {
    if (!*subcommands[i]) continue;
    try {
      return commands[i]->Execute();
    } catch (const std::exception& e) {
      fmt::print(stderr, "error: {}\n", cli::MessageOf(e));
      return cli::ExitCodeOf(e);
    }
  }
  return cli::kUsage;
}

#pragma once
/// The fuzz targets: each feeds one input file, as bytes, to the code that reads it in the
/// product (`validate`, `report`, `campaign merge`, `fdd-calibrate`) and checks what a user is
/// promised: the reader either accepts the file, and then everything it computes from it is
/// finite, or refuses it with one of the documented errors (io::ConfigError, io::InputFileError,
/// io::CorruptFileError: exit codes 2 and 3) whose message names the file. Anything else, an
/// undocumented exception, a crash or a non-finite output, is a finding: the target prints it and
/// aborts, which both fuzz drivers report with the input that did it (docs/reliability.md).
///
/// The inputs are written into a scratch folder made once per process, which holds a copy of
/// configs/ (so that a scenario's `vehicle: ../vehicles/...` resolves) and the fixture folders of
/// tests/fuzz/corpus/ (a saved run, a campaign's results), whose other files stay valid while one
/// of them is fuzzed.
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace rotorguard::fuzz {

/// How an input ended, when it was not a finding.
enum class Outcome { kAccepted, kRefused };

struct Target {
  std::string_view name;
  /// The file the input replaces, relative to the scratch folder; its name is what a refusal must
  /// name.
  std::string_view file;
  /// Seeds beyond the fixture's own file (tests/fuzz/corpus/`file`, when there is one), relative
  /// to the source tree: files, or folders searched for files with the target's extension.
  std::vector<std::string_view> seeds;
  std::string_view what;  ///< the reader it exercises, for --help
  Outcome (*run)(const std::string& path);
};

/// Every target, in a fixed order.
const std::vector<Target>& Targets();

/// The target of that name, or null.
const Target* FindTarget(std::string_view name);

/// Writes `bytes` to the target's file in the scratch folder (made on first use, removed at exit)
/// and runs the target on it. A finding aborts.
Outcome RunOne(const Target& target, std::string_view bytes);

/// The scratch folder (an io::TemporaryFolder made on first use with configs/ and the fixtures
/// copied in).
const std::string& ScratchFolder();

/// The finite-number check of the targets: a finding naming `where` (a JSON pointer below it) and
/// `input` when a number of `j` is not finite.
void RequireFinite(const nlohmann::json& j, const std::string& input, const std::string& where);

/// The seed files of a target: its fixture file, then its `seeds` resolved in the source tree, sorted.
std::vector<std::string> SeedFiles(const Target& target);

}  // namespace rotorguard::fuzz

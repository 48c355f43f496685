#pragma once
/// `rotorguard validate`: any of the project's config files, its kind recognised from its keys.
#include <string>

namespace rotorguard::benchmarks {

/// What `rotorguard validate` found in a file.
struct ValidationReport {
  std::string kind;     ///< "vehicle", "assembly", "campaign", "scenario" or "fdd thresholds"
  std::string summary;  ///< one line describing the content
};
/// Validates a vehicle, assembly, campaign, scenario or FDD thresholds file, recognising its kind
/// from its keys.
/// Throws io::ConfigError (bad content, with file, line and key path) or io::InputFileError.
ValidationReport ValidateConfigFile(const std::string& path);

}  // namespace rotorguard::benchmarks

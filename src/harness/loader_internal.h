#pragma once
// The loaders' shared helpers (not public API): overrides and relative paths.
#include <string>
#include <vector>

#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"

namespace rotorguard::harness {

/// Applies the `--set` overrides of one document: the scenario's (vehicle_part false) or, for
/// paths starting with "vehicle.", the vehicle file's with that prefix taken off.
void ApplyOverrides(io::ConfigDocument* doc, const std::vector<Override>& overrides, bool vehicle_part);

/// `path` relative to the folder of `base_file` (unless absolute or base_file is empty).
std::string ResolveRelative(const std::string& base_file, const std::string& path);

}  // namespace rotorguard::harness

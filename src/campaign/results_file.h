#pragma once
// The engine's own reading of its files (not public API): a shard's results file, whose every line
// is one trial's record, and JSON manifests.
#include <cstddef>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace rotorguard::campaign {

/// The trials recorded in a results file, by index, and where its whole lines end (a last line cut
/// short by a kill starts there). Every line must be one trial's record; anything else is corruption.
struct Recorded {
  std::map<int, nlohmann::json> trials;
  std::size_t whole_size = 0;
  bool cut = false;  ///< the file ends in a partial line
};
Recorded ReadResults(const std::string& path);

}  // namespace rotorguard::campaign

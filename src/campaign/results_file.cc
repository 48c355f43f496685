#include "results_file.h"

#include <fmt/format.h>

#include <filesystem>

#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"

namespace rotorguard::campaign {

Recorded ReadResults(const std::string& path) {
  Recorded r;
  if (!std::filesystem::exists(path)) return r;
  std::string text = io::ReadInputFile(path);
  const std::size_t end = text.rfind('\n');
  r.whole_size = end == std::string::npos ? 0 : end + 1;
  r.cut = r.whole_size < text.size();
  text.resize(r.whole_size);
  std::size_t offset = 0;
  while (offset < text.size()) {
    const std::size_t nl = text.find('\n', offset);
    nlohmann::json j = nlohmann::json::parse(text.substr(offset, nl - offset), nullptr, false);
    const bool valid = !j.is_discarded() && j.is_object() && j.contains("trial") && j["trial"].is_number_integer() &&
                       j.contains("id") && j["id"].is_string() && j.contains("params") && j["params"].is_object() &&
                       j.contains("status") && j["status"].is_string() && j.contains("message") &&
                       j["message"].is_string() && j.contains("metrics") &&
                       (j["metrics"].is_object() || j["metrics"].is_null());
    if (!valid) {
      throw io::CorruptFileError(path, offset,
                                 "expected one trial record per line: {trial, id, params, status, "
                                 "message, metrics}");
    }
    const int index = j["trial"].get<int>();
    if (r.trials.count(index)) throw io::CorruptFileError(path, offset, fmt::format("trial {} recorded twice", index));
    r.trials.emplace(index, std::move(j));
    offset = nl + 1;
  }
  return r;
}

}  // namespace rotorguard::campaign

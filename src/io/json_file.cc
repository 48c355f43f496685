#include "rotorguard/io/json_file.h"

#include "rotorguard/io/config_node.h"

namespace rotorguard::io {

nlohmann::json ReadJsonObject(const std::string& path) {
  const std::string text = ReadInputFile(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw CorruptFileError(path, e.byte > 0 ? e.byte - 1 : 0, "not valid JSON");
  } catch (const nlohmann::json::exception& e) {  // out_of_range: a number beyond a double
    throw CorruptFileError(path, 0, std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw CorruptFileError(path, 0, "expected a JSON object");
  return j;
}

}  // namespace rotorguard::io

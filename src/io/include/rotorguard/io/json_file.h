#pragma once
/// JSON files the program reads back (a run's summary.json and scene.json, a campaign's
/// manifest.json): one reader, so that every damage, a syntax error or a number out of the double's
/// range (1e999) alike, is the same documented error.
#include <nlohmann/json.hpp>
#include <string>

namespace rotorguard::io {

/// Reads a file holding one JSON object. Throws InputFileError when it cannot be read and
/// CorruptFileError (with the byte of a syntax error) when it is not a JSON object.
nlohmann::json ReadJsonObject(const std::string& path);

}  // namespace rotorguard::io

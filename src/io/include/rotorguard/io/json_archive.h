#pragma once
/// The keys an options struct declares (core/config_schema.h) as a JSON object, and back: what
/// summary.json records of a run's settings, in the same keys as the scenario file.
#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "rotorguard/core/config_schema.h"

namespace rotorguard::io {

/// Writes each declared key's value: numbers, integers, booleans, words, enum names, vectors as
/// lists, blocks as objects, lists of blocks as lists of objects, an unset optional as null.
class JsonWriter {
 public:
  template <typename T, typename... Rest>
  void Visit(const char* key, T* value, const KeyInfo& = {}, Rest&&...) {
    json_[key] = ToValue(*value);
  }
  void Visit(const char* key, DegreesOf angle, const KeyInfo&) {
    json_[key] = *angle.radians * 180.0 / 3.14159265358979323846;
  }
  void Visit(const char* key, PairOf pair, const KeyInfo&) { json_[key] = {*pair.first, *pair.second}; }
  void Visit(const char* key, ConvertedOf number, const KeyInfo&) { json_[key] = number.to_file(*number.value); }
  void Visit(const char* key, TripleOf t, const KeyInfo&) { json_[key] = {*t.x, *t.y, *t.z}; }
  nlohmann::json& json() { return json_; }

 private:
  template <typename T>
  static nlohmann::json ToValue(T& value) {
    if constexpr (requires(JsonWriter * w) { value.Serialize(w); }) {
      JsonWriter nested;
      value.Serialize(&nested);
      return nested.json_;
    } else if constexpr (NamedEnum<T>) {
      return ToName(value);
    } else if constexpr (requires {
                           value.data();
                           value.size();
                           typename T::Scalar;
                         }) {  // an Eigen vector
      return std::vector<double>(value.data(), value.data() + value.size());
    } else if constexpr (requires { value.has_value(); }) {
      return value ? ToValue(*value) : nlohmann::json(nullptr);
    } else if constexpr (requires {
                           typename T::key_type;
                           typename T::mapped_type;
                         }) {  // a map with string keys: an object
      nlohmann::json object = nlohmann::json::object();
      for (auto& [key, item] : value) object[key] = ToValue(item);
      return object;
    } else if constexpr (requires {
                           value.begin();
                           typename T::value_type;
                         } &&
                         !std::is_same_v<T, std::string>) {
      nlohmann::json list = nlohmann::json::array();
      for (auto& item : value) list.push_back(ToValue(item));
      return list;
    } else {
      return value;
    }
  }

  nlohmann::json json_ = nlohmann::json::object();
};

/// Reads each declared key back (every one must be there); throws nlohmann::json::exception for a
/// missing or mistyped one.
class JsonReader {
 public:
  explicit JsonReader(const nlohmann::json& json) : json_(json) {}
  template <typename T, typename... Rest>
  void Visit(const char* key, T* value, const KeyInfo& = {}, Rest&&...) {
    FromValue(json_.at(key), value);
  }
  void Visit(const char* key, DegreesOf angle, const KeyInfo&) {
    *angle.radians = json_.at(key).get<double>() * 3.14159265358979323846 / 180.0;
  }
  void Visit(const char* key, ConvertedOf number, const KeyInfo&) {
    *number.value = number.from_file(json_.at(key).get<double>());
  }
  void Visit(const char* key, PairOf pair, const KeyInfo&) {
    *pair.first = json_.at(key).at(0).get<double>();
    *pair.second = json_.at(key).at(1).get<double>();
  }
  void Visit(const char* key, TripleOf t, const KeyInfo&) {
    *t.x = json_.at(key).at(0).get<double>();
    *t.y = json_.at(key).at(1).get<double>();
    *t.z = json_.at(key).at(2).get<double>();
  }

 private:
  template <typename T>
  static void FromValue(const nlohmann::json& j, T* value) {
    if constexpr (requires(JsonReader * r) { value->Serialize(r); }) {
      JsonReader nested(j);
      value->Serialize(&nested);
    } else if constexpr (NamedEnum<T>) {
      const std::string name = j.get<std::string>();
      const std::optional<T> parsed = FromName<T>(name);
      if (!parsed) throw nlohmann::json::other_error::create(501, "unknown name '" + name + "'", &j);
      *value = *parsed;
    } else if constexpr (requires {
                           value->data();
                           value->size();
                           typename T::Scalar;
                         }) {  // an Eigen vector
      const std::vector<double> v = j.get<std::vector<double>>();
      if (static_cast<Eigen::Index>(v.size()) != value->size()) {
        throw nlohmann::json::other_error::create(502, "wrong number of elements", &j);
      }
      for (std::size_t i = 0; i < v.size(); ++i) (*value)[static_cast<Eigen::Index>(i)] = v[i];
    } else if constexpr (requires { value->has_value(); }) {
      if (j.is_null()) {
        value->reset();
      } else {
        FromValue(j, &value->emplace());
      }
    } else if constexpr (requires {
                           typename T::key_type;
                           typename T::mapped_type;
                         }) {
      value->clear();
      for (const auto& [key, item] : j.items()) FromValue(item, &(*value)[key]);
    } else if constexpr (requires {
                           value->begin();
                           typename T::value_type;
                         } &&
                         !std::is_same_v<T, std::string>) {
      value->clear();
      for (const nlohmann::json& item : j) {
        typename T::value_type v{};
        FromValue(item, &v);
        value->push_back(v);
      }
    } else {
      *value = j.get<T>();
    }
  }

  const nlohmann::json& json_;
};

/// `options`' declared keys as a JSON object.
template <typename T>
nlohmann::json ToJson(T options) {
  JsonWriter writer;
  options.Serialize(&writer);
  return writer.json();
}

/// Reads `options`' declared keys from a JSON object (every one of them must be there).
template <typename T>
void FromJson(const nlohmann::json& json, T* options) {
  JsonReader reader(json);
  options->Serialize(&reader);
}

}  // namespace rotorguard::io

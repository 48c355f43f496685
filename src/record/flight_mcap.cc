#include "rotorguard/record/flight_mcap.h"

#include <cmath>
#include <cstring>
#include <set>

#include <fmt/format.h>

#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"
#include "rotorguard/io/mcap.h"

namespace rotorguard::record {

namespace {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

constexpr const char* kLogTopic = "/rotorguard/log";
constexpr const char* kRecordName = "rotorguard";

std::uint64_t Nanoseconds(double t) { return static_cast<std::uint64_t>(std::llround(std::max(0.0, t) * 1e9)); }
Json Stamp(double t) {
  const std::uint64_t ns = Nanoseconds(t);
  return {{"sec", ns / 1000000000ull}, {"nsec", ns % 1000000000ull}};
}
Json Xyz(double x, double y, double z) { return {{"x", x}, {"y", y}, {"z", z}}; }
Json Xyzw(double w, double x, double y, double z) { return {{"x", x}, {"y", y}, {"z", z}, {"w", w}}; }
Json Pose(const Json& position, const Json& orientation) { return {{"position", position}, {"orientation", orientation}}; }
Json Identity() { return Pose(Xyz(0, 0, 0), Xyzw(1, 0, 0, 0)); }
Json Color(double r, double g, double b, double a) { return {{"r", r}, {"g", g}, {"b", b}, {"a", a}}; }
Json YawQuaternion(double yaw) { return Xyzw(std::cos(0.5 * yaw), 0, 0, std::sin(0.5 * yaw)); }
Json Vec3(const Json& a) { return Xyz(a[0].get<double>(), a[1].get<double>(), a[2].get<double>()); }

/// A JSON Schema naming the Foxglove (or rotorguard) type, with its top-level fields' types.
std::string SchemaText(const std::string& name, const Json& properties) {
  return Json{{"title", name}, {"type", "object"}, {"properties", properties}}.dump();
}
const Json kTime = {{"type", "object"}, {"properties", {{"sec", {{"type", "integer"}}}, {"nsec", {{"type", "integer"}}}}}};
const Json kObject = {{"type", "object"}};
const Json kString = {{"type", "string"}};
const Json kArray = {{"type", "array"}};
const Json kNumber = {{"type", "number"}};

Json Entity(double t, const std::string& id) {
  return {{"timestamp", Stamp(t)}, {"frame_id", "world"}, {"id", id}, {"lifetime", {{"sec", 0}, {"nsec", 0}}},
          {"frame_locked", false}, {"metadata", Json::array()}, {"arrows", Json::array()}, {"cubes", Json::array()},
          {"spheres", Json::array()}, {"cylinders", Json::array()}, {"lines", Json::array()},
          {"triangles", Json::array()}, {"texts", Json::array()}, {"models", Json::array()}};
}
Json Cube(const Json& center, const Json& size, double yaw, const Json& color) {
  return {{"pose", Pose(Vec3(center), YawQuaternion(yaw))}, {"size", Vec3(size)}, {"color", color}};
}
Json SceneUpdate(const Json& entities) { return {{"deletions", Json::array()}, {"entities", entities}}; }

class Writer {
 public:
  explicit Writer(io::McapWriter* w) : w_(w) {}
  std::uint16_t Channel(const std::string& topic, const std::string& schema, const Json& properties) {
    auto it = schemas_.find(schema);
    if (it == schemas_.end()) it = schemas_.emplace(schema, w_->AddSchema(schema, "jsonschema", SchemaText(schema, properties))).first;
    return w_->AddChannel(it->second, topic, "json");
  }

 private:
  io::McapWriter* w_;
  std::map<std::string, std::uint16_t> schemas_;
};

}  // namespace

void WriteFlightMcap(const FlightLog& log, const std::string& path) {
  io::McapWriter mcap;
  Writer channels(&mcap);
  const io::NumericTable& table = log.table;
  const auto col = [&](const std::string& name) -> const std::vector<double>& { return table.Column(name); };
  int n = 0;
  while (table.Has(fmt::format("cmd_{}", n))) ++n;
  const bool with_fdd = table.Has("mi_0");
  const bool with_lio = table.Has("lio_matched");

  const Json pose_props = {{"timestamp", kTime}, {"frame_id", kString}, {"pose", kObject}};
  const std::uint16_t tf = channels.Channel("/tf", "foxglove.FrameTransform",
                                            {{"timestamp", kTime}, {"parent_frame_id", kString}, {"child_frame_id", kString},
                                             {"translation", kObject}, {"rotation", kObject}});
  const std::uint16_t pose = channels.Channel("/pose", "foxglove.PoseInFrame", pose_props);
  const std::uint16_t estimate = channels.Channel("/estimate", "foxglove.PoseInFrame", pose_props);
  const std::uint16_t reference = channels.Channel("/reference", "foxglove.PoseInFrame", pose_props);
  const std::uint16_t rotors = channels.Channel(
      "/rotors", "rotorguard.RotorState",
      {{"timestamp", kTime}, {"command_n", kArray}, {"thrust_n", kArray}, {"rpm", kArray}, {"fault", kArray}});
  std::uint16_t fdd = 0;
  if (with_fdd) {
    fdd = channels.Channel("/fdd", "rotorguard.FddIndices",
                           {{"timestamp", kTime}, {"motor_index", kArray}, {"propeller_index", kArray}, {"health", kArray}});
  }
  std::uint16_t lio = 0;
  if (with_lio) {
    lio = channels.Channel("/lio", "rotorguard.LioHealth",
                           {{"timestamp", kTime},
                            {"used", kNumber},
                            {"degenerate", kNumber},
                            {"points_matched", kNumber},
                            {"residual_rms_m", kNumber},
                            {"weakest_std_m", kNumber}});
  }
  const Json scene_props = {{"deletions", kArray}, {"entities", kArray}};
  const std::uint16_t obstacles = channels.Channel("/obstacles", "foxglove.SceneUpdate", scene_props);
  const std::uint16_t plans = channels.Channel("/planner/trajectory", "foxglove.SceneUpdate", scene_props);
  const std::uint16_t map = channels.Channel("/map", "foxglove.PointCloud",
                                             {{"timestamp", kTime}, {"frame_id", kString}, {"pose", kObject},
                                              {"point_stride", {{"type", "integer"}}}, {"fields", kArray}, {"data", kString}});
  Json log_props = Json::object();
  for (const std::string& c : table.columns) log_props[c] = kNumber;
  const std::uint16_t raw = channels.Channel(kLogTopic, "rotorguard.LogRow", log_props);

  // Everything is written in time order: the log's rows, with the scene's events merged in.
  struct Event {
    double t;
    std::uint16_t channel;
    std::string data;
  };
  std::vector<Event> events;
  const Json& world = log.scene.at("world");
  {
    Json entity = Entity(0.0, "static");
    for (const Json& b : world.at("boxes")) {
      entity["cubes"].push_back(Cube(b.at("center_m"), b.at("size_m"), b.at("yaw_rad").get<double>(), Color(0.55, 0.45, 0.35, 0.9)));
    }
    for (const Json& c : world.at("cylinders")) {
      const double r = c.at("radius_m").get<double>(), h = c.at("height_m").get<double>();
      entity["cylinders"].push_back({{"pose", Pose(Xyz(c.at("center_m")[0].get<double>(), c.at("center_m")[1].get<double>(), 0.5 * h), Xyzw(1, 0, 0, 0))},
                                     {"size", Xyz(2 * r, 2 * r, h)}, {"bottom_scale", 1.0}, {"top_scale", 1.0},
                                     {"color", Color(0.35, 0.5, 0.3, 0.9)}});
    }
    events.push_back({0.0, obstacles, SceneUpdate(Json::array({entity})).dump()});
    const Json& moving = world.at("moving_boxes");
    for (std::size_t i = 0; i < moving.size(); ++i) {
      const Json& m = moving[i];
      for (std::size_t k = 0; k < m.at("t_s").size(); ++k) {
        const double t = m["t_s"][k].get<double>();
        Json e = Entity(t, fmt::format("moving_box_{}", i));
        e["cubes"].push_back(Cube(m["center_m"][k], m.at("size_m"), 0.0, Color(0.8, 0.35, 0.2, 0.9)));
        events.push_back({t, obstacles, SceneUpdate(Json::array({e})).dump()});
      }
    }
  }
  for (const Json& p : log.scene.at("plans")) {
    const double t = p.at("t_s").get<double>();
    Json e = Entity(t, "plan");
    Json points = Json::array();
    for (const Json& q : p.at("points_m")) points.push_back(Vec3(q));
    e["lines"].push_back({{"type", 0}, {"pose", Identity()}, {"thickness", 0.04}, {"scale_invariant", false},
                          {"points", points}, {"color", Color(0.1, 0.6, 1.0, 1.0)}, {"colors", Json::array()},
                          {"indices", Json::array()}});
    events.push_back({t, plans, SceneUpdate(Json::array({e})).dump()});
  }
  if (const Json& m = log.scene.at("map"); !m.is_null()) {
    const double res = m.at("resolution_m").get<double>();
    std::set<std::array<long, 3>> voxels;
    for (const Json& s : m.at("snapshots")) {
      const auto apply = [&](const Json& flat, bool add) {
        for (std::size_t k = 0; k + 2 < flat.size(); k += 3) {
          const std::array<long, 3> v = {flat[k].get<long>(), flat[k + 1].get<long>(), flat[k + 2].get<long>()};
          if (add) voxels.insert(v); else voxels.erase(v);
        }
      };
      apply(s.at("removed"), false);
      apply(s.at("added"), true);
      std::string bytes;
      for (const auto& v : voxels) {
        for (int a = 0; a < 3; ++a) {
          const auto f = static_cast<float>((static_cast<double>(v[a]) + 0.5) * res);
          char b[4];
          std::memcpy(b, &f, 4);  // little-endian float32, as Foxglove's FLOAT32 field
          bytes.append(b, 4);
        }
      }
      const double t = s.at("t_s").get<double>();
      const Json fields = Json::array({{{"name", "x"}, {"offset", 0}, {"type", 7}},
                                       {{"name", "y"}, {"offset", 4}, {"type", 7}},
                                       {{"name", "z"}, {"offset", 8}, {"type", 7}}});
      events.push_back({t, map,
                        Json{{"timestamp", Stamp(t)}, {"frame_id", "world"}, {"pose", Identity()}, {"point_stride", 12},
                             {"fields", fields}, {"data", io::Base64Encode(bytes)}}.dump()});
    }
  }
  std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.t < b.t; });

  const std::vector<double>& t = col("t");
  std::size_t next_event = 0;
  const auto flush_events = [&](double until) {
    for (; next_event < events.size() && events[next_event].t <= until; ++next_event) {
      mcap.AddMessage(events[next_event].channel, Nanoseconds(events[next_event].t), events[next_event].data);
    }
  };
  const auto per_rotor = [&](const char* prefix, std::size_t r) {
    Json a = Json::array();
    for (int i = 0; i < n; ++i) a.push_back(col(fmt::format("{}{}", prefix, i))[r]);
    return a;
  };
  for (std::size_t r = 0; r < table.rows(); ++r) {
    flush_events(t[r]);
    const std::uint64_t ns = Nanoseconds(t[r]);
    const Json stamp = Stamp(t[r]);
    const Json p = Xyz(col("p_x")[r], col("p_y")[r], col("p_z")[r]);
    const Json q = Xyzw(col("q_w")[r], col("q_x")[r], col("q_y")[r], col("q_z")[r]);
    mcap.AddMessage(tf, ns, Json{{"timestamp", stamp}, {"parent_frame_id", "world"}, {"child_frame_id", "base_link"},
                                 {"translation", p}, {"rotation", q}}.dump());
    mcap.AddMessage(pose, ns, Json{{"timestamp", stamp}, {"frame_id", "world"}, {"pose", Pose(p, q)}}.dump());
    mcap.AddMessage(estimate, ns,
                    Json{{"timestamp", stamp}, {"frame_id", "world"},
                         {"pose", Pose(Xyz(col("est_p_x")[r], col("est_p_y")[r], col("est_p_z")[r]),
                                       Xyzw(col("est_q_w")[r], col("est_q_x")[r], col("est_q_y")[r], col("est_q_z")[r]))}}.dump());
    mcap.AddMessage(reference, ns,
                    Json{{"timestamp", stamp}, {"frame_id", "world"},
                         {"pose", Pose(Xyz(col("ref_p_x")[r], col("ref_p_y")[r], col("ref_p_z")[r]), YawQuaternion(col("ref_yaw")[r]))}}.dump());
    mcap.AddMessage(rotors, ns, Json{{"timestamp", stamp}, {"command_n", per_rotor("cmd_", r)}, {"thrust_n", per_rotor("thrust_", r)},
                                     {"rpm", per_rotor("rpm_", r)}, {"fault", per_rotor("fault_", r)}}.dump());
    if (with_fdd) {
      mcap.AddMessage(fdd, ns, Json{{"timestamp", stamp}, {"motor_index", per_rotor("mi_", r)},
                                    {"propeller_index", per_rotor("pi_", r)}, {"health", per_rotor("health_", r)}}.dump());
    }
    if (with_lio) {
      mcap.AddMessage(lio, ns,
                      Json{{"timestamp", stamp},
                           {"used", col("lio_used")[r]},
                           {"degenerate", col("lio_degenerate")[r]},
                           {"points_matched", col("lio_matched")[r]},
                           {"residual_rms_m", col("lio_residual_rms_m")[r]},
                           {"weakest_std_m", col("lio_weakest_std_m")[r]}}
                          .dump());
    }
    OrderedJson row;
    for (std::size_t c = 0; c < table.columns.size(); ++c) row[table.columns[c]] = table.values[c][r];
    mcap.AddMessage(raw, ns, row.dump());
  }
  flush_events(std::numeric_limits<double>::infinity());
  std::string columns;
  for (const std::string& c : table.columns) columns += (columns.empty() ? "" : ",") + c;
  mcap.AddMetadata(kRecordName, {{"summary", log.summary.dump()}, {"scene", log.scene.dump()}, {"log_columns", columns}});
  io::WriteFileAtomically(path, mcap.Finish());
}

FlightLog ReadFlightMcap(const std::string& path) {
  const io::McapContent content = io::ReadMcap(path);
  const io::McapMetadata* record = content.FindMetadata(kRecordName);
  const io::McapChannel* log_channel = content.FindChannel(kLogTopic);
  if (record == nullptr || log_channel == nullptr || !record->metadata.count("scene") ||
      !record->metadata.count("summary") || !record->metadata.count("log_columns")) {
    throw io::CorruptFileError(path, 0, fmt::format("a valid MCAP file but not a rotorguard flight: it lacks the '{}' "
                                                    "metadata or the {} channel", kRecordName, kLogTopic));
  }
  FlightLog log;
  try {
    log.summary = Json::parse(record->metadata.at("summary"));
    log.scene = Json::parse(record->metadata.at("scene"));
  } catch (const Json::parse_error& e) {
    throw io::CorruptFileError(path, record->offset, fmt::format("the '{}' metadata is not valid JSON: {}", kRecordName, e.what()));
  }
  const std::string& columns = record->metadata.at("log_columns");
  for (std::size_t start = 0; start <= columns.size();) {
    const std::size_t end = std::min(columns.find(',', start), columns.size());
    log.table.columns.push_back(columns.substr(start, end - start));
    start = end + 1;
  }
  log.table.values.resize(log.table.columns.size());
  for (const io::McapMessage& m : content.messages) {
    if (m.channel_id != log_channel->id) continue;
    OrderedJson row;
    try {
      row = OrderedJson::parse(m.data);
    } catch (const OrderedJson::parse_error&) {
      throw io::CorruptFileError(path, m.offset, fmt::format("{} message {} is not valid JSON", kLogTopic, m.sequence));
    }
    for (std::size_t c = 0; c < log.table.columns.size(); ++c) {
      const auto it = row.find(log.table.columns[c]);
      if (it == row.end() || !it->is_number()) {
        throw io::CorruptFileError(path, m.offset, fmt::format("{} message {} lacks the number '{}'", kLogTopic, m.sequence,
                                                        log.table.columns[c]));
      }
      log.table.values[c].push_back(it->get<double>());
    }
  }
  return log;
}

}  // namespace rotorguard::record


#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "rotorguard/core/error.h"
#include "rotorguard/harness/assembly_mission.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::harness {

namespace {
using io::ConfigDocument;
using io::ConfigNode;

/// Runs a validation and re-raises its error at the offending key of `node`.
template <typename F>
void ValidateAt(const ConfigNode& node, F&& validate) {
  try {
    validate();
  } catch (const ValidationError& e) {
    node.FailAt(e.field(), e.what());
  } catch (const std::invalid_argument& e) {
    node.Fail(e.what());
  }
}

double OptionalDouble(const ConfigNode& map, std::string_view key, double fallback) {
  const auto n = map.Optional(key);
  return n ? n->AsDouble() : fallback;
}
Vector3 OptionalVector3(const ConfigNode& map, std::string_view key, const Vector3& fallback) {
  const auto n = map.Optional(key);
  return n ? n->AsVector3() : fallback;
}

/// Overwrites *value with the key's value when the key is present (the field's default stays
/// otherwise).
void ReadOptional(const ConfigNode& map, std::string_view key, double* value) {
  *value = OptionalDouble(map, key, *value);
}
void ReadOptional(const ConfigNode& map, std::string_view key, Vector3* value) {
  *value = OptionalVector3(map, key, *value);
}

// ---------------------------------------------------------------- vehicle

vehicle::VehicleParams ParseVehicle(const ConfigNode& root) {
  vehicle::VehicleParams v;
  v.name = root.Has("name") ? root.Required("name").AsString() : "vehicle";
  v.mass_kg = root.Required("mass_kg").AsDouble();
  const ConfigNode inertia = root.Required("inertia_kg_m2");
  if (!inertia.IsSequence() || inertia.size() != 3) {
    inertia.Fail("expected a 3x3 matrix written as three rows of three numbers");
  }
  for (std::size_t r = 0; r < 3; ++r) {
    const std::vector<double> row = inertia.At(r).AsDoubleList(3);
    for (int c = 0; c < 3; ++c) v.inertia_kg_m2(static_cast<int>(r), c) = row[c];
  }
  v.rotor_drag_kg_s = root.Required("rotor_drag_kg_s").AsVector3();
  v.yaw_damping_n_m_s = root.Required("yaw_damping_n_m_s").AsDouble();
  v.thrust_coefficient_n_s2 =
      vehicle::ThrustCoefficientFromRpm(root.Required("thrust_coefficient_n_per_rpm2").AsPositive());
  v.motor_time_constant_s = root.Required("motor_time_constant_s").AsDouble();
  v.motor_stop_time_constant_s = root.Required("motor_stop_time_constant_s").AsDouble();
  v.unloaded_speed_ratio = root.Required("unloaded_rpm_ratio").AsDouble();
  v.collision_radius_m = root.Required("collision_radius_m").AsDouble();
  if (root.Has("pwm_gain_n")) v.pwm_gain_n = root.Required("pwm_gain_n").AsPositive();
  if (const auto spheres = root.Optional("collision_spheres")) {
    if (!spheres->IsSequence() || spheres->size() == 0) spheres->Fail("expected a non-empty list of spheres");
    for (std::size_t i = 0; i < spheres->size(); ++i) {
      const ConfigNode c = spheres->At(i);
      v.collision_spheres.push_back({c.Required("centre_m").AsVector3(), c.Required("radius_m").AsPositive()});
      c.RejectUnknownKeys();
    }
  }
  const ConfigNode rotors = root.Required("rotors");
  if (!rotors.IsSequence() || rotors.size() == 0) rotors.Fail("expected a non-empty list of rotors");
  for (std::size_t i = 0; i < rotors.size(); ++i) {
    const ConfigNode r = rotors.At(i);
    vehicle::Rotor rotor;
    rotor.p_B = r.Required("position_m").AsVector3();
    rotor.direction = r.Required("direction").AsEnum({"ccw", "cw"}) == "cw"
                          ? vehicle::SpinDirection::kClockwise
                          : vehicle::SpinDirection::kCounterClockwise;
    rotor.yaw_coefficient_m = r.Required("yaw_coefficient_m").AsDouble();
    rotor.max_thrust_n = r.Required("max_thrust_n").AsDouble();
    r.RejectUnknownKeys();
    v.rotors.push_back(rotor);
  }
  root.RejectUnknownKeys();
  ValidateAt(root, [&] { v.Validate(); });
  return v;
}

}  // namespace

void FitStackToHardware(Scenario* s) {
  // The fault detectors know their own IMU: the sensor's rate and mounting point.
  s->stack.composite_fdd.imu_rate_hz = s->sim.imu.rate_hz;
  s->stack.composite_fdd.imu_position_m = s->sim.imu.position_m;
  s->stack.fixed_time_fdd.imu_rate_hz = s->sim.imu.rate_hz;
  s->stack.fixed_time_fdd.imu_position_m = s->sim.imu.position_m;
  s->stack.ukf_fdd.imu_rate_hz = s->sim.imu.rate_hz;
  s->stack.ukf_fdd.imu_position_m = s->sim.imu.position_m;
  s->stack.estimator.imu_position_m = s->sim.imu.position_m;  // its dead-reckoning removes the lever arm
  // The mapper knows where its LiDAR sits and inflates obstacles by the vehicle's radius and a margin.
  s->stack.lidar.deskew.sensor_position_m = s->sim.lidar.position_m;
  s->stack.lidar.map.inflation_radius_m = s->vehicle.collision_radius_m + s->stack.lidar.inflation_margin_m;
}

std::string ScenarioFingerprint(const Scenario& scenario) {
  return (scenario.file.empty() ? std::string() : io::ReadInputFile(scenario.file)) + "\n" +
         VehicleToYaml(scenario.vehicle);
}

std::string VehicleToYaml(const vehicle::VehicleParams& v) {
  auto out = fmt::memory_buffer();
  auto it = std::back_inserter(out);
  const auto vec = [](const Vector3& x) { return fmt::format("[{}, {}, {}]", x.x(), x.y(), x.z()); };
  const double rpm_per_rad_s = vehicle::RadPerSecondToRpm(1.0);
  fmt::format_to(it, "# Written by rotorguard: the vehicle a run flew (the format of configs/vehicles/).\n");
  // A JSON string is a valid YAML double-quoted scalar.
  fmt::format_to(it, "name: {}\nmass_kg: {}\ninertia_kg_m2:\n", nlohmann::json(v.name).dump(), v.mass_kg);
  for (int r = 0; r < 3; ++r) fmt::format_to(it, "  - {}\n", vec(v.inertia_kg_m2.row(r).transpose()));
  fmt::format_to(it, "rotor_drag_kg_s: {}\nyaw_damping_n_m_s: {}\n", vec(v.rotor_drag_kg_s), v.yaw_damping_n_m_s);
  fmt::format_to(it, "thrust_coefficient_n_per_rpm2: {}\n", v.thrust_coefficient_n_s2 / (rpm_per_rad_s * rpm_per_rad_s));
  fmt::format_to(it, "motor_time_constant_s: {}\nmotor_stop_time_constant_s: {}\n", v.motor_time_constant_s,
                 v.motor_stop_time_constant_s);
  fmt::format_to(it, "unloaded_rpm_ratio: {}\ncollision_radius_m: {}\n", v.unloaded_speed_ratio, v.collision_radius_m);
  if (v.pwm_gain_n > 0.0) fmt::format_to(it, "pwm_gain_n: {}\n", v.pwm_gain_n);
  if (!v.collision_spheres.empty()) {  // an assembly's footprint, unit by unit
    fmt::format_to(it, "collision_spheres:\n");
    for (const vehicle::CollisionSphere& c : v.collision_spheres) {
      fmt::format_to(it, "  - {{centre_m: {}, radius_m: {}}}\n", vec(c.centre_B), c.radius_m);
    }
  }
  fmt::format_to(it, "rotors:\n");
  for (const vehicle::Rotor& r : v.rotors) {
    fmt::format_to(it, "  - {{position_m: {}, direction: {}, yaw_coefficient_m: {}, max_thrust_n: {}}}\n",
                   vec(r.p_B), r.direction == vehicle::SpinDirection::kClockwise ? "cw" : "ccw", r.yaw_coefficient_m,
                   r.max_thrust_n);
  }
  return fmt::to_string(out);
}

namespace {

void ApplyOverrides(ConfigDocument* doc, const std::vector<Override>& overrides, bool vehicle_part) {
  constexpr std::string_view kVehiclePrefix = "vehicle.";
  for (const auto& [path, value] : overrides) {
    const bool is_vehicle = path.rfind(kVehiclePrefix, 0) == 0;
    if (is_vehicle != vehicle_part) continue;
    if (!is_vehicle) {
      doc->ApplyOverride(path, value);
      continue;
    }
    try {
      doc->ApplyOverride(path.substr(kVehiclePrefix.size()), value);
    } catch (const io::ConfigError& e) {
      // Report the path as the user wrote it, with its prefix.
      throw io::ConfigError(e.file(), e.line(), e.column(), std::string(kVehiclePrefix) + e.key_path(),
                            e.message());
    }
  }
}

// ---------------------------------------------------------------- world

sim::World ParseWorld(const ConfigNode& node) {
  sim::World w;
  if (const auto boxes = node.Optional("boxes")) {
    for (std::size_t i = 0; i < boxes->size(); ++i) {
      const ConfigNode b = boxes->At(i);
      sim::Box box;
      box.center_m = b.Required("center_m").AsVector3();
      box.size_m = b.Required("size_m").AsVector3();
      if (box.size_m.minCoeff() <= 0.0) b.FailAt("size_m", "box sizes must be > 0 m");
      box.yaw_rad = OptionalDouble(b, "yaw_rad", 0.0);
      b.RejectUnknownKeys();
      w.boxes.push_back(box);
    }
  }
  if (const auto cylinders = node.Optional("cylinders")) {
    for (std::size_t i = 0; i < cylinders->size(); ++i) {
      const ConfigNode c = cylinders->At(i);
      sim::Cylinder cyl;
      const std::vector<double> xy = c.Required("center_m").AsDoubleList(2);
      cyl.center_m = Eigen::Vector2d(xy[0], xy[1]);
      cyl.radius_m = c.Required("radius_m").AsPositive();
      cyl.height_m = c.Required("height_m").AsPositive();
      c.RejectUnknownKeys();
      w.cylinders.push_back(cyl);
    }
  }
  if (const auto moving = node.Optional("moving_boxes")) {
    for (std::size_t i = 0; i < moving->size(); ++i) {
      const ConfigNode m = moving->At(i);
      sim::MovingBox mb;
      mb.size_m = m.Required("size_m").AsVector3();
      if (mb.size_m.minCoeff() <= 0.0) m.FailAt("size_m", "box sizes must be > 0 m");
      const ConfigNode wps = m.Required("waypoints_m");
      if (!wps.IsSequence() || wps.size() == 0) wps.Fail("expected a non-empty list of [x, y, z] points");
      for (std::size_t k = 0; k < wps.size(); ++k) mb.waypoints_m.push_back(wps.At(k).AsVector3());
      mb.speed_m_s = m.Required("speed_m_s").AsNonNegative();
      if (const auto loop = m.Optional("loop")) mb.loop = loop->AsBool();
      if (const auto start = m.Optional("start_s")) mb.start_s = start->AsNonNegative();
      m.RejectUnknownKeys();
      w.moving_boxes.push_back(mb);
    }
  }
  node.RejectUnknownKeys();
  return w;
}

// ---------------------------------------------------------------- mission

std::shared_ptr<const ReferenceTrajectory> ParseMission(const ConfigNode& node, Scenario* scenario,
                                                        std::string* type) {
  const Scenario& s = *scenario;
  *type = node.Required("type").AsEnum(
      {"hover", "takeoff", "lemniscate", "circle", "waypoints", "navigate", "assembly_plan"});
  std::shared_ptr<const ReferenceTrajectory> ref;
  const double yaw = OptionalDouble(node, "yaw_rad", s.initial_yaw_rad);
  try {
    if (*type == "hover") {
      planning::HoverOptions o;
      o.position_m = OptionalVector3(node, "position_m", s.initial_position_m);
      o.yaw_rad = yaw;
      ref = std::make_shared<planning::HoverReference>(o);
    } else if (*type == "takeoff") {
      planning::TakeoffOptions o;
      o.start_m = s.initial_position_m;
      o.altitude_m = node.Required("altitude_m").AsPositive();  // a take-off climbs
      ReadOptional(node, "max_speed_m_s", &o.max_speed_m_s);
      o.yaw_rad = yaw;
      ref = std::make_shared<planning::TakeoffReference>(o);
    } else if (*type == "lemniscate") {
      planning::LemniscateOptions o;
      o.center_m = OptionalVector3(node, "center_m", s.initial_position_m);
      const Vector3 size = OptionalVector3(node, "size_m", Vector3(o.size_x_m, o.size_y_m, o.size_z_m));
      o.size_x_m = size.x();
      o.size_y_m = size.y();
      o.size_z_m = size.z();
      o.max_speed_m_s = node.Required("max_speed_m_s").AsDouble();
      ReadOptional(node, "ramp_s", &o.ramp_s);
      o.yaw_rad = yaw;
      ref = std::make_shared<planning::LemniscateReference>(o);
    } else if (*type == "circle") {
      planning::CircleOptions o;
      o.center_m = node.Required("center_m").AsVector3();
      o.radius_m = node.Required("radius_m").AsDouble();
      o.speed_m_s = node.Required("speed_m_s").AsDouble();
      ReadOptional(node, "ramp_s", &o.ramp_s);
      if (const auto cw = node.Optional("clockwise")) o.clockwise = cw->AsBool();
      ReadOptional(node, "climb_m_s", &o.climb_m_s);
      o.yaw_rad = yaw;
      ref = std::make_shared<planning::CircleReference>(o);
    } else if (*type == "assembly_plan") {
      // Planned once the stack's keys are read (its known faults): LoadScenario's end.
      if (!s.assembly) node.Fail("mission assembly_plan plans for an assembly; expected the key 'assembly'");
      if (!s.world.moving_boxes.empty()) {
        node.Fail("mission assembly_plan plans once, on a fixed map; expected a world without moving_boxes");
      }
      AssemblyPlanSpec p;
      p.goal_m = node.Required("goal_m").AsVector3();
      if (const auto m = node.Optional("method")) p.method = m->AsEnum({"ours", "baseline"});
      for (const auto& [key, field] : {std::pair{"max_speed_m_s", &p.max_speed_m_s},
                                       std::pair{"max_accel_m_s2", &p.max_accel_m_s2},
                                       std::pair{"max_jerk_m_s3", &p.max_jerk_m_s3},
                                       std::pair{"max_yaw_rate_rad_s", &p.max_yaw_rate_rad_s}}) {
        if (const auto v = node.Optional(key)) *field = v->AsPositive();
      }
      if (const auto v = node.Optional("safety_factor")) p.safety_factor = v->AsDoubleIn(0.01, 1.0);
      if (const auto v = node.Optional("attitude_weight")) p.attitude_weight = v->AsDoubleIn(0.0, 100.0);
      if (const auto v = node.Optional("time_weight")) p.time_weight = v->AsDoubleIn(0.0, 1e6);
      if (const auto v = node.Optional("map_resolution_m")) p.map_resolution_m = v->AsDoubleIn(0.02, 1.0);
      scenario->assembly_plan = p;
      planning::HoverOptions o;
      o.position_m = s.initial_position_m;
      o.yaw_rad = s.initial_yaw_rad;
      ref = std::make_shared<planning::HoverReference>(o);
    } else if (*type == "navigate") {
      // Planned on the LiDAR map (docs/planning.md): the stack holds the initial position until
      // its first plan, then flies the waypoints in turn, `rounds` times.
      const ConfigNode wps = node.Required("waypoints_m");
      if (!wps.IsSequence() || wps.size() == 0) wps.Fail("expected a non-empty list of [x, y, z] points");
      stack::NavigationOptions& n = scenario->stack.navigation;
      n.waypoints.clear();
      for (std::size_t k = 0; k < wps.size(); ++k) n.waypoints.push_back(wps.At(k).AsVector3());
      if (const auto r = node.Optional("rounds")) n.rounds = static_cast<int>(r->AsIntIn(1, 1000));
      planning::HoverOptions o;
      o.position_m = s.initial_position_m;
      o.yaw_rad = yaw;
      ref = std::make_shared<planning::HoverReference>(o);
    } else {
      planning::WaypointOptions o;
      o.waypoints_m.push_back(s.initial_position_m);
      const ConfigNode wps = node.Required("waypoints_m");
      if (!wps.IsSequence() || wps.size() == 0) wps.Fail("expected a non-empty list of [x, y, z] points");
      for (std::size_t k = 0; k < wps.size(); ++k) o.waypoints_m.push_back(wps.At(k).AsVector3());
      o.max_speed_m_s = node.Required("max_speed_m_s").AsDouble();
      ReadOptional(node, "max_accel_m_s2", &o.max_accel_m_s2);
      ReadOptional(node, "dwell_s", &o.dwell_s);
      o.yaw_rad = yaw;
      ref = std::make_shared<planning::WaypointReference>(o);
    }
  } catch (const std::invalid_argument& e) {
    node.Fail(e.what());
  }
  node.RejectUnknownKeys();
  return ref;
}

// ---------------------------------------------------------------- faults

sim::FaultSpec ParseFault(const ConfigNode& f) {
  sim::FaultSpec spec;
  // The range is checked against the vehicle's rotor count by FaultSpec::Validate.
  spec.rotor = static_cast<int>(f.Required("rotor").AsIntIn(-1'000'000, 1'000'000));
  const ConfigNode kind = f.Required("kind");
  spec.kind = *vehicle::ParseFaultKind(
      kind.AsEnum({"motor_stop", "propeller_loss", "loss_of_effectiveness", "stuck"}));
  if (spec.kind == vehicle::FaultKind::kLossOfEffectiveness) {
    spec.eta = f.Required("eta").AsDouble();
  } else if (f.Has("eta")) {
    f.FailAt("eta", "eta applies to kind loss_of_effectiveness only");
  }
  const ConfigNode onset = f.Required("onset");
  const std::vector<std::pair<const char*, sim::FaultOnset::Kind>> kinds = {
      {"at_time_s", sim::FaultOnset::Kind::kAtTime},
      {"at_altitude_m", sim::FaultOnset::Kind::kAtAltitude},
      {"during_takeoff_s", sim::FaultOnset::Kind::kDuringTakeoff}};
  int found = 0;
  for (const auto& [key, k] : kinds) {
    if (onset.Has(key)) {
      spec.onset.kind = k;
      spec.onset.value = onset.Required(key).AsDouble();
      ++found;
    }
  }
  onset.RejectUnknownKeys();
  if (found != 1) onset.Fail("expected exactly one of at_time_s, at_altitude_m, during_takeoff_s");
  if (const auto im = f.Optional("intermittent")) {
    sim::IntermittentPattern p;
    p.on_s = im->Required("on_s").AsDouble();
    p.off_s = im->Required("off_s").AsDouble();
    im->RejectUnknownKeys();
    spec.intermittent = p;
  }
  f.RejectUnknownKeys();
  return spec;
}

// ---------------------------------------------------------------- sensors, sim, stack

void ParseSensors(const ConfigNode& node, sim::SimulatorOptions* o) {
  if (const auto imu = node.Optional("imu")) {
    sim::ImuOptions& i = o->imu;
    ReadOptional(*imu, "rate_hz", &i.rate_hz);
    ReadOptional(*imu, "position_m", &i.position_m);
    ReadOptional(*imu, "accel_noise_density", &i.accel_noise_density);
    ReadOptional(*imu, "gyro_noise_density", &i.gyro_noise_density);
    ReadOptional(*imu, "accel_bias_random_walk", &i.accel_bias_random_walk);
    ReadOptional(*imu, "gyro_bias_random_walk", &i.gyro_bias_random_walk);
    ReadOptional(*imu, "accel_bias_initial", &i.accel_bias_initial);
    ReadOptional(*imu, "gyro_bias_initial", &i.gyro_bias_initial);
    imu->RejectUnknownKeys();
  }
  if (const auto esc = node.Optional("esc")) {
    sim::EscOptions& e = o->esc;
    ReadOptional(*esc, "rate_hz", &e.rate_hz);
    ReadOptional(*esc, "noise_rpm", &e.noise_rpm);
    ReadOptional(*esc, "quantization_rpm", &e.quantization_rpm);
    ReadOptional(*esc, "delay_s", &e.delay_s);
    esc->RejectUnknownKeys();
  }
  if (const auto odom = node.Optional("odometry")) {
    sim::OdometryOptions& d = o->odometry;
    ReadOptional(*odom, "rate_hz", &d.rate_hz);
    ReadOptional(*odom, "position_noise_m", &d.position_noise_m);
    ReadOptional(*odom, "velocity_noise_m_s", &d.velocity_noise_m_s);
    ReadOptional(*odom, "attitude_noise_rad", &d.attitude_noise_rad);
    ReadOptional(*odom, "rate_noise_gain", &d.rate_noise_gain);
    if (const auto outages = odom->Optional("outages")) {
      for (std::size_t i = 0; i < outages->size(); ++i) {
        const ConfigNode entry = outages->At(i);
        sim::OdometryOptions::Outage outage;
        outage.start_s = entry.Required("start_s").AsNonNegative();
        outage.duration_s = entry.Required("duration_s").AsNonNegative();
        entry.RejectUnknownKeys();
        d.outages.push_back(outage);
      }
    }
    odom->RejectUnknownKeys();
  }
  if (const auto lidar = node.Optional("lidar")) {
    sim::LidarOptions& l = o->lidar;
    l.enabled = true;  // a lidar block switches the sensor on unless it says otherwise
    if (const auto e = lidar->Optional("enabled")) l.enabled = e->AsBool();
    ReadOptional(*lidar, "frame_rate_hz", &l.frame_rate_hz);
    ReadOptional(*lidar, "points_per_s", &l.points_per_s);
    ReadOptional(*lidar, "min_range_m", &l.min_range_m);
    ReadOptional(*lidar, "max_range_m", &l.max_range_m);
    ReadOptional(*lidar, "min_elevation_rad", &l.min_elevation_rad);
    ReadOptional(*lidar, "max_elevation_rad", &l.max_elevation_rad);
    ReadOptional(*lidar, "range_noise_m", &l.range_noise_m);
    ReadOptional(*lidar, "dropout_probability", &l.dropout_probability);
    ReadOptional(*lidar, "position_m", &l.position_m);
    ReadOptional(*lidar, "grid_cell_m", &l.grid_cell_m);
    lidar->RejectUnknownKeys();
  }
  node.RejectUnknownKeys();
}

/// The outer-loop gains shared by the cascaded controllers' blocks (stack.nominal, stack.passive).
void ParsePositionLoop(const ConfigNode& n, control::PositionLoopOptions* p) {
  ReadOptional(n, "kp_position", &p->kp_position);
  ReadOptional(n, "kd_velocity", &p->kd_velocity);
  ReadOptional(n, "ki_position", &p->ki_position);
  ReadOptional(n, "integral_limit_m_s2", &p->integral_limit_m_s2);
  ReadOptional(n, "max_tilt_rad", &p->max_tilt_rad);
}

void ParseStack(const ConfigNode& node, stack::FlightStackOptions* o, modular::AllocatorOptions* allocation) {
  if (const auto c = node.Optional("controller")) {
    o->controller = c->AsEnum({"nominal", "nmpc", "passive", "indi", "lqr", "assembly"});
  }
  if (const auto n = node.Optional("assembly")) {
    if (const auto r = n->Optional("reallocation")) {
      allocation->method = *modular::ParseReallocation(r->AsEnum({"none", "partial", "full"}));
    }
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { allocation->Validate(); });
  }
  ReadOptional(node, "control_rate_hz", &o->control_rate_hz);
  if (const auto n = node.Optional("nominal")) {
    control::NominalControllerOptions& g = o->nominal;
    ParsePositionLoop(*n, &g.position);
    ReadOptional(*n, "k_attitude", &g.k_attitude);
    ReadOptional(*n, "k_rate", &g.k_rate);
    ReadOptional(*n, "max_rate_rad_s", &g.max_rate_rad_s);
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { g.Validate(); });
  }
  if (const auto n = node.Optional("passive")) {
    control::PassiveControllerOptions& g = o->passive;
    ParsePositionLoop(*n, &g.position);
    ReadOptional(*n, "k_tilt", &g.k_tilt);
    ReadOptional(*n, "k_rate", &g.k_rate);
    ReadOptional(*n, "regularisation", &g.regularisation);
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { g.Validate(); });
  }
  if (const auto n = node.Optional("indi")) {
    control::IndiControllerOptions& g = o->indi;
    ParsePositionLoop(*n, &g.position);
    ReadOptional(*n, "k_h", &g.k_h);
    ReadOptional(*n, "d_h", &g.d_h);
    ReadOptional(*n, "opposite_ratio", &g.opposite_ratio);
    ReadOptional(*n, "filter_cutoff_hz", &g.filter_cutoff_hz);
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { stack::IndiOptionsInStack(*o).Validate(); });
  }
  if (const auto n = node.Optional("nmpc")) {
    control::NmpcOptions& m = o->nmpc;
    if (const auto v = n->Optional("horizon_steps")) m.horizon_steps = static_cast<int>(v->AsIntIn(1, 200));
    ReadOptional(*n, "step_s", &m.step_s);
    if (const auto v = n->Optional("integrator_substeps")) m.integrator_substeps = static_cast<int>(v->AsIntIn(1, 20));
    ReadOptional(*n, "q_position", &m.q_position);
    if (const auto v = n->Optional("q_attitude")) {
      const std::vector<double> qa = v->AsDoubleList(4);
      m.q_attitude = Eigen::Vector4d(qa[0], qa[1], qa[2], qa[3]);
    }
    ReadOptional(*n, "q_velocity", &m.q_velocity);
    ReadOptional(*n, "q_rate", &m.q_rate);
    ReadOptional(*n, "q_thrust", &m.q_thrust);
    ReadOptional(*n, "r_input", &m.r_input);
    ReadOptional(*n, "max_rate_rad_s", &m.max_rate_rad_s);
    if (const auto v = n->Optional("max_sqp_iterations")) m.max_sqp_iterations = static_cast<int>(v->AsIntIn(1, 1000));
    if (const auto v = n->Optional("relinearise_every")) m.relinearise_every = static_cast<int>(v->AsIntIn(1, 20));
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { m.Validate(); });
  }
  if (const auto f = node.Optional("fdd")) o->fdd = f->AsEnum({"none", "composite", "fixedtime", "ukf"});
  if (const auto c = node.Optional("composite_fdd")) {
    fdd::CompositeFddOptions& d = o->composite_fdd;
    ReadOptional(*c, "motor_index_threshold", &d.motor_index_threshold);
    if (const auto v = c->Optional("motor_index_samples")) d.motor_index_samples = static_cast<int>(v->AsIntIn(1, 1000));
    ReadOptional(*c, "motor_index_min_thrust_n", &d.motor_index_min_thrust_n);
    ReadOptional(*c, "propeller_index_threshold", &d.propeller_index_threshold);
    ReadOptional(*c, "propeller_persistence_s", &d.propeller_persistence_s);
    ReadOptional(*c, "degraded_threshold", &d.degraded_threshold);
    ReadOptional(*c, "degraded_persistence_s", &d.degraded_persistence_s);
    ReadOptional(*c, "filter_cutoff_hz", &d.filter_cutoff_hz);
    ReadOptional(*c, "takeoff_max_altitude_m", &d.takeoff_max_altitude_m);
    ReadOptional(*c, "takeoff_window_s", &d.takeoff_window_s);
    ReadOptional(*c, "takeoff_angular_acceleration_rad_s2", &d.takeoff_angular_acceleration_rad_s2);
    ReadOptional(*c, "takeoff_direction_cosine", &d.takeoff_direction_cosine);
    c->RejectUnknownKeys();
  }
  if (const auto d = node.Optional("deskew_frames")) o->lidar.deskew_frames = d->AsBool();
  if (const auto sup = node.Optional("supervisor")) {
    // The supervisor's thresholds (docs/navigation.md): recovery, no-plan timeout, estimator
    // checks, the emergency landing's descent and touchdown.
    stack::SupervisorOptions& v = o->supervisor;
    ReadOptional(*sup, "recovery_tilt_rad", &v.recovery_tilt_rad);
    ReadOptional(*sup, "recovery_hold_s", &v.recovery_hold_s);
    ReadOptional(*sup, "no_plan_timeout_s", &v.no_plan_timeout_s);
    ReadOptional(*sup, "odometry_timeout_s", &v.odometry_timeout_s);
    ReadOptional(*sup, "max_speed_m_s", &v.max_speed_m_s);
    ReadOptional(*sup, "landing_speed_m_s", &v.landing_speed_m_s);
    ReadOptional(*sup, "landing_depth_m", &v.landing_depth_m);
    ReadOptional(*sup, "touchdown_thrust_ratio", &v.touchdown_thrust_ratio);
    ReadOptional(*sup, "touchdown_hold_s", &v.touchdown_hold_s);
    if (const auto m = sup->Optional("max_failed_rotors")) v.max_failed_rotors = static_cast<int>(m->AsIntIn(0, kMaxRotors));
    sup->RejectUnknownKeys();
    ValidateAt(*sup, [&] { v.Validate(); });
  }
  if (const auto n = node.Optional("planner"); n && !n->IsMap()) {
    o->navigation.method = n->AsEnum({"minco", "flatness"});  // `planner: flatness`, the defaults
  } else if (n) {
    // The navigate mission's planner (docs/planning.md): rate, nominal limits, eq. (33)'s safety
    // factor, eq. (22)'s weights, clearance, replanning period and altitude band.
    stack::NavigationOptions& nav = o->navigation;
    planning::ReplannerOptions& r = nav.replanner;
    if (const auto m = n->Optional("method")) nav.method = m->AsEnum({"minco", "flatness"});
    ReadOptional(*n, "start_s", &nav.start_s);
    ReadOptional(*n, "rate_hz", &nav.planner_rate_hz);
    ReadOptional(*n, "v_max", &r.nominal.v_max);
    ReadOptional(*n, "a_max", &r.nominal.a_max);
    ReadOptional(*n, "j_max", &r.nominal.j_max);
    ReadOptional(*n, "post_failure_safety_factor", &nav.post_failure_safety_factor);
    ReadOptional(*n, "replan_period_s", &r.replan_period_s);
    ReadOptional(*n, "clearance_m", &r.planner.optimizer.clearance_m);
    if (const auto c = n->Optional("post_failure_clearance_m")) r.post_failure_clearance_m = c->AsNonNegative();
    // A guide sample looks for its obstacle plane at least as far as the clearance it keeps.
    r.planner.plane_search_m =
        std::max({r.planner.plane_search_m, r.planner.optimizer.clearance_m, r.post_failure_clearance_m.value_or(0.0)});
    if (const auto aware = n->Optional("failure_aware")) nav.failure_aware = aware->AsBool();
    if (const auto band = n->Optional("altitude_band_m")) {
      const std::vector<double> b = band->AsDoubleList(2);
      r.planner.search.z_min_m = b[0];
      r.planner.search.z_max_m = b[1];
    }
    if (const auto w = n->Optional("weights")) {
      ReadOptional(*w, "time", &r.planner.optimizer.weight_time);
      ReadOptional(*w, "smoothness", &r.planner.optimizer.weight_smoothness);
      ReadOptional(*w, "feasibility", &r.planner.optimizer.weight_feasibility);
      ReadOptional(*w, "collision", &r.planner.optimizer.weight_collision);
      w->RejectUnknownKeys();
    }
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { nav.Validate(); });
  }
  if (const auto n = node.Optional("flatness")) {
    // Paper 004's planner (docs/flatness.md): envelope and actuator limits, the hold after a
    // detection and the time budget of the re-planned leg.
    planning::FlatnessNavigatorOptions& f = o->navigation.flatness;
    constexpr double kDeg = 3.14159265358979323846 / 180.0;
    for (const auto& [key, angle] : {std::pair{"theta_max_deg", &f.limits.theta_max_rad}, std::pair{"phi_max_deg", &f.limits.phi_max_rad}}) {
      if (const auto v = n->Optional(key)) {
        const double deg = v->AsDouble();
        if (!(deg > 0.0 && deg < 90.0)) v->Fail(fmt::format("{} = {:g} is invalid; expected an angle in (0, 90) deg", key, deg));
        *angle = deg * kDeg;
      }
    }
    ReadOptional(*n, "rho_angle", &f.limits.rho_angle);
    ReadOptional(*n, "u_max", &f.limits.u_max);
    ReadOptional(*n, "rho_u", &f.limits.rho_u);
    ReadOptional(*n, "hold_t_s", &f.hold_t_s);
    ReadOptional(*n, "min_hold_s", &f.min_hold_s);
    ReadOptional(*n, "max_hold_s", &f.max_hold_s);
    ReadOptional(*n, "time_budget_s", &f.time_budget_s);
    ReadOptional(*n, "min_t_s", &f.min_t_s);
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { f.Validate(); });
  }
  if (const auto n = node.Optional("map")) {
    // The inflation radius is the vehicle's collision radius plus inflation_margin_m and the
    // deskew lever arm the LiDAR's mounting point (FitStackToHardware): neither is a key here.
    perception::VoxelMapOptions& m = o->lidar.map;
    ReadOptional(*n, "inflation_margin_m", &o->lidar.inflation_margin_m);
    ReadOptional(*n, "resolution_m", &m.resolution_m);
    ReadOptional(*n, "window_size_m", &m.window_size_m);
    ReadOptional(*n, "log_odds_hit", &m.log_odds_hit);
    ReadOptional(*n, "log_odds_miss", &m.log_odds_miss);
    ReadOptional(*n, "log_odds_min", &m.log_odds_min);
    ReadOptional(*n, "log_odds_max", &m.log_odds_max);
    ReadOptional(*n, "occupied_threshold", &m.occupied_threshold);
    ReadOptional(*n, "max_clearing_range_m", &m.max_clearing_range_m);
    if (const auto v = n->Optional("clearing_stride")) {
      m.clearing_stride = static_cast<int>(v->AsIntIn(1, perception::VoxelMapOptions::kMaxClearingStride));
    }
    ReadOptional(*n, "recenter_hysteresis_m", &m.recenter_hysteresis_m);
    n->RejectUnknownKeys();
    ValidateAt(*n, [&] { o->lidar.Validate(); });
  }
  if (const auto kf = node.Optional("known_faults")) {
    if (!kf->IsSequence()) kf->Fail("expected a list of {rotor, at_time_s, loss}");
    for (std::size_t i = 0; i < kf->size(); ++i) {
      const ConfigNode f = kf->At(i);
      stack::KnownFault k;
      k.rotor = static_cast<int>(f.Required("rotor").AsIntIn(0, kMaxRotors - 1));
      k.at_time_s = f.Required("at_time_s").AsNonNegative();
      k.loss = OptionalDouble(f, "loss", 1.0);
      f.RejectUnknownKeys();
      o->known_faults.push_back(k);
    }
  }
  node.RejectUnknownKeys();
  ValidateAt(node, [&] { o->Validate(); });
}

/// Fault rules that need the rest of the scenario: a take-off onset needs a start on the ground,
/// and intermittent periods must be resolvable by the physics step.
void CheckFaultsAgainstScenario(const ConfigNode& root, const Scenario& s) {
  const double dt = 1.0 / s.sim.physics_rate_hz;
  for (std::size_t i = 0; i < s.faults.size(); ++i) {
    const sim::FaultSpec& f = s.faults[i];
    if (f.onset.kind == sim::FaultOnset::Kind::kDuringTakeoff && s.initial_position_m.z() > 0.0) {
      root.FailAt(fmt::format("faults.{}.onset.during_takeoff_s", i),
                  fmt::format("a take-off onset needs a start on the ground; initial.position_m has z = {:g} m",
                              s.initial_position_m.z()));
    }
    if (f.intermittent && std::min(f.intermittent->on_s, f.intermittent->off_s) < dt) {
      root.FailAt(fmt::format("faults.{}.intermittent", i),
                  fmt::format("intermittent periods must be at least one physics step ({:g} s)", dt));
    }
  }
}

/// The tracking window must hold at least one physics step's sample. The error names the key that
/// closes it: tracking_end_s when set, else tracking_start_s against what ends the window.
void CheckTrackingWindow(const ConfigNode& metrics, const Scenario& s) {
  const double dt = 1.0 / s.sim.physics_rate_hz, end = TrackingEndS(s);
  if (end - s.tracking_start_s >= dt * (1.0 - 1e-9)) return;
  if (s.tracking_end_s) {
    metrics.Required("tracking_end_s")
        .Fail(fmt::format("tracking_end_s = {:g} is invalid; expected at least one physics step ({:g} s) after "
                          "metrics.tracking_start_s = {:g}",
                          end, dt, s.tracking_start_s));
  }
  const bool plan_ends = end < s.duration_s;  // without tracking_end_s only a plan ends it early (TrackingEndS)
  metrics.Required("tracking_start_s")
      .Fail(fmt::format("tracking_start_s = {:g} is invalid; expected at least one physics step ({:g} s) before the "
                        "tracking window's end, {:.3f} s ({})",
                        s.tracking_start_s, dt, end,
                        plan_ends ? "the plan's duration, which ends the window of mission assembly_plan; or set "
                                    "metrics.tracking_end_s"
                                  : "duration_s"));
}

/// The mission must keep the reference above the ground (z >= 0) over the flight: a reference
/// below ground cannot be flown and is a configuration mistake.
void CheckReferenceAboveGround(const ConfigNode& mission, const Scenario& s) {
  // References are smooth on this scale; long runs are sampled more coarsely (at most 1e5 points).
  const double end = std::min(s.duration_s, s.reference->duration());
  const double step = std::max(0.01, end / 1e5);
  const auto samples = static_cast<long>(std::ceil(end / step));
  for (long k = 0; k <= samples; ++k) {
    const double t = std::min(static_cast<double>(k) * step, end);
    const double z = s.reference->Evaluate(t).p_W.z();
    if (z < -1e-9) {
      mission.Fail(fmt::format("the {} reference goes below the ground (z = {:.3f} m at t = {:.2f} s); raise "
                               "its centre or the initial position",
                               s.mission_type, z, t));
    }
  }
}

std::string ResolveRelative(const std::string& base_file, const std::string& path) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (p.is_absolute() || base_file.empty()) return p.lexically_normal().string();
  return (fs::path(base_file).parent_path() / p).lexically_normal().string();
}

vehicle::VehicleParams LoadVehicleDocument(ConfigDocument doc, const std::vector<Override>& overrides) {
  ApplyOverrides(&doc, overrides, /*vehicle_part=*/true);
  return ParseVehicle(doc.root());
}

}  // namespace

vehicle::VehicleParams LoadVehicle(const std::string& path, const std::vector<Override>& overrides) {
  return LoadVehicleDocument(ConfigDocument::LoadFile(path), overrides);
}

modular::AssemblyControllerOptions AssemblyControllerOptionsOf(const Scenario& scenario) {
  modular::AssemblyControllerOptions o;
  o.cascade = scenario.stack.nominal;
  o.allocation = scenario.allocation;
  return o;
}

modular::Assembly LoadAssembly(const std::string& path) {
  const ConfigDocument doc = ConfigDocument::LoadFile(path);
  const ConfigNode root = doc.root();
  modular::AssemblySpec spec;
  spec.name = root.Has("name") ? root.Required("name").AsString() : std::filesystem::path(path).stem().string();
  const ConfigNode unit = root.Required("unit");
  const std::string unit_file = ResolveRelative(path, unit.AsString());
  try {
    spec.unit = LoadVehicle(unit_file);
  } catch (const io::InputFileError& e) {
    throw io::InputFileError(e.path(), fmt::format("{} (named by 'unit' at {})", e.reason(), unit.Location()));
  }
  spec.spacing_m = root.Required("spacing_m").AsPositive();
  if (root.Has("shape") == root.Has("slots")) root.Fail("expected exactly one of 'shape' and 'slots'");
  if (const auto shape = root.Optional("shape")) {
    spec.slots = modular::ShapeSlots(shape->AsEnum({"3x1", "4x1", "3x2", "3x3", "3x3_plus"}));
  } else {
    const ConfigNode slots = root.Required("slots");
    if (!slots.IsSequence()) slots.Fail("expected a list of grid cells [i, j]");
    for (std::size_t k = 0; k < slots.size(); ++k) {
      const ConfigNode cell = slots.At(k);
      if (!cell.IsSequence() || cell.size() != 2) cell.Fail("expected a grid cell [i, j] of two integers");
      spec.slots.emplace_back(static_cast<int>(cell.At(0).AsIntIn(-64, 64)), static_cast<int>(cell.At(1).AsIntIn(-64, 64)));
    }
  }
  root.RejectUnknownKeys();
  modular::Assembly assembly;
  ValidateAt(root, [&] { assembly = modular::BuildAssembly(spec); });
  return assembly;
}

Scenario LoadScenario(const std::string& path, const std::vector<Override>& overrides) {
  ConfigDocument doc = ConfigDocument::LoadFile(path);
  ApplyOverrides(&doc, overrides, /*vehicle_part=*/false);
  const ConfigNode root = doc.root();
  Scenario s;
  s.file = path;
  s.name = root.Has("name") ? root.Required("name").AsString()
                            : std::filesystem::path(path).stem().string();
  if (root.Has("description")) root.Required("description").AsString();
  if (root.Has("assembly") == root.Has("vehicle")) {
    root.Fail("expected exactly one of 'vehicle' (a vehicle file) and 'assembly' (an assembly file)");
  }
  const char* vehicle_key = root.Has("assembly") ? "assembly" : "vehicle";
  const ConfigNode vehicle_node = root.Required(vehicle_key);
  s.vehicle_file = ResolveRelative(path, vehicle_node.AsString());
  try {
    if (root.Has("assembly")) {
      auto assembly = std::make_shared<modular::Assembly>(LoadAssembly(s.vehicle_file));
      s.vehicle = assembly->vehicle;
      s.assembly = std::move(assembly);
    } else {
      s.vehicle = LoadVehicle(s.vehicle_file, overrides);
    }
  } catch (const io::InputFileError& e) {
    // Still an unreadable input (exit 3), with the scenario line that names it.
    throw io::InputFileError(e.path(), fmt::format("{} (named by '{}' at {})", e.reason(), vehicle_key,
                                                   vehicle_node.Location()));
  }
  s.duration_s = root.Required("duration_s").AsDoubleIn(1e-3, 1e6);
  if (const auto seed = root.Optional("seed")) s.seed = seed->AsUint64();

  if (const auto initial = root.Optional("initial")) {
    ReadOptional(*initial, "position_m", &s.initial_position_m);
    s.initial_yaw_rad = OptionalDouble(*initial, "yaw_rad", 0.0);
    if (s.initial_position_m.z() < 0.0) initial->FailAt("position_m", "the start must be at or above the ground (z >= 0)");
    initial->RejectUnknownKeys();
  }
  if (const auto world = root.Optional("world")) s.world = ParseWorld(*world);

  // Simulation settings first: sensor rates are checked against the physics rate.
  if (const auto simn = root.Optional("sim")) {
    ReadOptional(*simn, "physics_rate_hz", &s.sim.physics_rate_hz);
    ReadOptional(*simn, "log_rate_hz", &s.log_rate_hz);
    ReadOptional(*simn, "crash_speed_m_s", &s.sim.crash_speed_m_s);
    ReadOptional(*simn, "crash_tilt_rad", &s.sim.crash_tilt_rad);
    simn->RejectUnknownKeys();
    if (s.log_rate_hz <= 0.0 || s.log_rate_hz > s.sim.physics_rate_hz) {
      simn->FailAt("log_rate_hz", fmt::format("log_rate_hz = {} is invalid; expected a rate in (0, {}] Hz "
                                              "(the physics rate)", s.log_rate_hz, s.sim.physics_rate_hz));
    }
  }
  if (const auto sensors = root.Optional("sensors")) ParseSensors(*sensors, &s.sim);
  if (const auto wind = root.Optional("wind")) {
    ReadOptional(*wind, "mean_m_s", &s.sim.wind.mean_m_s);
    ReadOptional(*wind, "gust_std_m_s", &s.sim.wind.gust_std_m_s);
    ReadOptional(*wind, "gust_time_constant_s", &s.sim.wind.gust_time_constant_s);
    wind->RejectUnknownKeys();
  }
  // Field names are scenario key paths ("sensors.esc.rate_hz"): defaults that clash are reported
  // at the key they would have, or its nearest existing parent.
  ValidateAt(root, [&] { s.sim.Validate(s.vehicle); });

  s.reference = ParseMission(root.Required("mission"), &s, &s.mission_type);

  if (const auto faults = root.Optional("faults")) {
    if (!faults->IsSequence() && !faults->IsNull()) faults->Fail("expected a list of faults");
    for (std::size_t i = 0; faults->IsSequence() && i < faults->size(); ++i) {
      s.faults.push_back(ParseFault(faults->At(i)));
    }
    // Rules that need the vehicle and the duration (rotor index, onset time).
    ValidateAt(root, [&] {
      for (std::size_t i = 0; i < s.faults.size(); ++i) {
        s.faults[i].Validate(static_cast<int>(i), s.vehicle.num_rotors(), s.duration_s);
      }
    });
  }
  CheckFaultsAgainstScenario(root, s);
  FitStackToHardware(&s);  // the stack's validation below sees the sensors' rates ...
  // An assembly reallocates over its rotors: it flies on while four remain (stack.supervisor keys
  // below may lower it).
  if (s.assembly) s.stack.supervisor.max_failed_rotors = s.assembly->FailedRotorAllowance();
  if (const auto st = root.Optional("stack")) ParseStack(*st, &s.stack, &s.allocation);
  FitStackToHardware(&s);  // ... and what the hardware implies follows the stack's keys (inflation margin)
  for (std::size_t i = 0; i < s.stack.known_faults.size(); ++i) {
    if (s.stack.known_faults[i].rotor >= s.vehicle.num_rotors()) {
      root.FailAt(fmt::format("stack.known_faults.{}.rotor", i),
                  fmt::format("rotor {} does not exist; expected an index in [0, {}]", s.stack.known_faults[i].rotor,
                              s.vehicle.num_rotors() - 1));
    }
  }
  if (s.stack.controller == "assembly" && !s.assembly) {
    root.FailAt("stack.controller", "controller assembly flies an assembly; expected the key 'assembly' in place of 'vehicle'");
  }
  if (s.stack.control_rate_hz > s.sim.physics_rate_hz) {
    root.FailAt("stack.control_rate_hz",
                fmt::format("stack.control_rate_hz = {:g} is invalid; expected at most the physics rate "
                            "sim.physics_rate_hz = {:g} Hz",
                            s.stack.control_rate_hz, s.sim.physics_rate_hz));
  }
  const std::optional<ConfigNode> metrics = root.Optional("metrics");
  if (metrics) {
    if (const auto t = metrics->Optional("tracking_start_s")) s.tracking_start_s = t->AsDoubleIn(0.0, s.duration_s);
    if (const auto t = metrics->Optional("tracking_end_s")) s.tracking_end_s = t->AsDoubleIn(0.0, s.duration_s);
    if (const auto e = metrics->Optional("success_error_m")) s.success_error_m = e->AsPositive();
    if (const auto h = metrics->Optional("success_hold_s")) s.success_hold_s = h->AsDoubleIn(0.0, s.duration_s);
    if (const auto r = metrics->Optional("recovered_tilt_rad")) s.recovered_tilt_rad = r->AsDoubleIn(1e-3, 1.5);
    metrics->RejectUnknownKeys();
  }
  root.RejectUnknownKeys();
  if (s.mission_type == "navigate" && s.stack.navigation.method == "minco" && !s.sim.lidar.enabled) {
    root.Required("mission").Fail("the navigate mission plans on the LiDAR map; expected sensors.lidar");
  }
  if (s.stack.navigation.method == "flatness" || s.stack.controller == "lqr") {
    // Paper 004's planner and controller work on the vehicle's PWM model: its layout is checked now.
    ValidateAt(root.Required(vehicle_key), [&] { vehicle::PwmQuadModel::FromVehicle(s.vehicle); });
  }
  if (s.assembly_plan) {
    const AssemblyPlanResult plan = PlanAssemblyMission(s);
    if (!plan.ok) root.Required("mission").Fail("cannot plan the assembly's path: " + plan.message);
    s.reference = plan.trajectory;
  }
  if (metrics) CheckTrackingWindow(*metrics, s);  // after planning: a plan ends the window
  CheckReferenceAboveGround(root.Required("mission"), s);
  return s;
}

double TrackingEndS(const Scenario& s) {
  if (s.tracking_end_s) return *s.tracking_end_s;
  if (s.assembly_plan && s.reference) return std::min(s.reference->duration(), s.duration_s);
  return s.duration_s;
}

}  // namespace rotorguard::harness

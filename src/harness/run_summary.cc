#include "rotorguard/harness/run_summary.h"

namespace rotorguard::harness {

nlohmann::json RunCost::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  for (const Part& p : kParts) j[p.name] = this->*p.field;
  return j;
}

nlohmann::json RunSummary::ToJson() const {
  nlohmann::json j;
  j["scenario"] = scenario;
  j["seed"] = seed;
  j["success"] = success;
  j["crashed"] = crashed;
  j["crash_reason"] = crashed ? nlohmann::json(crash_reason) : nlohmann::json(nullptr);
  j["failure_reason"] = success ? nlohmann::json(nullptr) : nlohmann::json(failure_reason);
  j["sim_time_s"] = sim_time_s;
  j["wall_time_s"] = wall_time_s;
  j["realtime_factor"] = realtime_factor;
  j["stack_realtime_factor"] = stack_realtime_factor;
  j["tracking_rmse_m"] = tracking_rmse_m;
  j["tracking_rmse_window_m"] = tracking_rmse_window_m;
  j["tracking_window_s"] = {tracking_start_s, tracking_end_s};
  j["tracking_rmse_eq37_m"] = tracking_rmse_eq37_m;
  j["max_position_error_m"] = max_position_error_m;
  j["min_altitude_m"] = min_altitude_m;
  j["max_spin_rad_s"] = max_spin_rad_s;
  j["max_tilt_rad"] = max_tilt_rad;
  j["tilt_recovery_s"] = tilt_recovery_s >= 0.0 ? nlohmann::json(tilt_recovery_s) : nlohmann::json(nullptr);
  j["faults"] = nlohmann::json::array();
  for (const FaultRecord& f : faults) {
    j["faults"].push_back({{"rotor", f.rotor}, {"kind", f.kind}, {"onset_s", f.onset_s}});
  }
  if (fdd) {
    j["fdd"] = {{"detected", fdd->detected},
                {"rotor", fdd->detected ? nlohmann::json(fdd->rotor) : nlohmann::json(nullptr)},
                {"kind", fdd->detected ? nlohmann::json(fdd->kind) : nlohmann::json(nullptr)},
                {"detector", fdd->detected ? nlohmann::json(fdd->detector) : nlohmann::json(nullptr)},
                {"detection_s", fdd->detected ? nlohmann::json(fdd->detection_s) : nlohmann::json(nullptr)},
                {"correct", fdd->correct},
                {"false_alarm", fdd->false_alarm},
                {"latency_s", fdd->correct ? nlohmann::json(fdd->latency_s) : nlohmann::json(nullptr)}};
  } else {
    j["fdd"] = nullptr;  // the stack ran no fault detection
  }
  j["composite_fdd"] = composite_fdd ? CompositeFddOptionsToJson(*composite_fdd) : nlohmann::json(nullptr);
  j["sensors"] = {{"imu_rate_hz", imu_rate_hz},
                  {"imu_position_m", {imu_position_m.x(), imu_position_m.y(), imu_position_m.z()}}};
  j["map_voxels_occupied"] = map_voxels_occupied >= 0 ? nlohmann::json(map_voxels_occupied) : nlohmann::json(nullptr);
  if (waypoints_total >= 0) {
    j["navigation"] = {{"waypoints_reached", waypoints_reached},
                       {"waypoints_total", waypoints_total},
                       {"plans", plans},
                       {"plans_failed", plans_failed},
                       {"plans_fine_search", plans_fine_search},
                       {"plans_rest_to_rest", plans_rest_to_rest},
                       {"plans_by_reason", plans_by_reason},
                       {"mission_time_s", mission_time_s >= 0.0 ? nlohmann::json(mission_time_s) : nlohmann::json(nullptr)},
                       {"planner_ms_mean", planner_ms_mean},
                       {"failed_plans", failed_plans},
                       {"infeasible_request", infeasible_request}};
  }
  if (!flatness_decisions.empty()) j["flatness"] = {{"decisions", flatness_decisions}};
  if (!ukf_w_hat.empty()) {
    j["ukf"] = {{"w_hat", ukf_w_hat}, {"settled_s", ukf_settled_s >= 0.0 ? nlohmann::json(ukf_settled_s) : nlohmann::json(nullptr)}};
  }
  j["lidar_points_dropped"] = lidar_points_dropped;
  j["supervisor"] = {{"final_mode", final_mode}, {"transitions", nlohmann::json::array()}};
  for (const ModeRecord& m : mode_transitions) {
    j["supervisor"]["transitions"].push_back({{"t", m.t}, {"from", m.from}, {"to", m.to}, {"reason", m.reason}});
  }
  j["stack_ms_per_cycle_mean"] = stack_ms_per_cycle_mean;
  j["cost_ms_per_sim_s"] = cost_ms_per_sim_s.ToJson();
  j["physics_steps"] = physics_steps;
  j["control_cycles"] = control_cycles;
  return j;
}

nlohmann::json CompositeFddOptionsToJson(const fdd::CompositeFddOptions& o) {
  return {{"motor_index_threshold", o.motor_index_threshold},
          {"motor_index_samples", o.motor_index_samples},
          {"motor_index_min_thrust_n", o.motor_index_min_thrust_n},
          {"propeller_index_threshold", o.propeller_index_threshold},
          {"propeller_persistence_s", o.propeller_persistence_s},
          {"degraded_threshold", o.degraded_threshold},
          {"degraded_persistence_s", o.degraded_persistence_s},
          {"filter_cutoff_hz", o.filter_cutoff_hz},
          {"takeoff_max_altitude_m", o.takeoff_max_altitude_m},
          {"takeoff_window_s", o.takeoff_window_s},
          {"takeoff_angular_acceleration_rad_s2", o.takeoff_angular_acceleration_rad_s2},
          {"takeoff_direction_cosine", o.takeoff_direction_cosine}};
}

fdd::CompositeFddOptions CompositeFddOptionsFromJson(const nlohmann::json& j) {
  fdd::CompositeFddOptions o;
  o.motor_index_threshold = j.at("motor_index_threshold").get<double>();
  o.motor_index_samples = j.at("motor_index_samples").get<int>();
  o.motor_index_min_thrust_n = j.at("motor_index_min_thrust_n").get<double>();
  o.propeller_index_threshold = j.at("propeller_index_threshold").get<double>();
  o.propeller_persistence_s = j.at("propeller_persistence_s").get<double>();
  o.degraded_threshold = j.at("degraded_threshold").get<double>();
  o.degraded_persistence_s = j.at("degraded_persistence_s").get<double>();
  o.filter_cutoff_hz = j.at("filter_cutoff_hz").get<double>();
  o.takeoff_max_altitude_m = j.at("takeoff_max_altitude_m").get<double>();
  o.takeoff_window_s = j.at("takeoff_window_s").get<double>();
  o.takeoff_angular_acceleration_rad_s2 = j.at("takeoff_angular_acceleration_rad_s2").get<double>();
  o.takeoff_direction_cosine = j.at("takeoff_direction_cosine").get<double>();
  return o;
}

}  // namespace rotorguard::harness

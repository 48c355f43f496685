#include "rotorguard/harness/run_summary.h"

#include "rotorguard/io/json_archive.h"

namespace rotorguard::harness {

nlohmann::json RunCost::ToJson() const {
  nlohmann::json j = nlohmann::json::object();
  for (const Part& p : kParts) j[p.name] = this->*p.field;
  return j;
}

namespace {

/// The value, or null.
template <typename T>
nlohmann::json OrNull(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}

nlohmann::json Vec(const Vector3& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json ExtremesJson(const fdd::IndexExtremes& e) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [name, member] : fdd::kIndexExtremesFields) j[std::string(name)] = e.*member;
  return j;
}

/// A diagnosis's rotor, kind, detector, detection_s and eta; nulls without one.
nlohmann::json DiagnosisJson(const std::optional<FddRecord::Diagnosis>& d) {
  if (!d)
    return {{"rotor", nullptr}, {"kind", nullptr}, {"detector", nullptr}, {"detection_s", nullptr}, {"eta", nullptr}};
  return {{"rotor", d->rotor},
          {"kind", d->kind},
          {"detector", d->detector},
          {"detection_s", d->detection_s},
          {"eta", d->eta}};
}

nlohmann::json SecondJson(const FddRecord::Second& s) {
  nlohmann::json j = DiagnosisJson(s.diagnosis);
  if (!s.isolated) j["detection_s"] = nullptr;
  j["isolated"] = s.isolated;
  j["correct"] = s.correct;
  j["latency_s"] = OrNull(s.latency_s);
  return j;
}

nlohmann::json FddJson(const FddRecord& f) {
  nlohmann::json j = DiagnosisJson(f.diagnosis);
  j["detected"] = f.detected();
  j["correct"] = f.correct;
  j["false_alarm"] = f.false_alarm;
  j["latency_s"] = OrNull(f.latency_s);
  j["reconfiguration_latency_s"] = OrNull(f.reconfiguration_latency_s);
  j["healthy_extremes"] = f.healthy_extremes ? ExtremesJson(*f.healthy_extremes) : nlohmann::json(nullptr);
  j["second"] = f.second ? SecondJson(*f.second) : nlohmann::json(nullptr);
  j["healthy_rotors_isolated"] = f.healthy_rotors_isolated;
  return j;
}

nlohmann::json NavigationJson(const stack::NavigationSummary& n, const std::optional<double>& mission_time_s,
                              bool infeasible_request) {
  return {{"waypoints_reached", n.waypoints_reached},
          {"waypoints_total", n.waypoints_total},
          {"plans", n.plans},
          {"plans_failed", n.plans_failed},
          {"plans_fine_search", n.plans_fine_search},
          {"plans_rest_to_rest", n.plans_rest_to_rest},
          {"plans_by_reason", n.plans_by_reason},
          {"mission_time_s", OrNull(mission_time_s)},
          {"planner_ms_mean", n.planner_ms_mean},
          {"failed_plans", n.failed_plans},
          {"infeasible_request", infeasible_request}};
}

nlohmann::json FlatnessDecisionJson(const planning::FlatnessDecision& d) {
  return {{"t", d.t},
          {"kind", d.kind},
          {"t_s", d.t_s},
          {"binding", d.binding},
          {"w_hat", {d.w_hat[0], d.w_hat[1], d.w_hat[2], d.w_hat[3]}},
          {"reason", d.reason},
          {"delta_m", Vec(d.delta_m)},
          {"envelope_s", d.envelope_s},
          {"actuator_s", d.actuator_s}};
}

/// The stack's account (RunSummary::stack) at summary.json's top level.
void AddStackJson(const RunSummary& r, nlohmann::json* j) {
  const stack::FlightStackSummary& s = r.stack;
  (*j)["map_voxels_occupied"] = OrNull(s.map_voxels_occupied);
  if (s.navigation) (*j)["navigation"] = NavigationJson(*s.navigation, r.mission_time_s, r.infeasible_request);
  if (!s.flatness_decisions.empty()) {
    nlohmann::json decisions = nlohmann::json::array();
    for (const planning::FlatnessDecision& d : s.flatness_decisions) decisions.push_back(FlatnessDecisionJson(d));
    (*j)["flatness"] = {{"decisions", decisions}};
  }
  if (s.ukf) (*j)["ukf"] = {{"w_hat", s.ukf->w_hat}, {"settled_s", OrNull(s.ukf->settled_s)}};
  (*j)["lidar_points_dropped"] = s.lidar_points_dropped;
  (*j)["battery_min_voltage_v"] = OrNull(s.battery_min_voltage_v);
  if (s.odometry) {
    const stack::LioSummary& o = *s.odometry;
    (*j)["odometry"] = {{"frames", o.frames},
                        {"frames_used", o.frames_used},
                        {"frames_degenerate", o.frames_degenerate},
                        {"points_mean", o.points_mean},
                        {"matched_mean", o.matched_mean},
                        {"residual_rms_m_mean", o.residual_rms_m_mean},
                        {"iterations_mean", o.iterations_mean},
                        {"frame_ms_mean", o.frame_ms_mean},
                        {"frame_ms_p99", o.frame_ms_p99},
                        {"map_points", o.map_points},
                        {"degenerate_std_m", o.degenerate_std_m},
                        {"lidar_rotation_rad", Vec(o.lidar_rotation_rad)},
                        {"lidar_time_offset_s", o.lidar_time_offset_s}};
  }
  nlohmann::json transitions = nlohmann::json::array();
  for (const stack::ModeTransition& m : s.transitions) {
    transitions.push_back(
        {{"t", m.t}, {"from", stack::ToString(m.from)}, {"to", stack::ToString(m.to)}, {"reason", m.reason}});
  }
  nlohmann::json deadline = nlohmann::json::array();
  for (const stack::DeadlineEvent& e : s.deadline_events) {
    deadline.push_back({{"t", e.t}, {"step", ToName(e.step)}, {"missed", e.missed}});
  }
  (*j)["supervisor"] = {
      {"final_mode", stack::ToString(s.final_mode)}, {"transitions", transitions}, {"deadline_events", deadline}};
}

}  // namespace

nlohmann::json RunSummary::ToJson() const {
  nlohmann::json j;
  j["scenario"] = scenario;
  j["seed"] = seed;
  j["success"] = success;
  j["crashed"] = crashed;
  j["crash_reason"] = OrNull(crash_reason);
  j["crash_speed_m_s"] = OrNull(crash_speed_m_s);
  j["parachute_release_s"] = OrNull(parachute_release_s);
  j["battery_final_charge"] = OrNull(battery_final_charge);
  j["thrust_limit_at_fault"] = OrNull(thrust_limit_at_fault);
  j["failure_reason"] = OrNull(failure_reason);
  j["truth"] = io::ToJson(truth);
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
  j["altitude_change_m"] = OrNull(altitude_change_m);
  j["max_spin_rad_s"] = max_spin_rad_s;
  j["max_tilt_rad"] = max_tilt_rad;
  j["estimate_position_rmse_m"] = estimate_position_rmse_m;
  j["estimate_position_max_m"] = estimate_position_max_m;
  j["estimate_attitude_max_rad"] = estimate_attitude_max_rad;
  j["tilt_recovery_s"] = OrNull(tilt_recovery_s);
  j["faults"] = nlohmann::json::array();
  for (const FaultRecord& f : faults) {
    j["faults"].push_back({{"rotor", f.rotor}, {"kind", f.kind}, {"onset_s", f.onset_s}});
  }
  j["fdd"] = fdd ? FddJson(*fdd) : nlohmann::json(nullptr);  // null: the stack ran no fault detection
  j["composite_fdd"] = composite_fdd ? io::ToJson(*composite_fdd) : nlohmann::json(nullptr);
  j["sensors"] = {{"imu_rate_hz", sensors.imu_rate_hz},
                  {"imu_position_m", Vec(sensors.imu_position_m)},
                  {"command_delay_s", sensors.command_delay_s},
                  {"imu_notch", io::ToJson(sensors.imu_notch)}};
  AddStackJson(*this, &j);
  j["stack_ms_per_cycle_mean"] = stack_ms_per_cycle_mean;
  j["cost_ms_per_sim_s"] = cost_ms_per_sim_s.ToJson();
  j["physics_steps"] = physics_steps;
  j["control_cycles"] = control_cycles;
  return j;
}

nlohmann::json RunSummary::ToJsonWithoutTruth() const {
  nlohmann::json j = ToJson();
  for (const char* key : {"success", "crashed", "crash_reason", "crash_speed_m_s", "parachute_release_s", "battery_final_charge",
                          "thrust_limit_at_fault", "failure_reason", "truth",
                          "tracking_rmse_m", "tracking_rmse_window_m", "tracking_window_s", "tracking_rmse_eq37_m",
                          "max_position_error_m", "min_altitude_m", "altitude_change_m", "max_spin_rad_s",
                          "max_tilt_rad", "estimate_position_rmse_m", "estimate_position_max_m",
                          "estimate_attitude_max_rad", "tilt_recovery_s", "faults", "physics_steps"}) {
    j[key] = nullptr;
  }
  if (fdd) {
    j["fdd"] = DiagnosisJson(fdd->diagnosis);
    j["fdd"]["detected"] = fdd->detected();
  }
  return j;
}

}  // namespace rotorguard::harness

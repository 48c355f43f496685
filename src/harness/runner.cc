#include "rotorguard/harness/runner.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>

#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/harness/flight_metrics.h"
#include "rotorguard/harness/scene_recorder.h"
#include "rotorguard/io/files.h"
#include "rotorguard/record/flight_log.h"
#include "rotorguard/record/flight_mcap.h"
#include "rotorguard/record/report.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::harness {

namespace {
using vehicle::StateView;

/// One row of log.csv (flight_log.h, LogColumns): the truth, the stack's reference, estimate and
/// outputs, the rotors, and the FDD indices and NMPC solve time when the stack has them.
void AppendRow(const sim::Simulator& sim, const stack::FlightStack& st, io::NumericTable* table) {
  const StateView s(sim.state());
  std::size_t c = 0;
  const auto put = [&](double v) { table->values[c++].push_back(v); };
  const auto v3 = [&](const Vector3& v) { put(v.x()), put(v.y()), put(v.z()); };
  const auto q4 = [&](const Quaternion& q) { put(q.w()), put(q.x()), put(q.y()), put(q.z()); };
  put(sim.time_s());
  v3(s.p_W());
  q4(s.q_WB());
  v3(s.v_W());
  v3(s.w_B());
  const ReferencePoint& r = st.reference_point();
  v3(r.p_W);
  v3(r.v_W);
  put(r.yaw);
  const StateEstimate& e = st.estimate();
  v3(e.p_W);
  q4(e.q_WB);
  v3(e.v_W);
  v3(e.w_B);
  v3(sim.wind());
  put(sim.landed() ? 1.0 : 0.0);
  put(static_cast<int>(st.supervisor().mode()));
  const int n = sim.model().num_rotors();
  for (int i = 0; i < n; ++i) put(sim.applied_command()[i]);
  for (int i = 0; i < n; ++i) put(sim.rotor_thrusts()[i]);
  for (int i = 0; i < n; ++i) put(vehicle::RadPerSecondToRpm(sim.motor_speeds()[i]));
  for (int i = 0; i < n; ++i) put(static_cast<int>(sim.faults()[i].kind));  // docs/scenarios.md, "Outputs"
  if (const fdd::FaultDetector* detector = st.fault_detector()) {
    const std::vector<fdd::RotorStatus>& rotors = detector->rotors();
    for (int i = 0; i < n; ++i) put(rotors[i].motor_index);
    for (int i = 0; i < n; ++i) put(rotors[i].propeller_index);
    for (int i = 0; i < n; ++i) put(static_cast<int>(rotors[i].health));
  }
  if (const control::NmpcController* nmpc = st.nmpc()) put(1e3 * nmpc->summary().solve_time_s);
  RG_INVARIANT(c == table->columns.size(), "log row and LogColumns disagree");
}

double Finite(double v) { return std::isfinite(v) ? v : 0.0; }

}  // namespace

void DeliverToStack(const sim::SensorOutputs& o, stack::FlightStack* st, std::string* sensor_log) {
  if (o.imu) {
    st->OnImu(*o.imu);
    if (sensor_log) record::AppendImu(*o.imu, sensor_log);
  }
  if (o.esc) {
    st->OnEscTelemetry(*o.esc);
    if (sensor_log) record::AppendEsc(*o.esc, sensor_log);
  }
  if (o.odometry) {
    st->OnOdometry(*o.odometry);
    if (sensor_log) record::AppendOdometry(*o.odometry, sensor_log);
  }
  if (o.lidar) st->OnLidar(*o.lidar);  // not in sensors.csv: 200k points/s would swamp it
}

RunSummary RunScenario(const Scenario& sc, const RunOptions& options) {
  namespace fs = std::filesystem;
  if (sc.stack.control_rate_hz > sc.sim.physics_rate_hz) {
    ThrowInvalidArgument("RunScenario", "stack.control_rate_hz", sc.stack.control_rate_hz,
                         "at most sim.physics_rate_hz (the runner polls the stack at physics steps)");
  }
  const auto wall_start = std::chrono::steady_clock::now();

  const bool record = !options.out_dir.empty();
  const bool write_csv = options.log_format != LogFormat::kMcap;
  std::optional<io::AtomicFileWriter> sensors;
  if (record) {
    std::error_code ec;
    fs::create_directories(options.out_dir, ec);
    if (ec) throw std::runtime_error(fmt::format("cannot create {}: {}", options.out_dir, ec.message()));
    // A summary left by an earlier run must not pass for this run's.
    fs::remove(fs::path(options.out_dir) / "summary.json", ec);
    for (const char* name : {"report.html", "flight.mcap", "log.csv", "scene.json", "sensors.csv"}) {
      fs::remove(fs::path(options.out_dir) / name, ec);  // an older run's files would mix with this one's
    }
    if (write_csv) sensors.emplace((fs::path(options.out_dir) / "sensors.csv").string());
  }

  const vehicle::MultirotorModel truth_model(sc.vehicle);
  const RotorVector initial_motors = sc.initial_position_m.z() > 0.0
                                         ? truth_model.HoverThrusts()
                                         : RotorVector::Zero(truth_model.num_rotors());
  sim::Simulator sim(truth_model, sc.world, sc.faults, sc.sim, sc.seed,
                     truth_model.MakeState(sc.initial_position_m, sc.initial_yaw_rad, initial_motors));
  // The stack builds its own model from the vehicle parameters: it never holds the simulator.
  std::unique_ptr<control::Controller> controller;
  if (sc.stack.controller == "assembly") {
    if (!sc.assembly) throw std::invalid_argument("RunScenario: controller assembly needs the scenario's assembly");
    controller = std::make_unique<modular::AssemblyController>(*sc.assembly, AssemblyControllerOptionsOf(sc));
  }
  stack::FlightStack st(sc.vehicle, sc.reference, sc.stack, std::move(controller));
  std::string sensor_buffer;
  std::string* sensor_log = sensors ? &sensor_buffer : nullptr;
  if (sensor_log) sensor_buffer = record::kSensorLogHeader;
  DeliverToStack(sim.outputs(), &st, sensor_log);

  const TimeNs dt_ns = sim.step_ns();
  const double dt = ToSeconds(dt_ns);
  const auto steps = static_cast<std::int64_t>(std::llround(sc.duration_s / dt));
  const TimeNs control_period = st.control_period_ns();
  const TimeNs log_period = PeriodFromRate(sc.log_rate_hz);
  const TimeNs tracking_start = FromSeconds(sc.tracking_start_s);
  // A window to duration_s ends with the last physics step (steps * dt may round past duration_s).
  const double tracking_end_s = TrackingEndS(sc);
  const TimeNs tracking_end =
      tracking_end_s >= sc.duration_s ? steps * dt_ns : std::min(FromSeconds(tracking_end_s), steps * dt_ns);
  if (tracking_end <= tracking_start) {
    ThrowInvalidArgument("RunScenario", "tracking_start_s", sc.tracking_start_s,
                         fmt::format("before the tracking window's end, {:g} s", ToSeconds(tracking_end)));
  }
  TimeNs next_control = 0, next_log = 0;
  std::int64_t next_progress = 0;
  const std::int64_t progress_stride = std::max<std::int64_t>(1, steps / 100);

  RunSummary summary;
  summary.scenario = sc.name;
  summary.seed = sc.seed;
  summary.imu_rate_hz = sc.sim.imu.rate_hz;
  summary.imu_position_m = sc.sim.imu.position_m;
  if (sc.stack.fdd == "composite") summary.composite_fdd = sc.stack.composite_fdd;
  TrackingErrorAccumulator tracking;
  // Success (DESIGN.md, SucR): no crash, and the error within success_error_m over the last
  // success_hold_s of the flight. Remember the last time it was exceeded.
  std::optional<double> last_violation_s;
  std::optional<double> last_tilted_s;  // last time the tilt exceeded recovered_tilt_rad after a fault
  double last_violation_error = 0.0;
  double min_alt_all = std::numeric_limits<double>::infinity();
  double min_alt_after_fault = std::numeric_limits<double>::infinity();
  record::FlightLog flight;
  flight.table.columns = record::LogColumns(truth_model.num_rotors(), st.fault_detector() != nullptr, st.nmpc() != nullptr);
  flight.table.values.resize(flight.table.columns.size());
  SceneRecorder scene(sc.vehicle, sc.world, {}, sc.assembly.get());
  RotorCommand command = st.command();
  std::chrono::steady_clock::duration stack_time{}, sim_time{};
  const int waypoints_total = static_cast<int>(sc.stack.navigation.waypoints.size()) * sc.stack.navigation.rounds;

  for (std::int64_t k = 0; k < steps; ++k) {
    const TimeNs t = sim.time_ns();
    if (t >= next_control) {
      const auto stack_start = std::chrono::steady_clock::now();
      command = st.Update(t);
      stack_time += std::chrono::steady_clock::now() - stack_start;
      if (sensor_log) record::AppendCommand(command, sensor_log);
      next_control += control_period;
      ++summary.control_cycles;
      if (options.on_control_cycle) options.on_control_cycle(st);
      if (record) scene.OnControlCycle(ToSeconds(t), st);
    }
    const StateView s(sim.state());
    const Vector3 p_ref = st.reference().Evaluate(ToSeconds(t)).p_W;  // the planner's when navigating
    if (t >= tracking_start && t < tracking_end) tracking.Add(dt, s.p_W(), p_ref);
    const double error = (s.p_W() - p_ref).norm();
    if (!(error <= sc.success_error_m)) {
      last_violation_s = ToSeconds(t);
      last_violation_error = error;
    }
    const double alt = s.p_W().z();
    min_alt_all = std::min(min_alt_all, alt);
    if (!sim.fault_events().empty()) min_alt_after_fault = std::min(min_alt_after_fault, alt);
    summary.max_spin_rad_s = std::max(summary.max_spin_rad_s, std::abs(s.w_B().z()));
    if (!sim.fault_events().empty() && TiltOf(s.q_WB()) > sc.recovered_tilt_rad) last_tilted_s = ToSeconds(t);
    summary.max_tilt_rad = std::max(summary.max_tilt_rad, TiltOf(s.q_WB()));
    if (record && t >= next_log) {
      AppendRow(sim, st, &flight.table);
      scene.OnTime(ToSeconds(t));
      next_log += log_period;
    }
    const auto sim_start = std::chrono::steady_clock::now();
    const sim::SensorOutputs& outputs = sim.Step(command);
    const auto deliver_start = std::chrono::steady_clock::now();
    sim_time += deliver_start - sim_start;
    DeliverToStack(outputs, &st, sensor_log);
    stack_time += std::chrono::steady_clock::now() - deliver_start;
    if (sensor_log && sensor_buffer.size() > (1u << 20)) {
      sensors->Write(sensor_buffer);
      sensor_buffer.clear();
    }
    ++summary.physics_steps;
    if (sim.crashed()) break;
    if (summary.mission_time_s < 0.0 && (st.navigator() || st.flatness()) && st.waypoints_reached() >= waypoints_total) {
      summary.mission_time_s = sim.time_s();
    }
    // Done once the last waypoint was reached, the vehicle had 3 s to settle on it and held it for
    // the success rule's window.
    if (options.stop_when_mission_complete && summary.mission_time_s >= 0.0 &&
        sim.time_s() >= summary.mission_time_s + 3.0 + sc.success_hold_s) {
      break;
    }
    if (options.progress && k >= next_progress) {
      options.progress(static_cast<double>(k) / static_cast<double>(steps));
      next_progress += progress_stride;
    }
  }
  {
    const double alt = StateView(sim.state()).p_W().z();  // the final state (or the crash site)
    min_alt_all = std::min(min_alt_all, alt);
    if (!sim.fault_events().empty()) min_alt_after_fault = std::min(min_alt_after_fault, alt);
  }
  if (record) {
    AppendRow(sim, st, &flight.table);
    flight.scene = scene.ToJson();
    if (write_csv) {
      record::WriteFlightLogFiles(flight, options.out_dir);
      sensors->Write(sensor_buffer);
      sensors->Commit();
    }
    // The vehicle the stack flew, so that the run's folder is enough to replay its sensor log.
    io::WriteFileAtomically((fs::path(options.out_dir) / "vehicle.yaml").string(), VehicleToYaml(sc.vehicle));
  }
  if (options.progress) options.progress(1.0);

  summary.sim_time_s = sim.time_s();
  if (const planning::Replanner* nav = st.navigator()) {
    summary.waypoints_reached = st.waypoints_reached();
    summary.waypoints_total = static_cast<int>(sc.stack.navigation.waypoints.size()) * sc.stack.navigation.rounds;
    summary.plans = static_cast<int>(nav->events().size());
    for (const planning::Replanner::Event& e : nav->events()) {
      ++summary.plans_by_reason[e.reason];
      summary.planner_ms_mean += e.plan_ms / static_cast<double>(nav->events().size());
      if (e.status == planning::PlanSummary::Status::kSuccess) {
        summary.plans_fine_search += e.fine_search;
        summary.plans_rest_to_rest += e.rest_to_rest;
        continue;
      }
      ++summary.plans_failed;
      summary.failed_plans.push_back(fmt::format("{:.2f} s {}: {}", e.t, e.reason, planning::ToString(e.status)));
    }
  }
  if (const planning::FlatnessNavigator* f = st.flatness()) {
    summary.waypoints_reached = st.waypoints_reached();
    summary.waypoints_total = static_cast<int>(sc.stack.navigation.waypoints.size()) * sc.stack.navigation.rounds;
    for (const planning::FlatnessDecision& d : f->decisions()) {
      summary.flatness_decisions.push_back({{"t", d.t}, {"kind", d.kind}, {"t_s", d.t_s}, {"binding", d.binding},
                                            {"w_hat", {d.w_hat[0], d.w_hat[1], d.w_hat[2], d.w_hat[3]}},
                                            {"reason", d.reason},
                                            {"delta_m", {d.delta_m.x(), d.delta_m.y(), d.delta_m.z()}},
                                            {"envelope_s", d.envelope_s},
                                            {"actuator_s", d.actuator_s}});
    }
  }
  if (const auto* ukf = dynamic_cast<const fdd::UkfFdd*>(st.fault_detector())) {
    const Eigen::VectorXd w = ukf->loss();
    summary.ukf_w_hat.assign(w.data(), w.data() + w.size());
    summary.ukf_settled_s = ukf->settled_after_detection_s().value_or(-1.0);
  }
  summary.crashed = sim.crashed();
  summary.crash_reason = sim.crash_reason().value_or("");
  for (const stack::ModeTransition& m : st.supervisor().transitions()) {
    summary.mode_transitions.push_back({m.t, stack::ToString(m.from), stack::ToString(m.to), m.reason});
  }
  summary.final_mode = stack::ToString(st.supervisor().mode());
  // Why the run failed, the most fundamental first: a crash; a mission the supervisor gave up (not
  // a success, however well the landing went); a position error at the end; waypoints missed.
  std::string emergency;
  for (const stack::ModeTransition& m : st.supervisor().transitions()) {
    if (m.to == stack::FlightMode::kEmergencyLanding) {
      emergency = fmt::format("emergency landing at t = {:.2f} s: {}{}", m.t, m.reason,
                              st.supervisor().mode() == stack::FlightMode::kLanded ? " (landed)" : "");
      break;
    }
  }
  if (summary.crashed) {
    summary.failure_reason = "crash: " + summary.crash_reason;
  } else if (!emergency.empty()) {
    summary.failure_reason = emergency;
  } else if (last_violation_s && *last_violation_s >= summary.sim_time_s - sc.success_hold_s) {
    summary.failure_reason =
        fmt::format("position error {:.2f} m > {:g} m at t = {:.2f} s, within the last {:g} s", last_violation_error,
                    sc.success_error_m, *last_violation_s, sc.success_hold_s);
  }
  if (summary.failure_reason.empty() && summary.waypoints_reached < summary.waypoints_total) {
    summary.failure_reason = fmt::format("navigation reached {} of {} waypoints", summary.waypoints_reached,
                                         summary.waypoints_total);
    // The waypoint being flown to, and what its last plan said.
    using Status = planning::PlanSummary::Status;
    const planning::Replanner* nav = st.navigator();
    const Status last = nav ? nav->last_plan().status : Status::kSuccess;
    if (nav && !nav->events().empty() && (last == Status::kGoalBlocked || last == Status::kGoalOutOfBounds || last == Status::kNoPath)) {
      const std::vector<Vector3>& w = sc.stack.navigation.waypoints;
      const Vector3& goal = w[static_cast<std::size_t>(summary.waypoints_reached) % w.size()];
      summary.infeasible_request = true;
      summary.failure_reason += fmt::format("; waypoint {} at [{:g}, {:g}, {:g}] is unreachable: {} ({})",
                                            summary.waypoints_reached + 1, goal.x(), goal.y(), goal.z(),
                                            planning::ToString(last), nav->last_plan().message);
    }
  }
  summary.success = summary.failure_reason.empty();
  summary.tracking_rmse_m = Finite(tracking.rmse());
  summary.tracking_rmse_eq37_m = Finite(tracking.rmse_eq37());
  summary.max_position_error_m = Finite(tracking.max_error());
  if (summary.crashed) {
    // A wreck does not follow the reference: over the rest of the window the vehicle is where it
    // crashed, so that crashing early does not shorten the error's window (paper 002's Table II
    // counts its collided flights' errors).
    const Vector3 wreck = StateView(sim.state()).p_W();
    TimeNs t = sim.time_ns();  // the physics steps' grid, as the flown samples
    if (t < tracking_start) t += (tracking_start - t + dt_ns - 1) / dt_ns * dt_ns;
    for (; t < tracking_end; t += dt_ns) {
      tracking.Add(dt, wreck, st.reference().Evaluate(ToSeconds(t)).p_W);
    }
  }
  summary.tracking_rmse_window_m = Finite(tracking.rmse());
  summary.tracking_start_s = sc.tracking_start_s;
  // A flight that stopped early without a crash (its mission done) was tracked up to its stop.
  summary.tracking_end_s =
      summary.crashed ? ToSeconds(tracking_end) : std::min(ToSeconds(tracking_end), summary.sim_time_s);
  summary.min_altitude_m = Finite(sim.fault_events().empty() ? min_alt_all : min_alt_after_fault);
  if (!sim.fault_events().empty() && !summary.crashed) {
    const double onset = sim.fault_events().front().onset_s;
    const double settle = last_tilted_s ? *last_tilted_s : onset;
    // Still tilted at the very end: it never settled.
    summary.tilt_recovery_s = settle >= summary.sim_time_s - 2.0 * dt ? -1.0 : std::max(0.0, settle - onset);
  }
  summary.map_voxels_occupied = st.map() ? st.map()->occupied_count() : -1;
  summary.lidar_points_dropped = st.lidar_points_dropped();
  if (const fdd::FaultDetector* detector = st.fault_detector()) {
    summary.fdd = ScoreFdd(detector->rotors(), sim.fault_events());
  }
  for (const sim::FaultEvent& e : sim.fault_events()) {
    summary.faults.push_back({e.rotor, std::string(vehicle::ToString(e.kind)), e.onset_s});
  }
  summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  const double stack_s = std::chrono::duration<double>(stack_time).count();
  const double simulator_s = std::chrono::duration<double>(sim_time).count();
  summary.stack_ms_per_cycle_mean =
      summary.control_cycles > 0 ? 1e3 * stack_s / static_cast<double>(summary.control_cycles) : 0.0;
  summary.realtime_factor = summary.wall_time_s > 0.0 ? summary.sim_time_s / summary.wall_time_s : 0.0;
  summary.stack_realtime_factor = stack_s > 0.0 ? summary.sim_time_s / stack_s : 0.0;
  if (summary.sim_time_s > 0.0) {
    const auto per_sim_s = [&](double wall_s) { return 1e3 * wall_s / summary.sim_time_s; };
    const stack::StackCost& c = st.cost();
    RunCost& cost = summary.cost_ms_per_sim_s;
    cost.simulator = per_sim_s(simulator_s);
    cost.mapper = per_sim_s(c.mapper_s);
    cost.planner = per_sim_s(c.planner_s);
    cost.controller = per_sim_s(c.controller_s);
    cost.stack_other = per_sim_s(std::max(0.0, stack_s - c.mapper_s - c.planner_s - c.controller_s));
    cost.runner = per_sim_s(std::max(0.0, summary.wall_time_s - stack_s - simulator_s));
  }
  if (record) {
    flight.summary = summary.ToJson();
    if (options.log_format != LogFormat::kCsv) {
      record::WriteFlightMcap(flight, (fs::path(options.out_dir) / "flight.mcap").string());
    }
    io::WriteFileAtomically((fs::path(options.out_dir) / "summary.json").string(), flight.summary.dump(2) + "\n");
    if (options.report) record::WriteFlightReport(flight, (fs::path(options.out_dir) / "report.html").string());
  }
  return summary;
}

}  // namespace rotorguard::harness

#include "rotorguard/rosbridge/replay.h"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <thread>
#include <variant>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/harness/flight_recorder.h"
#include "rotorguard/record/report.h"
#include "rotorguard/record/sensor_log.h"
#include "rotorguard/harness/sitl.h"
#include "rotorguard/io/files.h"
#include "rotorguard/rosbridge/topics.h"
#include "rotorguard/rosbridge/wire_convert.h"
#include "rotorguard/runtime/clock.h"
#include "rotorguard/runtime/spsc_queue.h"

namespace rotorguard::rosbridge {

namespace {

/// The topic without its leading slash (a bag written by `rosbag record` has resolved names).
std::string_view Bare(std::string_view topic) { return topic.starts_with('/') ? topic.substr(1) : topic; }

class CollectingSink final : public runtime::CommandSink {
 public:
  void Send(const runtime::CycleTelemetry& cycle) override { queue_.TryPush(cycle); }
  bool TryReceive(runtime::CycleTelemetry* cycle) { return queue_.TryPop(cycle); }

 private:
  runtime::SpscQueue<runtime::CycleTelemetry, 1024> queue_;
};


}  // namespace

std::string Diagnosis::ToString() const {
  std::string s;
  for (std::size_t i = 0; i < health.size(); ++i) {
    s += fmt::format("{}rotor {}: {}", i ? "; " : "", i, health[i]);
    if (first_not_ok_s[i]) s += fmt::format(" (from {:.3f} s)", *first_not_ok_s[i]);
  }
  return s.empty() ? "no fault detection" : s;
}

Diagnosis DiagnosisOf(const std::vector<runtime::CycleTelemetry>& cycles, double until_s) {
  Diagnosis d;
  for (const runtime::CycleTelemetry& c : cycles) {
    const double t = ToSeconds(c.command.state_t_ns);
    if (t > until_s + 1e-9 || c.command.held != 0) continue;
    const auto n = static_cast<std::size_t>(c.fdd_rotors);
    d.health.resize(n, "ok");
    d.first_not_ok_s.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      d.health[i] = ToName(c.health[i].health);
      if (c.health[i].health != fdd::RotorHealth::kOk && !d.first_not_ok_s[i]) d.first_not_ok_s[i] = t;
    }
  }
  return d;
}

nlohmann::json ReplaySummary::ReplayJson() const {
  return {{"inputs", inputs},
          {"frames_dropped_points", frames_dropped_points},
          {"cycles", cycles.size()},
          {"recorded_cycles", recorded_cycles.size()},
          {"compared", compared},
          {"recorded_held", recorded_held},
          {"position_max_diff_m", position_max_diff_m},
          {"attitude_max_diff_rad", attitude_max_diff_rad},
          {"velocity_max_diff_m_s", velocity_max_diff_m_s},
          {"first_divergence_s", first_divergence_s ? nlohmann::json(*first_divergence_s) : nlohmann::json()},
          {"diagnosis", diagnosis.ToString()},
          {"recorded_diagnosis", recorded_diagnosis.ToString()},
          {"diagnosis_equal", diagnosis == recorded_diagnosis}};
}

nlohmann::json ReplaySummary::ToJson() const {
  nlohmann::json j = summary.ToJsonWithoutTruth();
  // The simulator's loop measures these; a replay runs none (its wall time is wall_time_s).
  for (const char* key : {"stack_realtime_factor", "stack_ms_per_cycle_mean", "cost_ms_per_sim_s"}) j[key] = nullptr;
  j["source"] = {{"messages", bag.messages}, {"skipped_types", bag.skipped_types}, {"bad", bag.bad}};
  j["replay"] = ReplayJson();
  return j;
}

namespace {

/// The run folder of a replay: what `run` writes, without the truth.
void WriteRunFolder(const harness::NodeStack& node, const ReplaySummary& r, const std::string& sensor_log,
                    const ReplayOptions& options) {
  const stack::FlightStack& st = *node.stack;
  const harness::Scenario& sc = node.scenario;
  record::FlightLog log;
  const int rotors = st.model().num_rotors();
  const bool with_fdd = !r.cycles.empty() && r.cycles.front().fdd_rotors > 0;
  const stack::LioEstimator* lio = st.lio();
  log.table.columns = record::LogColumns({.rotors = rotors, .truth = false, .fdd = with_fdd, .lio = lio != nullptr});
  log.table.values.resize(log.table.columns.size());
  // A row per cycle at the log's rate, each with the odometry's newest frame at its instant.
  const std::vector<perception::LioFrameSummary> no_frames;
  const std::vector<perception::LioFrameSummary>& frames = lio ? lio->frames() : no_frames;
  std::size_t frame = 0;
  const TimeNs log_period = PeriodFromRate(sc.log_rate_hz);
  TimeNs next_row = std::numeric_limits<TimeNs>::min();
  for (const runtime::CycleTelemetry& c : r.cycles) {
    const TimeNs t = c.command.state_t_ns;
    if (t < next_row) continue;
    next_row = t + log_period;
    while (frame < frames.size() && frames[frame].t_ns <= t) ++frame;
    const perception::LioFrameSummary newest = frame > 0 ? frames[frame - 1] : perception::LioFrameSummary{};
    harness::AppendCycleRow(c, lio ? &newest : nullptr, &log.table);
  }
  // The scene: the vehicle and the map the stack built (a bag holds no world, and the plans are
  // the planner thread's, not reported per cycle).
  harness::SceneRecorder scene(sc.vehicle, sim::World{}, {}, sc.assembly.get());
  if (const perception::VoxelMap* map = st.map()) scene.OnMap(r.summary.sim_time_s, *map);
  log.scene = scene.ToJson();
  log.summary = r.ToJson();
  const std::filesystem::path dir(options.out_dir);
  record::WriteFlightLogFiles(log, options.out_dir);
  io::WriteFileAtomically((dir / "sensors.csv").string(), sensor_log);
  io::WriteFileAtomically((dir / "vehicle.yaml").string(), harness::VehicleToYaml(st.model().params()));
  io::WriteFileAtomically((dir / "summary.json").string(), log.summary.dump(2) + "\n");
  if (options.report) record::WriteFlightReport(log, (dir / "report.html").string());
}

}  // namespace

ReplaySummary Replay(const harness::Scenario& scenario, const std::string& bag_path, const ReplayOptions& options) {
  if (!options.out_dir.empty()) harness::PrepareRunFolder(options.out_dir);
  const Stopwatch wall;
  harness::NodeStack node = harness::MakeNodeStack(scenario);
  stack::FlightStack& st = *node.stack;
  const double period_s = options.frame_period_s > 0.0 ? options.frame_period_s : 1.0 / node.scenario.sim.lidar.frame_rate_hz;
  const TimeNs frame_period = FromSeconds(period_s);
  ReplaySummary r;
  // Both spellings of each topic: as rotorguard writes them, as `rosbag record` resolves them.
  const auto both = [](std::initializer_list<const char*> names) {
    std::vector<std::string> v;
    for (const char* n : names) v.insert(v.end(), {n, std::string("/") + n});
    return v;
  };

  // Pass 1: the flight's time base and the cycles it recorded.
  std::optional<TimeBase> flight_base;
  std::vector<ros1::Cycle> recorded;
  ros1::ReadBag(
      bag_path,
      [&](const ros1::BagMessage& m) {
        if (const auto* start = std::get_if<ros1::ClockTick>(&m.message); start && !flight_base) flight_base = TimeBase{start->clock};
        if (const auto* c = std::get_if<ros1::Cycle>(&m.message)) recorded.push_back(*c);
      },
      both({topics::kMissionStart.name, topics::kControlCycle.name}));
  // A cycle that knows its inputs (recorded by rotorguard) can be replayed on exactly them.
  const bool scripted = std::any_of(recorded.begin(), recorded.end(), [](const ros1::Cycle& c) { return c.inputs > 0; });

  runtime::SimulatedTime time(-1);
  runtime::SimulatedClock clock(&time);
  CollectingSink sink;
  runtime::OnboardExecutorOptions eo;
  eo.trigger = scripted ? runtime::CycleTrigger::kScript : runtime::CycleTrigger::kClock;
  eo.lockstep_order = true;
  runtime::OnboardExecutor executor(&st, &clock, &sink, eo);
  const TimeNs control_period = st.control_period_ns();
  TimeNs next_control = 0;
  // sensors.csv: every message handed over, and each cycle's command as it comes.
  const bool writes = !options.out_dir.empty();
  std::string sensor_log(writes ? record::kSensorLogHeader : "");
  // The cycles so far, taken from the sink (as they come: its queue is bounded).
  const auto drain = [&] {
    for (runtime::CycleTelemetry c; sink.TryReceive(&c);) {
      r.cycles.push_back(c);
      if (writes) record::AppendCommand({c.command.state_t_ns, c.command.thrust_n}, &sensor_log);
    }
  };
  const auto receive = [&](auto&& until) {
    for (drain(); !until(); drain()) std::this_thread::yield();
  };
  // Without a script: every control instant before `b` (a cycle sees the messages handed over up
  // to its instant), on the control grid.
  const auto run_until = [&](TimeNs b) {
    while (next_control < b) {
      time.Advance(next_control);
      const TimeNs t = next_control;
      receive([&] { return !r.cycles.empty() && r.cycles.back().command.state_t_ns >= t; });
      next_control += control_period;
    }
  };
  // With one: the recorded cycles whose inputs have all been handed over.
  std::vector<runtime::ScriptedCycle> script;
  std::size_t scripted_next = 0;
  std::uint64_t fed = 0;
  const auto push_script = [&] {
    for (; scripted_next < script.size() && script[scripted_next].inputs <= fed; ++scripted_next) {
      time.Advance(script[scripted_next].t_ns);
      executor.ScriptCycle(script[scripted_next]);
      drain();
    }
  };
  executor.Start();
  TimeNs last_t = 0;
  r.bag = ros1::ReadBag(
      bag_path,
      [&](const ros1::BagMessage& m) {
        if (!flight_base) flight_base = TimeBase{m.time};  // without a mission_start: t = 0 at the first message
        const TimeBase& b = *flight_base;
        if (script.empty() && scripted) {
          for (const ros1::Cycle& c : recorded) {
            if (c.command.held != 0) continue;
            const std::size_t n = std::min<std::size_t>(c.command.thrust_n.size(), kMaxRotors);
            script.push_back({b.ToTime(c.command.stamp), c.inputs, c.lio_serial,
                              Eigen::Map<const Eigen::VectorXd>(c.command.thrust_n.data(), static_cast<Eigen::Index>(n))});
          }
        }
        const std::string_view topic = Bare(m.topic);
        const TimeNs t = b.ToTime(m.time);
        if (!scripted) run_until(t);
        // Handed over in the bag's order; a full intake is waited for (a replay loses nothing).
        const auto hand_over = [&](auto&& give) {
          while (!give()) std::this_thread::yield();
          ++fed;
          ++r.inputs[std::string(topic)];
          last_t = t;
          if (scripted) push_script();
          drain();
        };
        if (const auto* imu = std::get_if<ros1::Imu>(&m.message); imu && topic == topics::kImu.name) {
          const ImuSample sample = FromWire(*imu, b);
          if (writes) record::AppendImu(sample, &sensor_log);
          hand_over([&] { return executor.OnImu(sample); });
        } else if (const auto* esc = std::get_if<ros1::Esc>(&m.message); esc && topic == topics::kEscTelemetry.name) {
          if (const std::optional<EscTelemetry> e = FromWire(*esc, b)) {
            if (writes) record::AppendEsc(*e, &sensor_log);
            hand_over([&] { return executor.OnEscTelemetry(*e); });
          }
        } else if (const auto* odo = std::get_if<ros1::Odometry>(&m.message); odo && topic == topics::kExternalOdometry.name) {
          const OdometrySample sample = FromWireOdometry(*odo, b);
          if (writes) record::AppendOdometry(sample, &sensor_log);
          hand_over([&] { return executor.OnOdometry(sample); });
        } else if (const auto* cloud = std::get_if<ros1::Cloud>(&m.message); cloud && topic == topics::kPoints.name) {
          auto frame = std::make_shared<const LidarFrame>(FromWire(*cloud, b, frame_period));
          r.frames_dropped_points += static_cast<std::uint64_t>(frame->dropped);
          hand_over([&] { return executor.OnLidar(frame); });
        }
      },
      both({topics::kMissionStart.name, topics::kImu.name, topics::kEscTelemetry.name, topics::kExternalOdometry.name,
            topics::kPoints.name}));
  if (r.inputs[topics::kImu.name] == 0) {
    time.Stop();
    executor.Stop();
    throw std::runtime_error(fmt::format("bag: '{}' holds no IMU samples on topic '{}'", bag_path, topics::kImu.name));
  }
  if (scripted) {
    push_script();
    receive([&] { return r.cycles.size() >= scripted_next; });
  } else {
    run_until(last_t + 1);
  }
  time.Stop();
  executor.Stop();
  drain();
  for (const ros1::Cycle& c : recorded) r.recorded_cycles.push_back(FromWire(c, flight_base.value_or(TimeBase{})));
  r.summary = harness::SummaryWithoutTruth(node, r.cycles.empty() ? 0.0 : ToSeconds(r.cycles.back().command.state_t_ns));
  r.summary.control_cycles = r.cycles.size();

  // The replay against the recording, at the instants both ran a cycle of their own.
  double until_s = -1.0;
  std::map<TimeNs, const runtime::CycleTelemetry*> by_instant;
  for (const runtime::CycleTelemetry& c : r.recorded_cycles) {
    if (c.command.held == 0) {
      by_instant[c.command.state_t_ns] = &c;
    } else {
      ++r.recorded_held;
    }
  }
  for (const runtime::CycleTelemetry& c : r.cycles) {
    const auto it = by_instant.find(c.command.state_t_ns);
    if (it == by_instant.end()) continue;
    const StateEstimate& a = c.estimate;
    const StateEstimate& e = it->second->estimate;
    ++r.compared;
    r.position_max_diff_m = std::max(r.position_max_diff_m, (a.p_W - e.p_W).norm());
    if (!r.first_divergence_s && (a.p_W - e.p_W).norm() > 1e-6) r.first_divergence_s = ToSeconds(c.command.state_t_ns);
    r.velocity_max_diff_m_s = std::max(r.velocity_max_diff_m_s, (a.v_W - e.v_W).norm());
    r.attitude_max_diff_rad = std::max(r.attitude_max_diff_rad, a.q_WB.angularDistance(e.q_WB));
    until_s = std::max(until_s, ToSeconds(c.command.state_t_ns));
  }
  if (r.compared == 0) until_s = std::numeric_limits<double>::infinity();  // nothing recorded: the whole replay
  r.diagnosis = DiagnosisOf(r.cycles, until_s);
  r.recorded_diagnosis = DiagnosisOf(r.recorded_cycles, until_s);

  r.summary.wall_time_s = wall.seconds();
  r.summary.realtime_factor = r.summary.sim_time_s / std::max(r.summary.wall_time_s, 1e-9);
  if (writes) WriteRunFolder(node, r, sensor_log, options);
  return r;
}

}  // namespace rotorguard::rosbridge

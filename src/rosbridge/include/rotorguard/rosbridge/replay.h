#pragma once
/// Replay: a bag's sensor messages through a scenario's flight stack (`rotorguard replay`,
/// docs/ros.md), handed over in the bag's time order, every LiDAR frame processed.
///
/// A bag rotorguard recorded holds its cycles (control_cycle), each with the number of messages
/// the stack had taken in before it and the odometry update it had fused: the replay runs each
/// cycle at its instant on exactly those (CycleTrigger::kScript), so a real-time flight, whose
/// interleaving of messages, cycles and odometry updates depended on its threads' timing, is
/// replayed as it happened, and the replay's estimates and FDD diagnosis are compared with the
/// recorded ones. Another bag (`rosbag record` of a vehicle's drivers) is replayed on the stack's
/// control grid, each cycle after the messages up to its instant, the perception finishing every
/// frame first (the lockstep order).
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/ros1/bag.h"
#include "rotorguard/runtime/onboard_executor.h"

namespace rotorguard::rosbridge {

struct ReplayOptions {
  /// Output folder ("" writes nothing): a run's files without its truth (docs/ros.md,
  /// "Replay"): summary.json (its "replay" key the comparison), log.csv, scene.json,
  /// sensors.csv, vehicle.yaml, and report.html when `report`.
  std::string out_dir;
  bool report = false;
  /// A LiDAR frame's sweep [s] (a cloud is stamped at its first instant); <= 0: the scenario's
  /// sensors.lidar.frame_rate_hz.
  double frame_period_s = 0.0;
};

/// The FDD's diagnosis of a flight from its cycles: per rotor, its health at the last cycle and
/// the instant it first left ok.
struct Diagnosis {
  std::vector<std::string> health;
  std::vector<std::optional<double>> first_not_ok_s;
  bool operator==(const Diagnosis&) const = default;
  std::string ToString() const;
};
/// The diagnosis of `cycles` (in the order they ran) up to instant `until_s` included (the deadline
/// guard's held commands are not cycles: skipped).
Diagnosis DiagnosisOf(const std::vector<runtime::CycleTelemetry>& cycles, double until_s);

struct ReplaySummary {
  ros1::BagReadSummary bag;
  std::map<std::string, std::uint64_t> inputs;  ///< messages handed to the stack, per topic
  std::uint64_t frames_dropped_points = 0;     ///< returns stamped outside their frame's sweep
  std::vector<runtime::CycleTelemetry> cycles;           ///< the replay's
  std::vector<runtime::CycleTelemetry> recorded_cycles;  ///< the bag's (control_cycle)
  std::uint64_t compared = 0;          ///< cycles at the same instant in both
  std::uint64_t recorded_held = 0;     ///< recorded commands the deadline guard held (no cycle of their own)
  double position_max_diff_m = 0.0;    ///< the largest |p_replay - p_recorded| over them
  double attitude_max_diff_rad = 0.0;  ///< the largest rotation between the two estimates' attitudes
  double velocity_max_diff_m_s = 0.0;
  /// The first instant whose estimates differ by more than a micrometre (where to look).
  std::optional<double> first_divergence_s;
  Diagnosis diagnosis, recorded_diagnosis;  ///< both up to the last instant compared
  harness::RunSummary summary;              ///< the stack's account and diagnosis (no truth)
  /// summary.json: summary.ToJsonWithoutTruth() with the comparison under "replay" (ReplayJson)
  /// and the bag under "source".
  nlohmann::json ToJson() const;
  /// The comparison with the recording, and what was handed over.
  nlohmann::json ReplayJson() const;
};

/// Replays the bag at `bag_path` through the stack of `scenario`. Throws std::runtime_error
/// naming the file when the bag cannot be read or holds no IMU samples.
ReplaySummary Replay(const harness::Scenario& scenario, const std::string& bag_path, const ReplayOptions& options = {});

}  // namespace rotorguard::rosbridge

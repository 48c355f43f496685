#pragma once
/// `rotorguard bench sitl`: the onboard runtime in software in the loop (docs/runtime.md).
///  - Platform: the machine's own wake-up lateness under each load, without the stack (the floor
///    under any loop's miss rate).
///  - Timing: a scenario (the forest: the LiDAR-inertial odometry on every frame, the replanner,
///    the NMPC) flown `repeats` times in each load condition, the stack in its own process
///    (`rotorguard node`): the miss rate (control instants whose command was sent more than a
///    control period after its IMU sample, or never: the thread came past the instant late), the
///    latency from IMU sample to command sent, holds and hand-overs of the deadline policy.
///    "one_core_busy": a thread of this process spins for the whole flight.
///  - FTC cells: paper 000's hover and tracking cells with a propeller loss and a motor stop,
///    `ftc_trials` flights each in software in the loop (stack in this process, on the executor's
///    threads) and the same flights in lockstep with the computation delay set to the range the
///    software-in-the-loop flight measured (its 10th to 90th percentile): equal outcomes and the
///    FDD latencies' difference.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/campaign_kinds/ftc_bench.h"
#include "rotorguard/harness/sitl.h"

namespace rotorguard::benchmarks {

struct SitlBenchOptions {
  std::string scenario;   ///< the timing flights' scenario file (required when repeats > 0)
  int repeats = 3;        ///< flights per load condition, in [0, 100]
  std::vector<std::string> loads = {"idle", "one_core_busy"};  ///< each idle or one_core_busy
  int fifo_priority = 0;  ///< 0: the normal scheduler; else SCHED_FIFO at it (sitl --fifo-priority)
  int control_cpu = -1;   ///< -1: no pinning; else the time-critical threads' CPU (sitl --control-cpu)
  /// Seconds per load (idle, one core busy, two cores busy) of the machine's own timing, without
  /// the stack: a thread scheduled as the control thread sleeping to instants one control period
  /// apart; how late it wakes (0: none).
  double platform_s = 60.0;
  /// The command that starts the stack's process: this program's path (`node` is appended).
  std::string self;
  /// The timing flights' transport, when not the shared-memory channel (SitlOptions::make_link:
  /// `bench sitl --transport ros`), and its name for the result.
  harness::StackLinkMaker make_link;
  std::string transport = "shared_memory";
  int ftc_trials = 20;  ///< flights per FTC cell, in [0, 1000]
  /// The FTC flights' vehicle, fault detection thresholds and world, as `bench ftc` sets them
  /// (its trials, seed, methods and cells are not used).
  FtcBenchOptions ftc;
  /// The FTC flights' first seed; flight k flies seed + k. 5001 on: seeds no test, calibration
  /// or other benchmark flies.
  std::uint64_t ftc_seed = 5001;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// Runs the benchmark; `progress` (when set) hears each flight's line.
nlohmann::json RunSitlBenchmark(const SitlBenchOptions& options,
                                const std::function<void(const std::string&)>& progress = {});
/// The result as Markdown tables.
std::string SitlMarkdown(const nlohmann::json& result);

}  // namespace rotorguard::benchmarks

#pragma once
/// Software in the loop (docs/runtime.md): the simulator steps in real time (or at a factor of
/// it) on the calling thread while the flight stack runs on the onboard executor's threads. Sensor
/// messages go to the stack as they are made; each command acts when it arrives, on the step's
/// time grid at the instant it was sent (sub-step resolution), plus the ESCs' drawn latency. The
/// stack's computation and hand-off delays are in the loop: measured, not drawn.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rotorguard/harness/run_summary.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/runtime/onboard_executor.h"
#include "rotorguard/sim/simulator.h"

namespace rotorguard::harness {

struct SitlOptions;

/// The stack's side of the loop as the simulator sees it: where sensor messages go and commands
/// come from, the clock the stack follows, and the stack's account at the end. RunSitl has two
/// of its own (the stack in this process; `rotorguard node` over shared memory); a transport
/// brings its own through SitlOptions::make_link (rosbridge: over ROS).
class StackLink {
 public:
  virtual ~StackLink() = default;
  /// The stack is ready for t = 0 once this returns (its threads started).
  virtual void Start() = 0;
  virtual runtime::Clock& clock() = 0;
  /// With lockstep_clock: the simulator's time moves to t, once the messages delivered so far are
  /// in the stack's hands.
  virtual void AdvanceTime(TimeNs t) = 0;
  /// Without lockstep_clock: the simulator's clock has reached t, the end of the step about to be
  /// simulated, whose sensor messages follow (a transport publishes its clock).
  virtual void OnClock(TimeNs /*t*/) {}
  virtual void Deliver(const sim::SensorOutputs& outputs) = 0;
  virtual bool TryReceive(runtime::CycleTelemetry* cycle) = 0;
  /// LiDAR frames the link could not hand on (its slots all still held), so far.
  virtual std::uint64_t frames_dropped() const { return 0; }
  /// Stops the stack; its account (JSON: the stack's summary, as `rotorguard node` sends it) and
  /// its loops' report (JSON).
  virtual nlohmann::json Finish(nlohmann::json* loops) = 0;
};

/// What makes a transport's link (SitlOptions::make_link).
using StackLinkMaker = std::function<std::unique_ptr<StackLink>(const SitlOptions&, const runtime::OnboardExecutorOptions&)>;

struct SitlOptions {
  /// Simulated seconds per wall-clock second, in (0, 10]: 1 is real time.
  double realtime_factor = 1.0;
  /// The simulator's time is the clock: the simulator waits at each control instant for the
  /// cycle's command, which acts after the scenario's computation delay, as in `run`; the
  /// executor's cycles run on the clock's instants and wait for the perception. The threaded
  /// stack then flies the lockstep runner's flight to the bit (tests/harness/sitl_test.cc);
  /// realtime_factor is not used.
  bool lockstep_clock = false;
  /// The executor's options (lockstep_clock sets its trigger and lockstep_order).
  runtime::OnboardExecutorOptions executor;
  /// Empty: the stack runs in this process. Else the command line that starts it in another
  /// (`rotorguard node SCENARIO ...`), given `--channel NAME` at its end: the two processes share
  /// a memory segment (runtime/sitl_channel.h). The node must fly the same scenario.
  std::vector<std::string> node_command;
  /// Set: the link to the stack, made by a transport (it then starts the node itself, from
  /// node_command when it needs one); RunSitl's own links are not used.
  StackLinkMaker make_link;
  /// Throws ValidationError naming the field.
  void Validate() const;
};

/// How the simulator's side of the loop fared.
struct SitlLinkReport {
  std::uint64_t commands = 0;        ///< commands received and applied
  std::uint64_t commands_after_end = 0;  ///< sent before the flight ended, received after it
  /// Stamped as sent before the IMU sample they were computed from: the two sides' clocks or the
  /// stamps disagree (0 when they agree).
  std::uint64_t commands_before_their_sample = 0;
  std::uint64_t commands_late = 0;   ///< received after the step they were sent in had been simulated
  double late_max_s = 0.0;           ///< the latest such arrival after its sending instant [s]
  std::uint64_t steps_behind = 0;    ///< physics steps begun more than half a step after their end had passed on the clock
  runtime::SlowestRecords behind;    ///< of those, the furthest behind the clock (latency: how far)
  /// The simulator's work per physics step on the wall clock (commands in, the step, sensors out,
  /// the log): what makes it fall behind when it does.
  runtime::LatencyHistogram step_work;
  runtime::SlowestRecords step_work_slowest;
  runtime::LatencyHistogram command_delay;  ///< a command's IMU sample -> it acts on the ESCs (before their latency)
  std::uint64_t frames_dropped = 0;  ///< LiDAR frames the link could not hand on (StackLink::frames_dropped)
  int processes = 1;                 ///< the simulator's and the stack's: 1 or 2
  std::string simulator_realtime = "normal scheduler (not asked)";  ///< the simulator thread's scheduling
  /// As runtime.json's "link" holds it (docs/runtime.md).
  nlohmann::json ToJson() const;
};

struct SitlResult {
  RunSummary summary;
  /// The executor's loops ("control", "perception", "planning": runs, deadline_misses, skipped,
  /// latency and compute percentiles, cpu_s, dropped) and its scheduling ("realtime"), as the
  /// process that ran it reported them.
  nlohmann::json loops;
  SitlLinkReport link;
  /// The runtime's and the link's figures (runtime.json).
  nlohmann::json RuntimeJson() const;
};

/// Flies `scenario` in software in the loop with the stack in this process. Writes summary.json
/// and runtime.json to options.out_dir when it is set (the log and the report are the lockstep
/// runner's). Throws as RunScenario does.
SitlResult RunSitl(const Scenario& scenario, const RunOptions& options, const SitlOptions& sitl);

/// The stack's process of a two-process flight: opens the shared-memory `channel` a RunSitl
/// created, builds the stack of `scenario` (the one the simulator flies), runs it on the onboard
/// executor until the flight ends and writes its account back. Throws std::runtime_error when the
/// channel cannot be opened or holds another layout (and tells the simulator of any failure).
void RunNode(const Scenario& scenario, const std::string& channel);

/// A node's flight stack for `scenario`: the scenario as flown (an assembly's mission planned
/// first, as the simulator's side plans it) and the stack built from its vehicle file and stack
/// keys alone.
struct NodeStack {
  Scenario scenario;
  std::unique_ptr<stack::FlightStack> stack;
};
NodeStack MakeNodeStack(const Scenario& scenario);

/// What a node sends back at the end of a flight, over any transport: {"account": the stack's
/// summary and FDD account, "loops": the executor's loops and scheduling (runtime.json's)}.
nlohmann::json NodeAccountJson(const stack::FlightStack& stack, const runtime::OnboardReport& report);

/// The summary of a flight known from its sensors alone (`rotorguard replay`: a bag holds no
/// truth) at instant sim_time_s [s]: the scenario, the stack's account, and its FDD's earliest
/// diagnosis. Write it with RunSummary::ToJsonWithoutTruth: its fields that need the truth are
/// not known.
RunSummary SummaryWithoutTruth(const NodeStack& node, double sim_time_s);

}  // namespace rotorguard::harness

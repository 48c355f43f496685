#pragma once
/// SitlChannel: software in the loop between two processes (docs/runtime.md), the simulator's and
/// the stack's (`rotorguard sitl` and the `rotorguard node` it starts), in one shared-memory
/// segment (Shared<SitlChannel>). Everything in it is fixed-size and lock-free: the sensor
/// messages in the order the simulator made them, LiDAR frames in slots, the cycles' commands and
/// telemetry back, the clock both follow, and the node's final account as JSON text.
#include <array>
#include <atomic>
#include <cstdint>

#include "rotorguard/runtime/clock.h"
#include "rotorguard/runtime/doorbell.h"
#include "rotorguard/runtime/onboard_executor.h"
#include "rotorguard/runtime/spsc_queue.h"

namespace rotorguard::runtime {

/// The layout's version: a change of anything below changes it.
inline constexpr std::uint64_t kSitlChannelMagic = 0x72672d7369746c04ull;  // "rg-sitl", 4

/// A LiDAR frame in shared memory (LidarFrame without its vectors).
struct FrameSlot {
  static constexpr int kMaxPoints = 1 << 16;
  TimeNs t_start_ns = 0, t_end_ns = 0;
  int dropped = 0;
  int points = 0;
  std::array<Eigen::Vector3f, kMaxPoints> points_S;
  std::array<std::uint32_t, kMaxPoints> offset_ns;
};

/// A message from the simulator: a sensor message, a frame in a slot, the simulator's time (on
/// its clock: the node's clock moves once the messages before it are in), or the flight's end.
struct SitlMessage {
  enum class Kind { kSensor, kFrame, kTime, kEnd };
  Kind kind = Kind::kSensor;
  SensorMessage sensor;
  int frame_slot = 0;
  TimeNs time_ns = 0;  ///< kTime
};

/// The node's progress, which the simulator waits on.
enum class NodeState : int {
  kStarting = 0,  ///< the node has not opened the channel yet
  kBuilt = 1,     ///< its stack is built; it waits for the clock
  kFlying = 2,    ///< its executor runs
  kDone = 3,      ///< its account is written
  kFailed = 4,    ///< it stopped on an error (the account holds the message)
};

struct SitlChannel {
  static constexpr int kFrameSlots = 4;
  static constexpr std::size_t kAccountBytes = 1 << 22;
  static constexpr std::size_t kMaxStalls = 8;

  // Set by the simulator: the executor's options, and the clock (lockstep: the simulator's time,
  // in kTime messages; else a steady clock from clock_origin_ns at clock_rate, set once the node
  // is built).
  CycleTrigger trigger = CycleTrigger::kImu;
  bool lockstep_order = false;
  bool lockstep_clock = false;
  RealtimeOptions realtime{.lock_memory = false, .fifo_priority = 0};
  int hold_periods = 2;
  double plan_ahead_s = 0.05;
  std::array<OnboardExecutorOptions::Stall, kMaxStalls> stalls{};
  std::size_t stall_count = 0;
  std::atomic<TimeNs> clock_origin_ns{0};
  double clock_rate = 1.0;

  std::atomic<int> node_state{0};
  Doorbell node_bell;  // rung at each change of node_state

  SpscQueue<SitlMessage, 4096> to_node;
  Doorbell to_node_bell;
  SpscQueue<int, 8> free_slots;  // frame slots the node has copied out, back to the simulator
  std::array<FrameSlot, kFrameSlots> frames;

  SpscQueue<CycleTelemetry, 1024> cycles;

  std::atomic<std::uint64_t> account_size{0};
  std::array<char, kAccountBytes> account{};  // JSON: the stack's account and the runtime's report, or an error
};

}  // namespace rotorguard::runtime

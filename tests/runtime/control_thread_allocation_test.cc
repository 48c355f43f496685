// The control thread never allocates (docs/runtime.md): every heap allocation of this process
// goes through the allocation counter's malloc family (allocation_counter.h), whose hook here
// counts the ones made on the executor's control thread while a flight is past its start.
// Flights in software in the loop, in this process, past their first second (the first cycles size the buffers: the NMPC's first plan, the
// histograms' first samples), without a fault in the flight (an isolation is an event that
// allocates: a mode transition's reason, a reconfiguration's new matrices).
#include <execinfo.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/harness/sitl.h"
#include "allocation_counter.h"
#include "test_util.h"

namespace {

thread_local bool t_counted = false;  // this thread is the control thread
std::atomic<bool> g_armed{false};     // the flight is past its start
std::atomic<long> g_allocations{0};
constexpr int kTraces = 4, kDepth = 24;
std::array<std::array<void*, kDepth>, kTraces> g_traces{};  // where the first ones came from
std::array<int, kTraces> g_depths{};

void Count() {
  if (!t_counted || !g_armed.load(std::memory_order_relaxed)) return;
  const long n = g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (n < kTraces) {
    t_counted = false;  // backtrace may allocate on its first call
    g_depths[static_cast<std::size_t>(n)] = backtrace(g_traces[static_cast<std::size_t>(n)].data(), kDepth);
    t_counted = true;
  }
}

}  // namespace

namespace rotorguard::harness {
namespace {

struct Flight {
  const char* name;
  std::vector<Override> overrides;
};

void PrintTo(const Flight& f, std::ostream* os) { *os << f.name; }

class ControlThread : public ::testing::TestWithParam<Flight> {};

TEST_P(ControlThread, NeverAllocatesOnceTheFlightIsUnderWay) {
  const Flight& f = GetParam();
  const Scenario sc = LoadScenario(testing::SourcePath(std::string("configs/scenarios/") + f.name + ".yaml"), f.overrides);
  SitlOptions o;
  o.realtime_factor = 0.5;
  o.executor.on_thread_start = [](std::string_view thread) { t_counted = thread == "control"; };
  RunOptions run;
  run.progress = [&](double fraction) { g_armed.store(fraction * sc.duration_s >= 1.0 && fraction < 1.0); };
  g_allocations.store(0);
  rotorguard::testing::SetAllocationHook(&Count);
  const SitlResult r = RunSitl(sc, run, o);
  g_armed.store(false);
  rotorguard::testing::SetAllocationHook(nullptr);
  const long n = g_allocations.load();
  EXPECT_GT(r.loops.at("control").at("runs").get<long>(), 100) << "a flight that ran no cycles checks nothing";
  EXPECT_EQ(n, 0) << "allocations on the control thread; the first ones' call stacks follow";
  for (long i = 0; i < std::min<long>(n, kTraces); ++i) {
    std::fprintf(stderr, "allocation %ld:\n", i);
    backtrace_symbols_fd(g_traces[static_cast<std::size_t>(i)].data(), g_depths[static_cast<std::size_t>(i)], STDERR_FILENO);
  }
}

// External odometry with the NMPC and the composite FDD; the LiDAR-inertial odometry's updates
// and its frames' tickets; the replanner's references handed over from the planning thread.
INSTANTIATE_TEST_SUITE_P(
    Flights, ControlThread,
    ::testing::Values(Flight{"fdd_hover_propeller_loss", {{"duration_s", "4"}, {"faults", "[]"}}},
                      Flight{"room_lidar_propeller_loss", {{"duration_s", "4"}, {"faults", "[]"}}},
                      Flight{"forest", {{"duration_s", "6"}, {"faults", "[]"}}}),
    [](const ::testing::TestParamInfo<Flight>& p) { return std::string(p.param.name); });

}  // namespace
}  // namespace rotorguard::harness

#pragma once
/// Two runs of one scenario are the same flight: the same steps and cycles, the same extremes of
/// the true state (a single bit's difference in any command changes them), the same estimate
/// error against the truth, the same diagnosis and reconfiguration, the same outcome.
#include <gtest/gtest.h>

#include "rotorguard/harness/run_summary.h"

namespace rotorguard::testing {

inline void ExpectSameFlight(const harness::RunSummary& a, const harness::RunSummary& b) {
  EXPECT_EQ(a.physics_steps, b.physics_steps);
  EXPECT_EQ(a.control_cycles, b.control_cycles);
  EXPECT_EQ(a.min_altitude_m, b.min_altitude_m);
  EXPECT_EQ(a.max_spin_rad_s, b.max_spin_rad_s);
  EXPECT_EQ(a.max_tilt_rad, b.max_tilt_rad);
  EXPECT_EQ(a.estimate_position_rmse_m, b.estimate_position_rmse_m);
  EXPECT_EQ(a.estimate_attitude_max_rad, b.estimate_attitude_max_rad);
  EXPECT_EQ(a.success, b.success);
  ASSERT_TRUE(a.fdd && b.fdd);
  ASSERT_TRUE(a.fdd->diagnosis && b.fdd->diagnosis);
  EXPECT_EQ(a.fdd->diagnosis->detection_s, b.fdd->diagnosis->detection_s);
  EXPECT_EQ(a.fdd->diagnosis->rotor, b.fdd->diagnosis->rotor);
  ASSERT_EQ(a.stack.reconfigurations.size(), b.stack.reconfigurations.size());
  for (std::size_t i = 0; i < a.stack.reconfigurations.size(); ++i) {
    EXPECT_EQ(a.stack.reconfigurations[i].t_s, b.stack.reconfigurations[i].t_s);
  }
}

}  // namespace rotorguard::testing

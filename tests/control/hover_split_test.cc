// Whether a vehicle can hover on the rotors it has left, against closed forms of the reference
// quadrotor's X layout: rotors 0 and 1 diagonal, 2 and 3 diagonal.
#include <gtest/gtest.h>

#include "rotorguard/control/allocation.h"
#include "rotorguard/core/error.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using rotorguard::testing::ReferenceQuad;

TEST(HoverThrustSplit, TheHealthyQuadrotorSharesItsWeightEqually) {
  const vehicle::VehicleParams v = ReferenceQuad();
  const std::optional<RotorVector> t = HoverThrustSplit(v, {false, false, false, false});
  ASSERT_TRUE(t);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR((*t)[i], v.weight_n() / 4.0, 1e-9);
}

TEST(HoverThrustSplit, OneFailureOrItsTwinLeavesTheOtherDiagonalCarryingHalfEach) {
  // Zero roll and pitch torque with rotor 0 out: T1 + T2 - T3 = 0 and -T1 + T2 - T3 = 0 (the
  // layout's y and x arms), so T1 = 0 and T2 = T3 = W/2, whether rotor 1 works or not.
  const vehicle::VehicleParams v = ReferenceQuad();
  for (const std::vector<bool>& failed :
       {std::vector<bool>{true, false, false, false}, std::vector<bool>{true, true, false, false}}) {
    const std::optional<RotorVector> t = HoverThrustSplit(v, failed);
    ASSERT_TRUE(t);
    EXPECT_NEAR((*t)[0], 0.0, 1e-9);
    EXPECT_NEAR((*t)[1], 0.0, 1e-9);
    EXPECT_NEAR((*t)[2], v.weight_n() / 2.0, 1e-9);
    EXPECT_NEAR((*t)[3], v.weight_n() / 2.0, 1e-9);
  }
}

TEST(HoverThrustSplit, TwoAdjacentFailuresOrTooWeakARemainingPairCannotHover) {
  vehicle::VehicleParams v = ReferenceQuad();
  // Rotors 0 and 2 share the +x side: whatever 1 and 3 give pitches the vehicle.
  EXPECT_FALSE(HoverThrustSplit(v, {true, false, true, false}));
  EXPECT_FALSE(HoverThrustSplit(v, {false, true, false, true}));
  EXPECT_FALSE(HoverThrustSplit(v, {true, true, true, true}));
  // One failure when the remaining diagonal pair cannot lift the weight: 2 x 0.49 W < W.
  for (vehicle::Rotor& r : v.rotors) r.max_thrust_n = 0.49 * v.weight_n();
  EXPECT_TRUE(HoverThrustSplit(v, {false, false, false, false}));
  EXPECT_FALSE(HoverThrustSplit(v, {true, false, false, false}));
}

TEST(HoverThrustSplit, AFailedListOfTheWrongSizeIsRejected) {
  RG_EXPECT_THROW_WITH(HoverThrustSplit(ReferenceQuad(), {true}), std::invalid_argument, "failed.size()");
}

}  // namespace
}  // namespace rotorguard::control


#include <cmath>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/vehicle/effectiveness.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::vehicle {
namespace {

using rotorguard::testing::MatricesNear;
using rotorguard::testing::ReferenceQuad;

TEST(EffectivenessMatrix, EqualsPaperEquation5ForTheReferenceQuad) {
  const double rd = 0.063, kt = 0.0107, h = 0.5 * std::sqrt(2.0) * rd;
  Eigen::Matrix4d expected;  // paper 000, eq. (5), typed from the paper
  expected << 1, 1, 1, 1,                    //
      -h, h, h, -h,                          //
      -h, h, -h, h,                          //
      -kt, -kt, kt, kt;
  EXPECT_TRUE(MatricesNear(ComputeEffectivenessMatrix(ReferenceQuad().rotors), expected, 1e-15));
}

TEST(EffectivenessMatrix, HandlesAnyRotorListAsData) {
  // A hexarotor with rotors every 60 degrees at 0.2 m: thrust row all ones, torques r x F.
  std::vector<Rotor> hex;
  for (int i = 0; i < 6; ++i) {
    const double ang = i * M_PI / 3.0;
    hex.push_back(Rotor{{0.2 * std::cos(ang), 0.2 * std::sin(ang), 0.05},
                        i % 2 ? SpinDirection::kClockwise : SpinDirection::kCounterClockwise, 0.01, 8.0});
  }
  const EffectivenessMatrix m = ComputeEffectivenessMatrix(hex);
  ASSERT_EQ(m.cols(), 6);
  for (int i = 0; i < 6; ++i) {
    // Torque of a thrust T along body z at r is r x (0, 0, T) = (r_y T, -r_x T, 0).
    const Eigen::Vector3d tau = hex[i].p_B.cross(Eigen::Vector3d(0, 0, 1));
    EXPECT_NEAR(m(0, i), 1.0, 1e-15);
    EXPECT_NEAR(m(1, i), tau.x(), 1e-15);
    EXPECT_NEAR(m(2, i), tau.y(), 1e-15);
    EXPECT_NEAR(m(3, i), i % 2 ? 0.01 : -0.01, 1e-15);
  }
}

TEST(EffectivenessMatrix, PseudoInverseIsARightInverse) {
  const EffectivenessMatrix m = ComputeEffectivenessMatrix(ReferenceQuad().rotors);
  const AllocationMatrix pinv = PseudoInverse(m);
  EXPECT_TRUE(MatricesNear(m * pinv, Eigen::Matrix4d::Identity(), 1e-12));
}

TEST(EffectivenessMatrix, PseudoInverseRejectsRankDeficientGeometry) {
  std::vector<Rotor> coaxial(4, Rotor{{0, 0, 0}, SpinDirection::kClockwise, 0.01, 5.0});
  RG_EXPECT_THROW_WITH(PseudoInverse(ComputeEffectivenessMatrix(coaxial)), std::invalid_argument,
                       "rank deficient");
}

TEST(VehicleParams, ValidationNamesFieldAndRule) {
  VehicleParams p = ReferenceQuad();
  p.mass_kg = -1.0;
  RG_EXPECT_THROW_WITH(p.Validate(), ValidationError, "mass_kg = -1");
  p = ReferenceQuad();
  p.inertia_kg_m2(2, 2) = -1e-3;
  RG_EXPECT_THROW_WITH(p.Validate(), ValidationError, "positive definite");
  p = ReferenceQuad();
  p.inertia_kg_m2(2, 2) = 14.0e-3;  // > I_xx + I_yy = 13.854e-3: no distribution of mass has it
  RG_EXPECT_THROW_WITH(p.Validate(), ValidationError, "each principal moment at most the sum of the other two");
  p.inertia_kg_m2(2, 2) = 13.85e-3;  // a flat plate's bound, approached from below: a body
  EXPECT_NO_THROW(p.Validate());
  p = ReferenceQuad();
  for (auto& r : p.rotors) r.max_thrust_n = 2.0;  // 8 N < 11.3 N weight
  try {
    p.Validate();
    ADD_FAILURE() << "thrust-to-weight below one accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "rotors");
    EXPECT_NE(std::string(e.what()).find("thrust-to-weight"), std::string::npos);
  }
  p = ReferenceQuad();
  for (auto& r : p.rotors) r.yaw_coefficient_m = 0.0;  // no yaw authority: rank 3
  RG_EXPECT_THROW_WITH(p.Validate(), ValidationError, "independent thrust");
  p = ReferenceQuad();
  p.rotors[0].max_thrust_n = p.rotors[1].max_thrust_n = 1.0;  // T/W > 1 but hover needs 2.82 N each
  p.rotors[2].max_thrust_n = 20.0;
  RG_EXPECT_THROW_WITH(p.Validate(), ValidationError, "allows hover");
  p = ReferenceQuad();
  p.rotors[2].max_thrust_n = std::nan("");
  try {
    p.Validate();
    ADD_FAILURE() << "NaN max thrust accepted";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.field(), "rotors.2.max_thrust_n");
  }
}

}  // namespace
}  // namespace rotorguard::vehicle

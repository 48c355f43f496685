
#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/modular/assembly.h"
#include "rotorguard/vehicle/effectiveness.h"
#include "assembly_fixture.h"
#include "test_util.h"

namespace rotorguard::modular {
namespace {

TEST(Assembly, ThreeByTwoMassAndInertiaByHand) {
  const Assembly a = BuildAssembly(testing::MarsSpec("3x2"));
  EXPECT_EQ(a.num_units, 6);
  EXPECT_EQ(a.vehicle.num_rotors(), 24);
  EXPECT_DOUBLE_EQ(a.vehicle.mass_kg, 3.0);
  // Units at x in {-0.25, 0, 0.25} (two each), y = +-0.125 (three each) about the centre of mass:
  // Ixx = 6 * 2.2e-3 + 0.5 * 6 * 0.125^2, Iyy = 6 * 2.2e-3 + 0.5 * 4 * 0.25^2,
  // Izz = 6 * 4e-3 + 0.5 * (4 * 0.25^2 + 6 * 0.125^2), no products (symmetric).
  Matrix3 expected = Matrix3::Zero();
  expected(0, 0) = 0.0132 + 0.046875;
  expected(1, 1) = 0.0132 + 0.125;
  expected(2, 2) = 0.024 + 0.125 + 0.046875;
  EXPECT_TRUE(testing::MatricesNear(a.vehicle.inertia_kg_m2, expected, 1e-12));
  EXPECT_TRUE(testing::MatricesNear(a.unit_position_B[0], Vector3(-0.25, -0.125, 0.0), 1e-12));
}

TEST(Assembly, LShapeHasTheProductOfInertiaOfItsAsymmetry) {
  AssemblySpec s = testing::MarsSpec("3x1");
  s.slots = {Eigen::Vector2i(0, 0), Eigen::Vector2i(1, 0), Eigen::Vector2i(0, 1)};
  const Assembly a = BuildAssembly(s);
  // Centre of mass at (s/3, s/3); offsets (-1,-1)s/3, (2,-1)s/3, (-1,2)s/3: sum x y = -s^2 / 3, so
  // I_xy = -m sum x y = m s^2 / 3; I_xx = I_yy = 3 * 2.2e-3 + m * (1 + 1 + 4) s^2 / 9.
  const double m = 0.5, sp = 0.25;
  EXPECT_NEAR(a.vehicle.inertia_kg_m2(0, 1), m * sp * sp / 3.0, 1e-12);
  EXPECT_NEAR(a.vehicle.inertia_kg_m2(1, 0), m * sp * sp / 3.0, 1e-12);
  EXPECT_NEAR(a.vehicle.inertia_kg_m2(0, 0), 3 * 2.2e-3 + m * 6.0 * sp * sp / 9.0, 1e-12);
  EXPECT_NEAR(a.vehicle.inertia_kg_m2(0, 2), 0.0, 1e-15);
}

TEST(Assembly, RotorsAreTheUnitsRotorsMovedToTheirSlots) {
  const AssemblySpec spec = testing::MarsSpec("3x3_plus");
  const Assembly a = BuildAssembly(spec);
  ASSERT_EQ(a.vehicle.num_rotors(), 20);
  for (int r = 0; r < a.vehicle.num_rotors(); ++r) {
    const int unit = a.UnitOfRotor(r), j = r - a.FirstRotor(unit);
    EXPECT_TRUE(testing::MatricesNear(a.vehicle.rotors[r].p_B, spec.unit.rotors[j].p_B + a.unit_position_B[unit], 1e-15));
    EXPECT_EQ(a.vehicle.rotors[r].direction, spec.unit.rotors[j].direction);
  }
  // The plus is symmetric about its centre unit: the centre of mass is the centre unit's.
  EXPECT_TRUE(testing::MatricesNear(a.unit_position_B[0], Vector3::Zero(), 1e-15));
  // Hover: the healthy rotors, equal thrusts, hold the weight without torque.
  const EffectivenessMatrix B = vehicle::ComputeEffectivenessMatrix(a.vehicle.rotors);
  const RotorVector t = RotorVector::Constant(20, a.vehicle.weight_n() / 20.0);
  EXPECT_TRUE(testing::MatricesNear(B * t, Eigen::Vector4d(a.vehicle.weight_n(), 0, 0, 0), 1e-12));
  // The collision sphere covers the outermost unit's.
  EXPECT_DOUBLE_EQ(a.vehicle.collision_radius_m, 0.25 + 0.15);
}

TEST(Assembly, InvalidSpecsNameTheField) {
  AssemblySpec s = testing::MarsSpec("3x2");
  s.slots[4] = s.slots[1];
  RG_EXPECT_THROW_WITH(BuildAssembly(s), ValidationError, "slots.4");
  s = testing::MarsSpec("3x2");
  s.spacing_m = 0.1;
  RG_EXPECT_THROW_WITH(BuildAssembly(s), ValidationError, "spacing_m = 0.1");
  s = testing::MarsSpec("3x2");
  for (int k = 0; k < 11; ++k) s.slots.emplace_back(10 + k, 0);  // 17 units, 68 rotors
  RG_EXPECT_THROW_WITH(BuildAssembly(s), ValidationError, "at most 64 rotors");
  s.slots.clear();
  RG_EXPECT_THROW_WITH(BuildAssembly(s), ValidationError, "slots");
  RG_EXPECT_THROW_WITH(ShapeSlots("5x5"), std::invalid_argument, "shape = 5x5");
}

}  // namespace
}  // namespace rotorguard::modular

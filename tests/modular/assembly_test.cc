
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

TEST(ComposeVehicle, UnequalPartsByTheParallelAxisTheorem) {
  // Two parts 1 m apart along x, of 1 kg and 3 kg: the common centre of gravity lies 0.75 m from
  // the light one, and the pair adds m1 m2 d^2 / (m1 + m2) = 0.75 kg m^2 about y and z.
  vehicle::VehicleParams light = testing::MarsSpec("3x1").unit, heavy = light;
  heavy.mass_kg = 3.0;
  light.mass_kg = 1.0;
  heavy.motor_time_constant_s = 3.0 * light.motor_time_constant_s;
  heavy.rotor_drag_kg_s *= 2.0;
  Vector3 cog;
  const vehicle::VehicleParams v =
      ComposeVehicle({{&light, Vector3::Zero()}, {&heavy, Vector3(1.0, 0.0, 0.0)}}, "pair", &cog);
  EXPECT_EQ(v.name, "pair");
  EXPECT_DOUBLE_EQ(v.mass_kg, 4.0);
  EXPECT_TRUE(testing::MatricesNear(cog, Vector3(0.75, 0.0, 0.0), 1e-15));
  const Matrix3 pair = Vector3(0.0, 0.75, 0.75).asDiagonal();
  EXPECT_TRUE(testing::MatricesNear(v.inertia_kg_m2, light.inertia_kg_m2 + heavy.inertia_kg_m2 + pair, 1e-12));
  EXPECT_TRUE(testing::MatricesNear(v.rotor_drag_kg_s, 3.0 * light.rotor_drag_kg_s, 1e-15));
  EXPECT_DOUBLE_EQ(v.motor_time_constant_s, 2.0 * light.motor_time_constant_s);
  ASSERT_EQ(v.num_rotors(), 2 * light.num_rotors());
  const int n = light.num_rotors();
  for (int i = 0; i < n; ++i) {
    EXPECT_TRUE(testing::MatricesNear(v.rotors[i].p_B, light.rotors[i].p_B - Vector3(0.75, 0, 0), 1e-15));
    EXPECT_TRUE(testing::MatricesNear(v.rotors[n + i].p_B, heavy.rotors[i].p_B + Vector3(0.25, 0, 0), 1e-15));
  }
  ASSERT_EQ(v.collision_spheres.size(), 2u);
  EXPECT_DOUBLE_EQ(v.collision_radius_m, 0.75 + light.collision_radius_m);
  EXPECT_THROW(ComposeVehicle({}, "none"), std::invalid_argument);
}

TEST(ComposeVehicle, OfIdenticalUnitsIsTheAssembly) {
  const Assembly a = BuildAssembly(testing::MarsSpec("3x2"));
  std::vector<RigidPart> parts;
  for (const Vector3& r : a.unit_position_B) parts.push_back({&a.unit, r + Vector3(0.1, -0.2, 0.05)});
  Vector3 cog;
  const vehicle::VehicleParams v = ComposeVehicle(parts, a.vehicle.name, &cog);
  EXPECT_TRUE(testing::MatricesNear(cog, Vector3(0.1, -0.2, 0.05), 1e-15));
  EXPECT_TRUE(testing::MatricesNear(v.inertia_kg_m2, a.vehicle.inertia_kg_m2, 1e-14));
  for (int i = 0; i < v.num_rotors(); ++i) {
    EXPECT_TRUE(testing::MatricesNear(v.rotors[i].p_B, a.vehicle.rotors[i].p_B, 1e-15));
  }
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

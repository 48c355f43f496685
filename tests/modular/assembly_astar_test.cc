
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/modular/assembly_astar.h"
#include "assembly_fixture.h"
#include "test_util.h"

namespace rotorguard::modular {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(AttitudeObjective, FourByOneMatchesTheHandSummedTorqueSpans) {
  const Assembly a = testing::MarsAssembly("4x1");
  const RotorVector eta = RotorVector::Ones(16);
  // Flying along x at yaw 0: every rotor's lateral arm is 0.075 m (roll span 16 * 0.075 * 2.6); the
  // longitudinal arms are 0.05, 0.2, 0.3, 0.45 m twice on each side (pitch span 4.0 * 2.6).
  const double roll = 16 * 0.075 * 2.6, pitch = 4.0 * 2.6;
  EXPECT_NEAR(AttitudeObjective(a, eta, 0.0, Eigen::Vector2d::UnitX()), roll - pitch, 1e-12);
  EXPECT_NEAR(AttitudeObjective(a, eta, 0.5 * kPi, Eigen::Vector2d::UnitX()), pitch - roll, 1e-12);
  // Only the angle between the yaw and the direction matters.
  EXPECT_NEAR(AttitudeObjective(a, eta, 0.3, Eigen::Vector2d(std::cos(0.3), std::sin(0.3))), roll - pitch, 1e-12);
}

TEST(AttitudeObjective, TheOptimalAttitudeFliesARowLengthwise) {
  const Assembly a = testing::MarsAssembly("4x1");
  const RotorVector eta = RotorVector::Ones(16);
  const auto yaws = [&](const Eigen::Vector2d& d) { return OptimalYaws(a, eta, d, 24); };
  ASSERT_EQ(yaws(Eigen::Vector2d::UnitX()).size(), 2u);
  EXPECT_NEAR(yaws(Eigen::Vector2d::UnitX())[0], 0.0, 1e-12);
  EXPECT_NEAR(yaws(Eigen::Vector2d::UnitX())[1], kPi, 1e-12);
  EXPECT_NEAR(yaws(Eigen::Vector2d::UnitY())[0], 0.5 * kPi, 1e-12);
  EXPECT_NEAR(yaws(Eigen::Vector2d(1.0, 1.0))[0], 0.25 * kPi, 1e-12);
  // A dead end unit lowers both spans but the row still flies lengthwise.
  RotorVector dead = eta;
  dead.segment(12, 4).setZero();
  EXPECT_NEAR(OptimalYaws(a, dead, Eigen::Vector2d::UnitX(), 24)[0], 0.0, 1e-12);
}

using testing::Band;
using testing::WallWithGap;

TEST(AssemblyAStar, ARowTurnsLengthwiseToPassAGapNarrowerThanItIsLong) {
  const Assembly a = testing::MarsAssembly("4x1");  // 1.05 m long, 0.3 m wide
  std::vector<Vector3> wall;
  const perception::VoxelMap map = WallWithGap(0.8, &wall);
  const RotorVector eta = RotorVector::Ones(16);
  // Broadside to the wall at the start.
  const AssemblyPath path = FindAssemblyPath(map, a, eta, {Vector3(-1.5, 0.0, 1.5), 0.5 * kPi}, Vector3(1.5, 0.0, 1.5), Band());
  ASSERT_EQ(path.status, AssemblyPathStatus::kFound) << ToString(path.status);
  EXPECT_TRUE(testing::MatricesNear(path.poses.back().p_W, Vector3(1.5, 0.0, 1.5), 1e-12));
  bool crossed_lengthwise = false;
  for (const AssemblyPose& pose : path.poses) {
    // The truth, by brute force: every unit's sphere clear of every wall voxel centre.
    EXPECT_GE(testing::NearestUnitToPoints(a, pose, wall), a.unit_radius_m) << "at " << pose.p_W.transpose();
    if (pose.p_W.x() > -0.1 && pose.p_W.x() < 0.3) {
      crossed_lengthwise = std::abs(std::sin(pose.yaw_rad)) < 1e-9;
    }
  }
  EXPECT_TRUE(crossed_lengthwise);
  EXPECT_GT(path.length_m, 2.9);
}

TEST(AssemblyAStar, TheAttitudeCostTurnsARowAlongItsFlightInOpenSpace) {
  const Assembly a = testing::MarsAssembly("4x1");
  const perception::VoxelMap map = WallWithGap(100.0);  // no wall
  const RotorVector eta = RotorVector::Ones(16);
  AssemblyAStarOptions o = Band();
  const AssemblyPath aware = FindAssemblyPath(map, a, eta, {Vector3(-1.5, 0.0, 1.5), 0.5 * kPi}, Vector3(1.5, 0.0, 1.5), o);
  o.attitude_weight = 0.0;  // shape only
  const AssemblyPath shape_only = FindAssemblyPath(map, a, eta, {Vector3(-1.5, 0.0, 1.5), 0.5 * kPi}, Vector3(1.5, 0.0, 1.5), o);
  ASSERT_EQ(aware.status, AssemblyPathStatus::kFound);
  ASSERT_EQ(shape_only.status, AssemblyPathStatus::kFound);
  EXPECT_NEAR(std::sin(aware.poses.back().yaw_rad), 0.0, 1e-9);          // turned lengthwise
  EXPECT_NEAR(std::sin(shape_only.poses.back().yaw_rad), 1.0, 1e-9);     // no reason to turn
  EXPECT_LT(aware.attitude_deviation_rad, shape_only.attitude_deviation_rad);
}

TEST(AssemblyAStar, NoPathThroughAGapNarrowerThanTheRowIsWideAndClearStatuses) {
  const Assembly a = testing::MarsAssembly("4x1");  // 0.3 m wide
  const RotorVector eta = RotorVector::Ones(16);
  const perception::VoxelMap narrow = WallWithGap(0.25);
  const AssemblyPath none = FindAssemblyPath(narrow, a, eta, {Vector3(-1.5, 0.0, 1.5), 0.0}, Vector3(1.5, 0.0, 1.5), Band());
  EXPECT_EQ(none.status, AssemblyPathStatus::kNoPath);
  EXPECT_GT(none.expansions, 0);
  EXPECT_EQ(FindAssemblyPath(narrow, a, eta, {Vector3(0.1, 1.0, 1.5), 0.0}, Vector3(1.5, 0.0, 1.5), Band()).status,
            AssemblyPathStatus::kStartBlocked);
  EXPECT_EQ(FindAssemblyPath(narrow, a, eta, {Vector3(-1.5, 0.0, 1.5), 0.0}, Vector3(0.1, 1.5, 1.5), Band()).status,
            AssemblyPathStatus::kGoalBlocked);
  AssemblyAStarOptions few = Band();
  few.max_expansions = 10;
  EXPECT_EQ(FindAssemblyPath(narrow, a, eta, {Vector3(-1.5, 0.0, 1.5), 0.0}, Vector3(1.5, 0.0, 1.5), few).status,
            AssemblyPathStatus::kExpansionLimit);
  few.yaw_bins = 0;
  RG_EXPECT_THROW_WITH(FindAssemblyPath(narrow, a, eta, {}, Vector3::Zero(), few), ValidationError, "yaw_bins = 0");
  perception::VoxelMapOptions thin;
  thin.inflation_radius_m = 0.1;
  RG_EXPECT_THROW_WITH(FindAssemblyPath(perception::VoxelMap(thin), a, eta, {}, Vector3::Zero(), Band()),
                       std::invalid_argument, "inflation_radius_m");
}

}  // namespace
}  // namespace rotorguard::modular

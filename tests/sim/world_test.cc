#include "rotorguard/sim/world.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace rotorguard::sim {
namespace {

TEST(World, BoxDistanceMatchesClosedForms) {
  Box b{Vector3(1, 2, 3), Vector3(2, 4, 6), 0.0};
  EXPECT_EQ(b.Distance(Vector3(1, 2, 3)), 0.0);               // centre
  EXPECT_NEAR(b.Distance(Vector3(3, 2, 3)), 1.0, 1e-15);      // beyond the +x face
  EXPECT_NEAR(b.Distance(Vector3(3, 5, 3)), std::hypot(1.0, 1.0), 1e-15);  // off an edge
  // Rotated 90 degrees: the 2 m side now lies along y.
  Box r{Vector3(0, 0, 0), Vector3(2, 4, 1), M_PI / 2};
  EXPECT_NEAR(r.Distance(Vector3(0, 1.5, 0)), 0.5, 1e-12);
  EXPECT_NEAR(r.Distance(Vector3(2.5, 0, 0)), 0.5, 1e-12);
}

TEST(World, CylinderDistanceMatchesClosedForms) {
  Cylinder c{Eigen::Vector2d(0, 0), 0.5, 4.0};
  EXPECT_NEAR(c.Distance(Vector3(2, 0, 1)), 1.5, 1e-15);
  EXPECT_NEAR(c.Distance(Vector3(0, 0, 5)), 1.0, 1e-15);   // above the top
  EXPECT_NEAR(c.Distance(Vector3(1.5, 0, 6)), std::hypot(1.0, 2.0), 1e-15);
  EXPECT_EQ(c.Distance(Vector3(0.1, 0.1, 2)), 0.0);
}

TEST(World, MovingBoxFollowsItsWaypointsAtConstantSpeed) {
  MovingBox m;
  m.waypoints_m = {Vector3(0, 0, 1), Vector3(4, 0, 1), Vector3(4, 3, 1)};
  m.speed_m_s = 2.0;
  m.loop = true;  // closing leg back to the start is 5 m: the loop is 12 m, 6 s
  EXPECT_NEAR((m.At(1.0).center_m - Vector3(2, 0, 1)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((m.At(2.5).center_m - Vector3(4, 1, 1)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((m.At(6.0).center_m - Vector3(0, 0, 1)).norm(), 0.0, 1e-12);
  m.loop = false;
  EXPECT_NEAR((m.At(100.0).center_m - Vector3(4, 3, 1)).norm(), 0.0, 1e-12);
}

TEST(World, MovingBoxRestsAtItsFirstWaypointUntilItsStartTime) {
  MovingBox m;
  m.waypoints_m = {Vector3(0, 0, 1), Vector3(4, 0, 1)};
  m.speed_m_s = 2.0;
  m.loop = false;
  m.start_s = 10.0;
  EXPECT_EQ(m.At(0.0).center_m, Vector3(0, 0, 1));
  EXPECT_EQ(m.At(10.0).center_m, Vector3(0, 0, 1));
  EXPECT_NEAR((m.At(11.0).center_m - Vector3(2, 0, 1)).norm(), 0.0, 1e-12);
  EXPECT_EQ(m.At(20.0).center_m, Vector3(4, 0, 1));
}

TEST(World, SphereCollisionNamesTheObstacle) {
  World w;
  w.boxes.push_back(Box{Vector3(5, 0, 1), Vector3(1, 1, 2), 0.0});
  w.cylinders.push_back(Cylinder{Eigen::Vector2d(0, 5), 0.2, 5.0});
  EXPECT_FALSE(w.SphereCollision(Vector3(0, 0, 1), 0.2, 0.0));
  EXPECT_EQ(*w.SphereCollision(Vector3(4.4, 0, 1), 0.2, 0.0), "box 0");
  EXPECT_EQ(*w.SphereCollision(Vector3(0, 4.7, 1), 0.2, 0.0), "cylinder 0");
  EXPECT_FALSE(w.SphereCollision(Vector3(0, 4.5, 1), 0.2, 0.0));  // 0.3 m from the trunk
}

TEST(World, DistanceToSurfaceIsTheNearestOfGroundAndObstacles) {
  World w;
  w.boxes.push_back({Vector3(5, 0, 1), Vector3(2, 2, 2), 0.0});
  MovingBox m;
  m.size_m = Vector3(1, 1, 1);
  m.waypoints_m = {Vector3(0, 5, 3), Vector3(10, 5, 3)};
  m.speed_m_s = 1.0;
  m.loop = false;
  w.moving_boxes.push_back(m);
  EXPECT_DOUBLE_EQ(w.DistanceToSurface(Vector3(0, 0, 0.7), 0.0), 0.7);           // the ground
  EXPECT_DOUBLE_EQ(w.DistanceToSurface(Vector3(3.5, 0, 1.5), 0.0), 0.5);         // the box's face
  EXPECT_DOUBLE_EQ(w.DistanceToSurface(Vector3(4, 5, 4.0), 4.0), 0.5);           // the moving box at t = 4 s
  EXPECT_DOUBLE_EQ(w.DistanceToSurface(Vector3(4, 5, 4.0), 0.0), std::hypot(3.5, 0.5));  // it has not come yet
  // Without the ground: the box's face x = 4 from (0, 0, 0.7).
  EXPECT_DOUBLE_EQ(w.DistanceToObstacles(Vector3(0, 0, 0.7), 0.0), 4.0);
  EXPECT_DOUBLE_EQ(w.DistanceToObstacles(Vector3(4, 5, 4.0), 4.0), 0.5);
  EXPECT_EQ(World{}.DistanceToObstacles(Vector3::Zero(), 0.0), std::numeric_limits<double>::infinity());
}

}  // namespace
}  // namespace rotorguard::sim

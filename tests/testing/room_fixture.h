#pragma once
/// A room for LiDAR tests: four 1 m thick walls (one of them yawed) around an 8 x 6 x 3 m floor,
/// and a pillar.
#include "rotorguard/sim/world.h"

namespace rotorguard::testing {

inline sim::World Room() {
  sim::World w;
  w.boxes = {{Vector3(4.5, 0, 1.5), Vector3(1, 8, 3), 0.0},
             {Vector3(-4.5, 0, 1.5), Vector3(1, 8, 3), 0.0},
             {Vector3(0, 3.5, 1.5), Vector3(10, 1, 3), 0.3},
             {Vector3(0, -3.5, 1.5), Vector3(10, 1, 3), 0.0}};
  w.cylinders = {{Eigen::Vector2d(1.5, 1.0), 0.2, 3.0}};
  return w;
}

}  // namespace rotorguard::testing

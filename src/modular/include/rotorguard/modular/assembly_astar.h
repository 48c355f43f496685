#pragma once
/// Paper 002, Sec. III-1: the dynamically feasible A* (Algorithm 1). It searches over
/// (x, y, z, psi) for an assembly, checks the assembly's footprint unit by unit against the map,
/// and adds eq. (9)'s attitude cost: the distance of the node's yaw from the optimal attitude of
/// eqs. (7)-(8), the yaw at which the remaining rotors give the most torque about the axis that
/// accelerates the assembly along its direction of flight.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rotorguard/core/types.h"
#include "rotorguard/modular/assembly.h"
#include "rotorguard/perception/voxel_map.h"

namespace rotorguard::modular {

/// A position of the assembly's centre of mass and its yaw (the search's node; roll and pitch are
/// the controller's).
struct AssemblyPose {
  Vector3 p_W = Vector3::Zero();
  double yaw_rad = 0.0;
};

/// Eqs. (7)-(8) for a level assembly at `yaw_rad`, flying along the horizontal `direction_W`:
/// tau_max+- . C_tau with C_tau = [1, 1, -1, -1]. In the path frame (x along the direction),
/// tau_max+- = [tau_y-, tau_x+, tau_y+, tau_x-] are the largest torques of each sign the rotors can
/// give (each at eta_k T_bar_k, eq. 8's u_a^max), so the objective is the roll span minus the pitch
/// span: the smaller, the more of the assembly's torque turns it about the axis that accelerates
/// it along the path. `eta` is each rotor's effectiveness (a dead unit adds nothing).
double AttitudeObjective(const Assembly& assembly, const RotorVector& eta, double yaw_rad,
                         const Eigen::Vector2d& direction_W);

/// Eq. (7): the yaws among `yaw_bins` equally spaced ones (from 0) that minimise AttitudeObjective
/// within 1e-9 (several for symmetric shapes: a 4x1 row is as good either way round).
std::vector<double> OptimalYaws(const Assembly& assembly, const RotorVector& eta, const Eigen::Vector2d& direction_W,
                                int yaw_bins);

struct AssemblyAStarOptions {
  double resolution_m = 0.1;   ///< grid cell edge [m], > 0
  int yaw_bins = 24;           ///< yaw steps per turn (15 deg), in [1, 360]
  double z_min_m = 0.5;        ///< altitude band of the centre of mass [m]
  double z_max_m = 2.5;
  /// L_Phi of eq. (9b): path cost per radian of yaw away from the optimal attitude [m/rad], >= 0.
  /// 0 is the shape-only search (the baseline's front end).
  double attitude_weight = 0.3;
  double yaw_step_cost_m = 0.05;  ///< path cost of one yaw step turned in place [m], >= 0
  int max_expansions = 400000;    ///< >= 1
  void Validate() const;
};

enum class AssemblyPathStatus { kFound, kStartBlocked, kGoalBlocked, kNoPath, kExpansionLimit };
const char* ToString(AssemblyPathStatus status);

struct AssemblyPath {
  AssemblyPathStatus status = AssemblyPathStatus::kNoPath;
  std::vector<AssemblyPose> poses;  ///< start to goal, one per grid move (when found)
  int expansions = 0;
  double length_m = 0.0;              ///< of the centre of mass's path
  double attitude_deviation_rad = 0.0;  ///< eq. (12b)'s sum of |psi* - psi| along the poses
};

/// The footprint's signed-distance check at its sample points, the unit centres: true when one lies
/// in `map`'s inflated layer (occupied voxels grown by the map's inflation radius, at least the
/// unit's collision radius: the units' spheres overlap, so they cover the assembly) or outside its
/// window (a plan stays where the map knows the world).
bool FootprintCollides(const perception::VoxelMap& map, const Assembly& assembly, const AssemblyPose& pose);

/// Algorithm 1: from `start` to within half a cell of `goal` (any yaw), on `map`'s inflated layer
/// (unknown space is free; the inflation radius must cover a unit's collision sphere, else
/// std::invalid_argument). Position moves to the 26 neighbours keep the yaw; yaw moves turn one
/// bin in place. F = G + H + J_Phi, with G the path length (plus the yaw steps), H the distance
/// to the goal and J_Phi = L_Phi |psi* - psi| for the direction of the move into the node.
AssemblyPath FindAssemblyPath(const perception::VoxelMap& map, const Assembly& assembly, const RotorVector& eta,
                              const AssemblyPose& start, const Vector3& goal, const AssemblyAStarOptions& options);

}  // namespace rotorguard::modular

#pragma once
/// Modular aerial robot systems (paper 002): n identical quadrotor units docked rigidly on a planar
/// grid. An assembly is itself a multirotor with 4n rotors, so it flies in the same simulator and
/// through the same controllers as a single vehicle: geometry as data.
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::modular {

/// [m]: the largest docking distance; a unit's frame is a metre or less across.
inline constexpr double kMaxSpacingM = 10.0;

/// Where the units sit: cell (i, j) of a grid whose pitch is the docking distance; unit k is at
/// (i, j) * spacing_m along the assembly's body x and y before the centre of mass is subtracted.
struct AssemblySpec {
  std::string name;
  vehicle::VehicleParams unit;       ///< every unit's parameters (its own frame: FLU, CoG at origin)
  double spacing_m = 0.0;            ///< centre-to-centre distance of two docked units [m], <= kMaxSpacingM
  std::vector<Eigen::Vector2i> slots;  ///< one grid cell per unit, in unit order (paper's No. k+1)
  /// Throws ValidationError naming the field: a valid unit, at least one slot, no two units in
  /// one cell, 4 n rotors within kMaxRotors, a spacing that keeps neighbouring rotors apart.
  void Validate() const;
};

/// The docked assembly as one rigid multirotor.
struct Assembly {
  std::string name;
  int num_units = 0;
  int rotors_per_unit = 0;
  /// Mass, inertia about the assembly's centre of mass (parallel-axis theorem), drag, and the 4n
  /// rotors with positions relative to that centre; rotor r belongs to unit r / rotors_per_unit.
  vehicle::VehicleParams vehicle;
  std::vector<Vector3> unit_position_B;  ///< each unit's centre relative to the assembly's CoM [m]
  std::vector<Eigen::Vector2i> slots;    ///< the grid cells, as in the spec
  double unit_radius_m = 0.0;            ///< each unit's collision sphere (the unit's collision_radius_m)
  vehicle::VehicleParams unit;           ///< the spec's unit, for assemblies built from this one
  double spacing_m = 0.0;                ///< the spec's docking distance [m]

  int UnitOfRotor(int rotor) const { return rotor / rotors_per_unit; }
  /// Failed rotors the assembly flies on with reallocation: all but one unit's worth (4n - 4).
  int FailedRotorAllowance() const { return vehicle.num_rotors() - rotors_per_unit; }
  /// First rotor index of unit `unit_index`.
  int FirstRotor(int unit_index) const { return unit_index * rotors_per_unit; }
};

/// One rigid part of a composed vehicle: a vehicle (rotors, inertia, spheres about its own centre
/// of gravity) and where that centre lies in the composed body's frame. Parts keep the body's
/// orientation (a grid of docked units).
struct RigidPart {
  const vehicle::VehicleParams* params = nullptr;
  Vector3 cog_B = Vector3::Zero();
};

/// The vehicle of rigidly joined `parts` about their common centre of gravity, which `*cog_B`
/// (when given) receives in the parts' frame: masses, drag and yaw damping summed, inertia by the
/// parallel-axis theorem, every rotor and a sphere per part (its collision radius about its centre)
/// moved to that centre. What one number holds for the whole vehicle (the motors' time constants)
/// is the parts' mean; the rest (k_n, the feet, the propellers' radius) is the first part's.
/// Throws std::invalid_argument without a part.
vehicle::VehicleParams ComposeVehicle(const std::vector<RigidPart>& parts, const std::string& name,
                                      Vector3* cog_B = nullptr);

/// Builds the assembly of `spec` (validated): ComposeVehicle of its identical units. Units keep their own drag and yaw damping (summed);
/// the collision radius covers every unit's sphere.
Assembly BuildAssembly(const AssemblySpec& spec);

/// Grid cells of the named shapes of paper 002: "3x1", "4x1", "3x2", "3x3" (full), "3x3_plus"
/// (the five cells of a plus in a 3x3 grid, centre first). Throws std::invalid_argument otherwise.
std::vector<Eigen::Vector2i> ShapeSlots(const std::string& shape);

}  // namespace rotorguard::modular

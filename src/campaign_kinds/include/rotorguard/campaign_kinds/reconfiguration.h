#pragma once
/// Self-reconfiguration in flight (paper 002, Sec. IV-B): a unit separates from a hovering
/// assembly, flies as its own vehicle with its own stack to another slot, and docks there. Each
/// body is its own simulator and flight stack while apart; at separation and docking the truth
/// state is split or merged (positions and velocities of the bodies' centres of mass, momentum
/// conserved at docking) and the stacks of the new bodies start from their sensors.
///
/// The assembly's attitude deviation and acceleration around the two events are measured for the
/// reallocation that prepares the separation (the split allocation blended in beforehand, so that
/// nothing acts through the latch when it opens) and for a naive switch (the min-variance
/// allocation up to the release).
///
/// Each unit is drawn about its file once (docs/truth.md) and every body is made of its units'
/// draws: masses, moments and centres of gravity composed (modular::ComposeVehicle), each rotor
/// its unit's, the sensors, ESCs and computation delay of the body's first unit.
#include <string>

#include <Eigen/Core>

#include "rotorguard/harness/scenario.h"

namespace rotorguard::benchmarks {

struct ReconfigurationOptions {
  /// An assembly hovering with controller assembly (configs/scenarios/mars_reconfigure_3x1.yaml):
  /// vehicle, sensors, stack, faults (injected from the start and known to the controller).
  harness::Scenario base;
  int unit = 0;                                  ///< the unit that separates (index)
  Eigen::Vector2i target_slot = Eigen::Vector2i(1, 1);  ///< the free grid cell it docks at
  double separate_s = 5.0;   ///< the latch opens [s], after a steady window
  double blend_s = 0.5;      ///< the split allocation is blended in over this long before [s], > 0
  bool naive = false;        ///< the naive switch: no blend
  double transfer_speed_m_s = 0.3;  ///< the unit's speed on its way (up, across, down) [m/s], > 0
  double climb_m = 0.35;            ///< how high above the assembly it crosses [m], > 0
  double dock_tolerance_m = 0.03;   ///< docking when this close to the slot ... [m], > 0
  double dock_speed_m_s = 0.1;      ///< ... and this slow relative to the assembly [m/s], > 0
  /// The docking camera: within this range of its slot [m] the unit measures where the slot is
  /// relative to itself (markers on the assembly), each axis with this noise [m], at this rate
  /// [Hz]; its guidance moves the unit's path onto the measured slot through a first-order lag of
  /// this time constant [s]. Each body's odometry drifts on its own in the drawn world (about
  /// 0.1 m apart after the transfer): without a relative measurement the unit misses its slot.
  double dock_camera_range_m = 0.6;
  double dock_camera_noise_m = 0.005;
  double dock_camera_rate_hz = 30.0;
  double dock_guidance_time_constant_s = 0.5;
  double hold_s = 4.0;              ///< flown after docking [s], > 0
  double window_s = 2.0;            ///< attitude and acceleration measured this long after each event [s]
  /// Throws std::invalid_argument naming the field.
  void Validate() const;
};

struct ReconfigurationResult {
  bool success = false;
  std::string failure;
  double separation_s = 0.0, docking_s = -1.0;
  /// Largest tilt of the remaining assembly's body z from where it pointed just before the
  /// window, from blend start (or the release) to window_s after [deg].
  double separation_max_attitude_deg = 0.0;
  double docking_max_attitude_deg = 0.0;  ///< the same for the docked assembly after docking
  /// Largest acceleration of the assembly's centre of mass in those windows [m/s^2] (hover: ~0),
  /// each its velocity's change over 20 ms.
  double separation_max_accel_m_s2 = 0.0;
  double docking_max_accel_m_s2 = 0.0;
  double unit_max_tilt_deg = 0.0;  ///< the travelling unit's largest tilt
  /// The same attitude figure over an equally long window of steady hover before the separation
  /// is prepared: the floor that sensor noise and the fault's compensation set.
  double steady_max_attitude_deg = 0.0;
  double steady_max_accel_m_s2 = 0.0;  ///< the acceleration's floor, the same way
};

ReconfigurationResult RunReconfiguration(const ReconfigurationOptions& options);

}  // namespace rotorguard::benchmarks

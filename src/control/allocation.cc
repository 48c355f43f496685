#include "rotorguard/control/allocation.h"

#include <fmt/format.h>

#include <algorithm>

#include "rotorguard/control/dense_qp.h"
#include "rotorguard/core/error.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::control {

PseudoInverseAllocator::PseudoInverseAllocator(const vehicle::MultirotorModel& model)
    : pinv_(vehicle::PseudoInverse(model.effectiveness())), max_thrust_(model.max_thrust()) {}

bool PseudoInverseAllocator::Allocate(const Eigen::Vector4d& wrench, RotorVector* thrust) const {
  *thrust = pinv_ * wrench;
  bool unsaturated = true;
  for (int i = 0; i < thrust->size(); ++i) {
    const double clipped = std::clamp((*thrust)[i], 0.0, max_thrust_[i]);
    unsaturated = unsaturated && clipped == (*thrust)[i];
    (*thrust)[i] = clipped;
  }
  return unsaturated;
}

std::optional<RotorVector> HoverThrustSplit(const vehicle::VehicleParams& vehicle, const std::vector<bool>& failed) {
  const int n = vehicle.num_rotors();
  if (static_cast<int>(failed.size()) != n) {
    ThrowInvalidArgument("HoverThrustSplit", "failed.size()", failed.size(), fmt::format("{} (one per rotor)", n));
  }
  // min 1/2 |T|^2  s.t.  [thrust; roll; pitch] rows of the effectiveness matrix T = [W; 0; 0],
  // 0 <= T_i <= max (0 when failed): a strictly convex QP, infeasible exactly when no split exists.
  DenseQp qp(n, 3);  // H = I, g = 0
  qp.lb.setZero();
  for (int i = 0; i < n; ++i) qp.ub[i] = failed[static_cast<std::size_t>(i)] ? 0.0 : vehicle.rotors[i].max_thrust_n;
  qp.C = vehicle::ComputeEffectivenessMatrix(vehicle.rotors).topRows<3>();
  qp.lc << vehicle.weight_n(), 0.0, 0.0;
  qp.uc = qp.lc;
  ActiveSetOptions options;
  options.feasibility_tolerance = 1e-9 * vehicle.weight_n();
  DenseQpSolver solver(n, 3, options);
  if (!solver.Solve(qp).IsSolutionUsable()) return std::nullopt;
  return RotorVector(solver.z());
}

}  // namespace rotorguard::control

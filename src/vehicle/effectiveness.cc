#include "rotorguard/vehicle/effectiveness.h"

#include <Eigen/Dense>
#include <stdexcept>

namespace rotorguard::vehicle {

EffectivenessMatrix ComputeEffectivenessMatrix(const std::vector<Rotor>& rotors) {
  EffectivenessMatrix m(4, static_cast<int>(rotors.size()));
  for (int i = 0; i < static_cast<int>(rotors.size()); ++i) {
    const Rotor& r = rotors[i];
    m(0, i) = 1.0;
    m(1, i) = r.p_B.y();
    m(2, i) = -r.p_B.x();
    m(3, i) = r.yaw_sign() * r.yaw_coefficient_m;
  }
  return m;
}

AllocationMatrix PseudoInverse(const EffectivenessMatrix& m) {
  const Eigen::Matrix4d mmt = m * m.transpose();
  Eigen::LDLT<Eigen::Matrix4d> ldlt(mmt);
  const double scale = mmt.diagonal().maxCoeff();
  if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 1e-12 * scale) {
    throw std::invalid_argument(
        "PseudoInverse: effectiveness matrix is rank deficient; the rotors cannot produce "
        "independent thrust, roll, pitch and yaw torques");
  }
  return m.transpose() * ldlt.solve(Eigen::Matrix4d::Identity());
}

}  // namespace rotorguard::vehicle

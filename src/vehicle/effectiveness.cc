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

std::vector<int> DiagonalTwins(const std::vector<Rotor>& rotors, int rotor) {
  const Eigen::Vector2d p = rotors.at(static_cast<std::size_t>(rotor)).p_B.head<2>();
  std::vector<int> twins;
  for (int j = 0; j < static_cast<int>(rotors.size()); ++j) {
    if (j != rotor && (rotors[j].p_B.head<2>() + p).norm() < 0.05 * p.norm()) twins.push_back(j);
  }
  return twins;
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

#pragma once
/// Fixed-size views of an OCP QP's stage matrices, shared by its two solvers (ocp_qp.cc,
/// riccati_qp.cc). Sizes known at compile time make Eigen's small products several times faster,
/// so the NMPC's quadrotor (nx = 17, nu = 4) gets its own instantiation; other sizes use Dynamic.
#include <Eigen/Core>

#include "rotorguard/control/ocp_qp.h"

namespace rotorguard::control::internal {

/// True for the sizes with a fixed-size instantiation.
inline bool IsNmpcSize(const OcpQpDims& dims) { return dims.nx == 17 && dims.nu == 4; }

/// A stage's A_k, B_k, Q_k and R_k as maps of NX x NX, NX x NU, NX x NX, NU x NU (NX, NU when known
/// at compile time, else Dynamic).
template <int NX, int NU>
struct StageMaps {
  const OcpQp& qp;
  int nx, nu;
  Eigen::Map<const Eigen::Matrix<double, NX, NX>> A(int k) const { return {qp.A[k].data(), nx, nx}; }
  Eigen::Map<const Eigen::Matrix<double, NX, NU>> B(int k) const { return {qp.B[k].data(), nx, nu}; }
  Eigen::Map<const Eigen::Matrix<double, NX, NX>> Q(int k) const { return {qp.Q[k].data(), nx, nx}; }
  Eigen::Map<const Eigen::Matrix<double, NU, NU>> R(int k) const { return {qp.R[k].data(), nu, nu}; }
};

}  // namespace rotorguard::control::internal

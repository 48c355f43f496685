#pragma once
/// Oracles for the OCP QP solvers' tests, independent of the solvers' recursions: random problems,
/// the problem condensed the naive way (explicit products), and its KKT conditions.
#include <Eigen/Core>
#include <vector>

#include "rotorguard/control/ocp_qp.h"
#include "rotorguard/core/rng.h"

namespace rotorguard::control {

Eigen::MatrixXd RandomMatrix(int r, int c, Rng& rng, double scale = 1.0);

/// A random time-varying OCP QP with state bounds on `bounded` and input bounds that bind.
OcpQp RandomOcp(int N, int nx, int nu, std::vector<int> bounded, Rng& rng);

/// RandomOcp with mild dynamics from a small start and a cost that pulls states 0 and 3 to +-4,
/// beyond the bounds' +-1.5, so that state bounds bind.
OcpQp OcpPulledAgainstItsStateBounds(int N, int nx, int nu, std::vector<int> bounded, Rng& rng);

/// States of a trajectory at their +-1.5 bound (stages 1..N, the bounded indices).
int StateBoundsAtTheirLimit(const std::vector<Eigen::VectorXd>& x, const std::vector<int>& bounded);

/// Condensing done the naive way: the prediction matrix built from explicit products, the Hessian
/// as Gamma' Qbig Gamma + Rbig. An oracle independent of the solver's recursions.
void NaiveCondense(const OcpQp& qp, Eigen::MatrixXd* H, Eigen::VectorXd* g, Eigen::MatrixXd* C, Eigen::VectorXd* lc,
                   Eigen::VectorXd* uc);

/// Checks (gtest expectations) the KKT conditions of `qp`, condensed the naive way, at the inputs
/// u (N nu) with the multipliers yu of their bounds and yx of the state bounds (N nbx, stages
/// 1..N): feasibility, stationarity H u + g = yu + C' yx, and multipliers that are zero off their
/// bounds and of the right sign on them (positive at a lower bound). For a strictly convex QP they
/// define the optimum. Returns the number of bounds active at the point.
int ExpectKktOfTheNaiveCondensing(const OcpQp& qp, const Eigen::VectorXd& u, const Eigen::VectorXd& yu,
                                  const Eigen::VectorXd& yx);

}  // namespace rotorguard::control

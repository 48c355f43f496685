#pragma once
/// The NMPC's prediction model: paper 000's eqs. (1)-(3) and (6) for a healthy multirotor without
/// wind (rotor failures enter the OCP as input bounds, not as model changes), its analytic
/// Jacobians, and an RK4 discretisation with exact sensitivities (forward mode through the stages).
#include <Eigen/Core>

#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::control {

/// State layout as vehicle::StateIndex: [p (3), q (4: w, x, y, z), v (3), w (3), T (n)].
class NmpcModel {
 public:
  explicit NmpcModel(const vehicle::VehicleParams& params);
  int nx() const { return 13 + nu_; }
  int nu() const { return nu_; }
  const vehicle::VehicleParams& params() const { return params_; }

  /// x_dot = f(x, u); `u` are commanded thrusts (not saturated: the OCP bounds them).
  void Dynamics(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_dot) const;
  /// f and its Jacobians df/dx (nx x nx) and df/du (nx x nu).
  void DynamicsWithJacobians(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_dot,
                             Eigen::MatrixXd* fx, Eigen::MatrixXd* fu) const;
  /// DynamicsWithJacobians for a caller that keeps its Jacobians: writes only the entries the
  /// model's structure can make nonzero. `fx` (nx x nx) and `fu` (nx x nu) must be zero elsewhere,
  /// as after DynamicsWithJacobians or a previous call.
  void UpdateDynamicsWithJacobians(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_dot,
                                   Eigen::MatrixXd* fx, Eigen::MatrixXd* fu) const;
  /// out = fx * M for an fx of DynamicsWithJacobians, using its block sparsity (about a quarter of
  /// the dense product's work): p_dot depends on v only, q_dot on q and w, v_dot on q, v and T,
  /// w_dot on w and T, T_dot on T.
  void MultiplyStateJacobian(const Eigen::MatrixXd& fx, const Eigen::MatrixXd& M, Eigen::MatrixXd* out) const;

 private:
  vehicle::VehicleParams params_;
  int nu_;
  Eigen::Matrix3d inertia_, inertia_inv_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> torque_map_;  // rows 1..3 of the effectiveness matrix
  Eigen::Matrix<double, 3, Eigen::Dynamic> alpha_map_;   // I^-1 torque_map_
};

/// One RK4 step of NmpcModel over `dt` with `substeps` equal sub-steps, input held, and the exact
/// sensitivities A = dx+/dx, B = dx+/du of the discrete map. Owns its scratch memory.
class Rk4Sensitivity {
 public:
  Rk4Sensitivity(const NmpcModel& model, double dt, int substeps);
  /// x_next = F(x, u); with A and B when they are not null.
  void Step(const Eigen::VectorXd& x, const Eigen::VectorXd& u, Eigen::VectorXd* x_next,
            Eigen::MatrixXd* A = nullptr, Eigen::MatrixXd* B = nullptr);

 private:
  const NmpcModel& model_;
  double h_;
  int substeps_;
  Eigen::VectorXd k_[4], xs_, xtmp_;
  // The sensitivities to x and u side by side, [d/dx d/du] without the position columns (nx x
  // (nx - 3 + nu)): one structured product per stage. Nothing in the model depends on the
  // position, so d/dp stays [I; 0] through every stage and is not propagated.
  Eigen::MatrixXd fx_, fu_, dk_[4], ab_, abtmp_;
};

}  // namespace rotorguard::control

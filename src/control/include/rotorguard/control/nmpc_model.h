#pragma once
/// The NMPC's prediction model: paper 000's eqs. (1)-(3) and (6) for the vehicle file's multirotor
/// (rotor failures enter the OCP as input bounds), corrected by what the stack has learnt in flight
/// (ModelCorrection), its analytic Jacobians, and an RK4 discretisation with exact sensitivities
/// (forward mode through the stages).
#include <Eigen/Core>

#include "rotorguard/vehicle/vehicle_params.h"

namespace rotorguard::control {

/// What the model learns in flight, so that its predictions are offset-free where the file is
/// wrong (docs/control.md, "Offset-free NMPC"): each rotor's effectiveness eta_i (its thrust and
/// torque are eta_i T_i: a partial loss, or 0 for a rotor given up), and the constant world-frame
/// acceleration and body-frame angular acceleration the file's model misses (mass, centre of
/// gravity, thrust coefficients, an external force or torque), added to eqs. (1) and (3).
struct ModelCorrection {
  Eigen::VectorXd effectiveness;                                     ///< one entry per rotor in [0, 1]; empty: all 1
  Eigen::Vector3d acceleration_W = Eigen::Vector3d::Zero();          ///< [m/s²]
  Eigen::Vector3d angular_acceleration_B = Eigen::Vector3d::Zero();  ///< [rad/s²]
};

/// State layout as vehicle::StateIndex: [p (3), q (4: w, x, y, z), v (3), w (3), T (n)].
class NmpcModel {
 public:
  explicit NmpcModel(const vehicle::VehicleParams& params);
  int nx() const { return 13 + nu_; }
  int nu() const { return nu_; }
  const vehicle::VehicleParams& params() const { return params_; }

  /// SetEffectiveness and SetDisturbance together. Throws std::invalid_argument as they do;
  /// nothing changes then.
  void SetCorrection(const ModelCorrection& correction);
  /// Each rotor's effectiveness (empty: all 1). Throws std::invalid_argument for the wrong size
  /// or an entry outside [0, 1].
  void SetEffectiveness(const Eigen::VectorXd& effectiveness);
  /// The constant accelerations alone, without allocating (every control cycle). Throws
  /// std::invalid_argument for a non-finite one.
  void SetDisturbance(const Eigen::Vector3d& acceleration_W, const Eigen::Vector3d& angular_acceleration_B);
  const ModelCorrection& correction() const { return correction_; }
  /// The rotor effectiveness in use (all 1 unless corrected).
  const Eigen::VectorXd& effectiveness() const { return correction_.effectiveness; }
  /// The uncorrected accelerations of x: v_dot and w_dot of eqs. (1) and (3) with the rotor
  /// effectiveness but without the constant accelerations (what a disturbance observer compares
  /// with the measurement).
  void ModelAccelerations(const Eigen::VectorXd& x, Eigen::Vector3d* a_W, Eigen::Vector3d* alpha_B) const;

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
  ModelCorrection correction_;                           // its effectiveness always has nu_ entries
  Eigen::Matrix<double, 3, Eigen::Dynamic> alpha_map_;  // I^-1 torque_map_ diag(eta)
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

// Oracle test: the NMPC iterated to convergence against Ipopt on the same discretised OCP
// (multiple shooting, RK4 nodes, the NMPC's own node costs and bounds). Ipopt is an independent
// interior-point NLP solver; it shares only the problem definition with the NMPC.
#include <cmath>
#include <memory>

#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>
#include <gtest/gtest.h>

#include "rotorguard/control/nmpc.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/vehicle/multirotor.h"
#include "vehicle_fixture.h"

namespace rotorguard::control {
namespace {

using Ipopt::Index;
using Ipopt::Number;
using vehicle::StateIndex;

/// The OCP as an Ipopt NLP: variables [x_0, u_0, x_1, u_1, ..., x_N], constraints x_0 = x_hat and
/// F(x_k, u_k) - x_{k+1} = 0, bounds 0 <= u <= u_bar and |w_k| <= w_max for k >= 1.
class OcpNlp : public Ipopt::TNLP {
 public:
  OcpNlp(const NmpcController& nmpc, const NmpcModel& model, const ReferenceTrajectory& ref, Eigen::VectorXd x_hat,
         Eigen::VectorXd u_guess)
      : nmpc_(nmpc),
        rk4_(model, nmpc.options().step_s, nmpc.options().integrator_substeps),
        ref_(ref),
        x_hat_(std::move(x_hat)),
        u_guess_(std::move(u_guess)),
        N_(nmpc.options().horizon_steps),
        nx_(model.nx()),
        nu_(model.nu()) {}

  int X(int k) const { return k * (nx_ + nu_); }
  int U(int k) const { return k * (nx_ + nu_) + nx_; }
  int num_variables() const { return N_ * (nx_ + nu_) + nx_; }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override {
    n = num_variables();
    m = (N_ + 1) * nx_;
    nnz_jac_g = nx_ + N_ * (nx_ * nx_ + nx_ * nu_ + nx_);
    nnz_h_lag = 0;
    style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    for (Index i = 0; i < n; ++i) {
      x_l[i] = -1e20;
      x_u[i] = 1e20;
    }
    const Eigen::VectorXd& u_max = nmpc_.input_upper_bounds();
    const Eigen::Vector3d w_max = nmpc_.options().max_rate_rad_s;
    for (int k = 0; k <= N_; ++k) {
      if (k > 0) {
        for (int i = 0; i < 3; ++i) {
          x_l[X(k) + StateIndex::kBodyRate + i] = -w_max[i];
          x_u[X(k) + StateIndex::kBodyRate + i] = w_max[i];
        }
      }
      if (k < N_) {
        for (int i = 0; i < nu_; ++i) {
          x_l[U(k) + i] = 0.0;
          x_u[U(k) + i] = u_max[i];
        }
      }
    }
    for (Index i = 0; i < m; ++i) g_l[i] = g_u[i] = 0.0;
    return true;
  }

  bool get_starting_point(Index n, bool, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    for (Index i = 0; i < n; ++i) x[i] = 0.0;
    for (int k = 0; k <= N_; ++k) {
      for (int i = 0; i < nx_; ++i) x[X(k) + i] = x_hat_[i];
      if (k < N_) {
        for (int i = 0; i < nu_; ++i) x[U(k) + i] = u_guess_[i];
      }
    }
    return true;
  }

  Eigen::Map<const Eigen::VectorXd> Xk(const Number* z, int k) const { return {z + X(k), nx_}; }
  Eigen::Map<const Eigen::VectorXd> Uk(const Number* z, int k) const { return {z + U(k), nu_}; }

  bool eval_f(Index, const Number* z, bool, Number& f) override {
    f = 0.0;
    for (int k = 0; k <= N_; ++k) {
      const Eigen::VectorXd x = Xk(z, k);
      const Eigen::VectorXd u = k < N_ ? Eigen::VectorXd(Uk(z, k)) : Eigen::VectorXd();
      f += nmpc_.NodeCost(x, k < N_ ? &u : nullptr, ref_.Evaluate(k * nmpc_.options().step_s), nullptr, nullptr);
    }
    return true;
  }

  bool eval_grad_f(Index n, const Number* z, bool, Number* grad) override {
    for (Index i = 0; i < n; ++i) grad[i] = 0.0;
    Eigen::VectorXd gx, gu;
    for (int k = 0; k <= N_; ++k) {
      const Eigen::VectorXd x = Xk(z, k);
      const Eigen::VectorXd u = k < N_ ? Eigen::VectorXd(Uk(z, k)) : Eigen::VectorXd();
      nmpc_.NodeCost(x, k < N_ ? &u : nullptr, ref_.Evaluate(k * nmpc_.options().step_s), &gx, &gu);
      for (int i = 0; i < nx_; ++i) grad[X(k) + i] = gx[i];
      if (k < N_) {
        for (int i = 0; i < nu_; ++i) grad[U(k) + i] = gu[i];
      }
    }
    return true;
  }

  bool eval_g(Index, const Number* z, bool, Index, Number* g) override {
    Eigen::Map<Eigen::VectorXd>(g, nx_) = Xk(z, 0) - x_hat_;
    Eigen::VectorXd next;
    for (int k = 0; k < N_; ++k) {
      rk4_.Step(Xk(z, k), Uk(z, k), &next);
      Eigen::Map<Eigen::VectorXd>(g + (k + 1) * nx_, nx_) = next - Xk(z, k + 1);
    }
    return true;
  }

  bool eval_jac_g(Index, const Number* z, bool, Index, Index, Index* row, Index* col, Number* values) override {
    int e = 0;
    if (values == nullptr) {
      for (int i = 0; i < nx_; ++i, ++e) {
        row[e] = i;
        col[e] = X(0) + i;
      }
      for (int k = 0; k < N_; ++k) {
        const int r0 = (k + 1) * nx_;
        for (int i = 0; i < nx_; ++i) {
          for (int j = 0; j < nx_; ++j, ++e) {
            row[e] = r0 + i;
            col[e] = X(k) + j;
          }
          for (int j = 0; j < nu_; ++j, ++e) {
            row[e] = r0 + i;
            col[e] = U(k) + j;
          }
          row[e] = r0 + i;
          col[e] = X(k + 1) + i;
          ++e;
        }
      }
      return true;
    }
    for (int i = 0; i < nx_; ++i) values[e++] = 1.0;
    Eigen::VectorXd next;
    Eigen::MatrixXd A, B;
    for (int k = 0; k < N_; ++k) {
      rk4_.Step(Xk(z, k), Uk(z, k), &next, &A, &B);
      for (int i = 0; i < nx_; ++i) {
        for (int j = 0; j < nx_; ++j) values[e++] = A(i, j);
        for (int j = 0; j < nu_; ++j) values[e++] = B(i, j);
        values[e++] = -1.0;
      }
    }
    return true;
  }

  bool eval_h(Index, const Number*, bool, Number, Index, const Number*, bool, Index, Index*, Index*, Number*) override {
    return false;  // limited-memory quasi-Newton
  }

  void finalize_solution(Ipopt::SolverReturn status, Index n, const Number* z, const Number*, const Number*, Index,
                         const Number*, const Number*, Number obj, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    status_ = status;
    objective_ = obj;
    solution_ = Eigen::Map<const Eigen::VectorXd>(z, n);
  }

  Ipopt::SolverReturn status_ = Ipopt::INTERNAL_ERROR;
  double objective_ = 0.0;
  Eigen::VectorXd solution_;

 private:
  const NmpcController& nmpc_;
  Rk4Sensitivity rk4_;
  const ReferenceTrajectory& ref_;
  Eigen::VectorXd x_hat_, u_guess_;
  int N_, nx_, nu_;
};

struct OracleCase {
  StateEstimate estimate;
  std::unique_ptr<ReferenceTrajectory> reference;
};

OracleCase RandomCase(Rng& rng) {
  OracleCase c;
  c.estimate.valid = true;
  c.estimate.p_W = Vector3(rng.Uniform(-0.8, 0.8), rng.Uniform(-0.8, 0.8), 1.5 + rng.Uniform(-0.5, 0.5));
  c.estimate.v_W = Vector3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-0.5, 0.5));
  const Vector3 axis = Vector3(rng.Normal(), rng.Normal(), 0.0).normalized();
  c.estimate.q_WB = QuaternionFromYaw(rng.Uniform(-0.5, 0.5)) * Quaternion(Eigen::AngleAxisd(rng.Uniform(0.0, 0.3), axis));
  c.estimate.w_B = Vector3(rng.Uniform(-1, 1), rng.Uniform(-1, 1), rng.Uniform(-1, 1));
  c.estimate.motor_thrust_n = RotorVector::Constant(4, 2.82) + 0.5 * RotorVector::Random(4);
  if (rng.Uniform() < 0.5) {
    planning::HoverOptions o;
    o.position_m = Vector3(0, 0, 1.5);
    c.reference = std::make_unique<planning::HoverReference>(o);
  } else {
    planning::LemniscateOptions o;
    o.center_m = Vector3(0, 0, 1.5);
    o.max_speed_m_s = 1.0;
    o.ramp_s = 0.0;
    c.reference = std::make_unique<planning::LemniscateReference>(o);
  }
  return c;
}

void ExpectMatchesIpopt(int failed_rotor, std::uint64_t seed) {
  Rng rng(seed);
  const vehicle::VehicleParams vehicle = rotorguard::testing::ReferenceQuad();
  NmpcModel model(vehicle);
  for (int trial = 0; trial < 6; ++trial) {
    const OracleCase c = RandomCase(rng);
    NmpcOptions o;
    o.max_sqp_iterations = 200;
    o.sqp_tolerance = 1e-10;
    NmpcController nmpc(vehicle, o);
    if (failed_rotor >= 0) nmpc.SetRotorFailed(failed_rotor);
    RotorVector cmd;
    nmpc.Compute(c.estimate, *c.reference, 0.0, 0.0, &cmd);
    ASSERT_EQ(nmpc.summary().status, NmpcStatus::kSolved) << nmpc.summary().BriefReport();
    // The same prediction model: a failed rotor's effectiveness is 0, and the disturbance
    // observer's first estimate (zero) is in it.
    model.SetCorrection(nmpc.model_correction());

    // The NMPC's converged objective, from the same node costs.
    const auto& xs = nmpc.planned_states();
    const auto& us = nmpc.planned_inputs();
    double cost = 0.0;
    for (int k = 0; k <= o.horizon_steps; ++k) {
      cost += nmpc.NodeCost(xs[k], k < o.horizon_steps ? &us[k] : nullptr, c.reference->Evaluate(k * o.step_s),
                            nullptr, nullptr);
    }
    Eigen::VectorXd x_hat(17);
    x_hat << c.estimate.p_W, c.estimate.q_WB.w(), c.estimate.q_WB.x(), c.estimate.q_WB.y(), c.estimate.q_WB.z(),
        c.estimate.v_W, c.estimate.w_B, c.estimate.motor_thrust_n;
    Ipopt::SmartPtr<OcpNlp> nlp = new OcpNlp(nmpc, model, *c.reference, x_hat, nmpc.ThrustReference(1.15 * kGravity));
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
    app->Options()->SetNumericValue("tol", 1e-10);
    app->Options()->SetNumericValue("acceptable_tol", 1e-9);
    app->Options()->SetIntegerValue("max_iter", 3000);
    app->Options()->SetIntegerValue("print_level", 0);
    app->Options()->SetStringValue("sb", "yes");
    app->Options()->SetStringValue("hessian_approximation", "limited-memory");
    app->Options()->SetIntegerValue("limited_memory_max_history", 50);
    ASSERT_EQ(app->Initialize(), Ipopt::Solve_Succeeded);
    const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
    // "Search direction too small" is Ipopt at its precision limit with the quasi-Newton Hessian;
    // the comparison below decides whether that point is the optimum.
    ASSERT_TRUE(status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level ||
                status == Ipopt::Search_Direction_Becomes_Too_Small)
        << "Ipopt status " << status << " (trial " << trial << ")";
    EXPECT_NEAR(cost, nlp->objective_, 1e-4 * std::abs(nlp->objective_)) << "trial " << trial;
    double input_error = 0.0;
    for (int k = 0; k < o.horizon_steps; ++k) {
      input_error = std::max(input_error, (us[k] - nlp->solution_.segment(nlp->U(k), 4)).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(input_error, 1e-3) << "trial " << trial;
  }
}

TEST(NmpcOracle, ConvergedSolutionMatchesIpoptNominal) { ExpectMatchesIpopt(-1, 101); }

TEST(NmpcOracle, ConvergedSolutionMatchesIpoptWithRotor0BoundedToZero) { ExpectMatchesIpopt(0, 202); }

}  // namespace
}  // namespace rotorguard::control

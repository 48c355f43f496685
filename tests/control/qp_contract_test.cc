// The contract every QP solver of the project keeps, one typed suite for all: DenseQpSolver (on the
// OCP QP condensed the naive way) and RiccatiQpSolver, the two factorisations under the shared
// active-set core (active_set.h), and CondensingQpSolver, DenseQpSolver's OCP front end.
//  - The returned point satisfies the KKT conditions of the naively condensed QP (for the solvers
//    that report multipliers) and equals Ipopt's solution of the same QP (an interior-point method,
//    exact Hessian, tolerance 1e-12: an independent solver), on random problems with input and
//    state bounds binding; and a problem whose solution is known in closed form.
//  - Warm starts reach the cold solution, in fewer active-set changes over a sequence of nearby
//    problems (the NMPC's calls).
//  - Crossed bounds and state bounds no admissible input reaches are reported infeasible; NaN data
//    and an indefinite Hessian are a numerical failure with finite outputs; the iteration cap holds.
//  - A solve allocates nothing once the solver has solved a problem of its size (where allocations
//    are counted).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "ocp_qp_oracle.h"
#include "rotorguard/control/dense_qp.h"
#include "rotorguard/control/ocp_qp.h"
#include "rotorguard/control/riccati_qp.h"
#include "rotorguard/core/rng.h"
#ifdef ROTORGUARD_COUNTS_ALLOCATIONS
#include "allocation_counter.h"
#endif

namespace rotorguard::control {
namespace {

using Ipopt::Index;
using Ipopt::Number;

/// minimise 1/2 z'Hz + g'z subject to lb <= z <= ub, lc <= Cz <= uc, as an Ipopt NLP.
class DenseQpNlp : public Ipopt::TNLP {
 public:
  explicit DenseQpNlp(const DenseQp& qp) : qp_(qp), z_(Eigen::VectorXd::Zero(qp.num_variables())) {}
  const Eigen::VectorXd& z() const { return z_; }
  Ipopt::SolverReturn status() const { return status_; }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag, IndexStyleEnum& style) override {
    n = qp_.num_variables();
    m = qp_.num_constraints();
    nnz_jac_g = n * m;
    nnz_h_lag = n * (n + 1) / 2;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) override {
    const auto finite = [](double v) { return std::clamp(v, -1e20, 1e20); };  // Ipopt's infinity
    for (Index i = 0; i < n; ++i) {
      x_l[i] = finite(qp_.lb[i]);
      x_u[i] = finite(qp_.ub[i]);
    }
    for (Index i = 0; i < m; ++i) {
      g_l[i] = finite(qp_.lc[i]);
      g_u[i] = finite(qp_.uc[i]);
    }
    return true;
  }
  bool get_starting_point(Index n, bool, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    std::fill(x, x + n, 0.0);
    return true;
  }
  bool eval_f(Index n, const Number* x, bool, Number& f) override {
    const Eigen::Map<const Eigen::VectorXd> z(x, n);
    f = 0.5 * z.dot(qp_.H * z) + qp_.g.dot(z);
    return true;
  }
  bool eval_grad_f(Index n, const Number* x, bool, Number* grad) override {
    Eigen::Map<Eigen::VectorXd>(grad, n) = qp_.H * Eigen::Map<const Eigen::VectorXd>(x, n) + qp_.g;
    return true;
  }
  bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override {
    if (m > 0) Eigen::Map<Eigen::VectorXd>(g, m) = qp_.C * Eigen::Map<const Eigen::VectorXd>(x, n);
    return true;
  }
  bool eval_jac_g(Index n, const Number*, bool, Index m, Index, Index* rows, Index* cols, Number* values) override {
    for (Index i = 0, k = 0; i < m; ++i) {
      for (Index j = 0; j < n; ++j, ++k) {
        if (values == nullptr) {
          rows[k] = i;
          cols[k] = j;
        } else {
          values[k] = qp_.C(i, j);
        }
      }
    }
    return true;
  }
  bool eval_h(Index n, const Number*, bool, Number obj_factor, Index, const Number*, bool, Index, Index* rows,
              Index* cols, Number* values) override {
    for (Index i = 0, k = 0; i < n; ++i) {
      for (Index j = 0; j <= i; ++j, ++k) {
        if (values == nullptr) {
          rows[k] = i;
          cols[k] = j;
        } else {
          values[k] = obj_factor * qp_.H(i, j);
        }
      }
    }
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn status, Index n, const Number* x, const Number*, const Number*, Index,
                         const Number*, const Number*, Number, const Ipopt::IpoptData*,
                         Ipopt::IpoptCalculatedQuantities*) override {
    status_ = status;
    z_ = Eigen::Map<const Eigen::VectorXd>(x, n);
  }

 private:
  const DenseQp& qp_;
  Eigen::VectorXd z_;
  Ipopt::SolverReturn status_ = Ipopt::INTERNAL_ERROR;
};

/// The OCP QP condensed the naive way into a DenseQp over the inputs, its state bounds as rows.
DenseQp Condensed(const OcpQp& qp) {
  const int N = qp.dims.horizon, nu = qp.dims.nu, nbx = static_cast<int>(qp.dims.state_bound_index.size());
  DenseQp dense(N * nu, N * nbx);
  NaiveCondense(qp, &dense.H, &dense.g, &dense.C, &dense.lc, &dense.uc);
  for (int k = 0; k < N; ++k) {
    dense.lb.segment(k * nu, nu) = qp.u_lower[k];
    dense.ub.segment(k * nu, nu) = qp.u_upper[k];
  }
  return dense;
}

/// Ipopt's inputs for the QP (exact Hessian, tolerance 1e-12).
Eigen::VectorXd IpoptSolution(const OcpQp& qp) {
  const DenseQp dense = Condensed(qp);
  Ipopt::SmartPtr<DenseQpNlp> nlp = new DenseQpNlp(dense);
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetNumericValue("tol", 1e-12);
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetStringValue("hessian_constant", "yes");
  app->Options()->SetStringValue("jac_c_constant", "yes");
  app->Options()->SetStringValue("jac_d_constant", "yes");
  EXPECT_EQ(app->Initialize(), Ipopt::Solve_Succeeded);
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  EXPECT_TRUE(status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level) << "Ipopt " << status;
  return nlp->z();
}

/// What every solver under the contract reports, in the condensed QP's terms: the inputs u (N nu)
/// and, where the solver has them, the multipliers of the input bounds and of the state bounds.
struct Solution {
  QpStatus status = QpStatus::kNotSolved;
  QpStart start = QpStart::kCold;
  int iterations = 0;
  Eigen::VectorXd u, yu, yx;
};

/// DenseQpSolver on the naively condensed QP.
class DenseUnderContract {
 public:
  static constexpr bool kHasMultipliers = true;
  DenseUnderContract(const OcpQpDims& dims, const ActiveSetOptions& options)
      : nu_(dims.horizon * dims.nu),
        nbx_(dims.horizon * static_cast<int>(dims.state_bound_index.size())),
        solver_(nu_, nbx_, options),
        dense_(nu_, nbx_) {
    solution_.u.resize(nu_);
    solution_.yu.resize(nu_);
    solution_.yx.resize(nbx_);
  }
  /// Condenses (allocating); Solve solves what was loaded.
  void Load(const OcpQp& qp) { dense_ = Condensed(qp); }
  const Solution& Solve() {
    const DenseQpSummary& s = solver_.Solve(dense_);
    solution_.status = s.status;
    solution_.start = s.start;
    solution_.iterations = s.iterations;
    solution_.u = solver_.z();
    solution_.yu = solver_.bound_multipliers();
    solution_.yx = solver_.constraint_multipliers();
    return solution_;
  }

 private:
  int nu_, nbx_;
  DenseQpSolver solver_;
  DenseQp dense_;
  Solution solution_;
};

/// An OcpQpSolver on the stage-form QP; multipliers where the solver reports them.
template <typename S>
class OcpUnderContract {
 public:
  static constexpr bool kHasMultipliers = std::is_same_v<S, RiccatiQpSolver>;
  OcpUnderContract(const OcpQpDims& dims, const ActiveSetOptions& options) : dims_(dims), solver_(dims, options) {
    const int nbx = static_cast<int>(dims.state_bound_index.size());
    solution_.u.resize(dims.horizon * dims.nu);
    solution_.yu.setZero(dims.horizon * dims.nu);
    solution_.yx.setZero(dims.horizon * nbx);
  }
  void Load(const OcpQp& qp) { qp_ = qp; }
  const Solution& Solve() {
    const OcpQpSummary& s = solver_.Solve(qp_);
    solution_.status = s.status;
    solution_.start = s.start;
    solution_.iterations = s.iterations;
    const int N = dims_.horizon, nu = dims_.nu, nbx = static_cast<int>(dims_.state_bound_index.size());
    for (int k = 0; k < N; ++k) {
      solution_.u.segment(k * nu, nu) = solver_.u()[k];
      if constexpr (kHasMultipliers) {
        solution_.yu.segment(k * nu, nu) = solver_.input_multipliers()[k];
        solution_.yx.segment(k * nbx, nbx) = solver_.state_multipliers()[k + 1];
      }
    }
    return solution_;
  }

 private:
  OcpQpDims dims_;
  S solver_;
  OcpQp qp_{dims_};
  Solution solution_;
};

template <typename T>
class QpContract : public ::testing::Test {};
using SolversUnderContract =
    ::testing::Types<DenseUnderContract, OcpUnderContract<RiccatiQpSolver>, OcpUnderContract<CondensingQpSolver>>;
class SolverNames {
 public:
  template <typename T>
  static std::string GetName(int) {
    if constexpr (std::is_same_v<T, DenseUnderContract>) return "DenseQpSolver";
    if constexpr (std::is_same_v<T, OcpUnderContract<RiccatiQpSolver>>) return "RiccatiQpSolver";
    return "CondensingQpSolver";
  }
};
TYPED_TEST_SUITE(QpContract, SolversUnderContract, SolverNames);

/// Solves `qp` cold with a new solver of the type under test.
template <typename T>
Solution SolveCold(const OcpQp& qp, ActiveSetOptions options = {}) {
  options.warm_start = false;
  T solver(qp.dims, options);
  solver.Load(qp);
  return solver.Solve();
}

TYPED_TEST(QpContract, SolutionsSatisfyTheKktConditionsAndEqualIpopts) {
  Rng rng(41);
  int binding = 0;
  for (int trial = 0; trial < 12; ++trial) {
    SCOPED_TRACE(::testing::Message() << "trial " << trial);
    // Input bounds bind in the first kind (random dynamics with state bounds are mostly
    // infeasible), input and state bounds in the second; the third is the NMPC's size (the
    // compile-time-sized code paths).
    const OcpQp qp = trial % 3 == 0   ? RandomOcp(8, 5, 2, {}, rng)
                     : trial % 3 == 1 ? OcpPulledAgainstItsStateBounds(10, 6, 3, {0, 3}, rng)
                                      : OcpPulledAgainstItsStateBounds(12, 17, 4, {0, 3, 10}, rng);
    const Solution s = SolveCold<TypeParam>(qp);
    ASSERT_EQ(s.status, QpStatus::kSolved);
    ASSERT_TRUE(s.u.allFinite());
    if constexpr (TypeParam::kHasMultipliers) {
      binding += ExpectKktOfTheNaiveCondensing(qp, s.u, s.yu, s.yx);
    }
    const Eigen::VectorXd ipopt = IpoptSolution(qp);
    EXPECT_LE((s.u - ipopt).cwiseAbs().maxCoeff(), 1e-6) << "against Ipopt";
  }
  if constexpr (TypeParam::kHasMultipliers) {
    EXPECT_GT(binding, 40) << "the problems must exercise the bounds";
  }
}

TYPED_TEST(QpContract, SolvesAProblemWithAClosedFormSolutionExactly) {
  // x_{k+1} = b u_k + c_k with A = 0, diagonal Q, R and b: each input component minimises its own
  // scalar quadratic 1/2 (Q (b u + c)² + R u²) + q (b u + c) + r u, so the solution is that
  // quadratic's minimiser clipped to the input's bounds intersected with those its state's bounds
  // imply, (x_lower - c) / b <= u <= (x_upper - c) / b for b > 0.
  const int N = 6, n = 3;
  OcpQp qp(OcpQpDims{N, n, n, {0, 1, 2}});
  Rng rng(7);
  Eigen::VectorXd expected(N * n);
  qp.x0.setOnes();
  for (int k = 0; k < N; ++k) {
    qp.A[k].setZero();
    qp.B[k] = Eigen::Vector3d(1.0, 0.5, 2.0).asDiagonal();
    qp.c[k] = Eigen::VectorXd::Constant(n, 0.1 * k);
    qp.R[k] = Eigen::Vector3d(1.0, 2.0, 0.5).asDiagonal();
    qp.r[k] = RandomMatrix(n, 1, rng);
    qp.u_lower[k].setConstant(-0.7);
    qp.u_upper[k].setConstant(0.9);
  }
  for (int k = 0; k <= N; ++k) {
    qp.Q[k] = Eigen::Vector3d(3.0, 1.0, 0.2).asDiagonal();
    qp.q[k] = 4.0 * RandomMatrix(n, 1, rng);
    qp.x_lower[k].setConstant(-1.2);
    qp.x_upper[k].setConstant(0.8);
  }
  int clipped = 0;
  for (int k = 0; k < N; ++k) {
    for (int i = 0; i < n; ++i) {
      const double b = qp.B[k](i, i), c = qp.c[k][i], Q = qp.Q[k + 1](i, i), R = qp.R[k](i, i);
      const double free = -(Q * b * c + qp.q[k + 1][i] * b + qp.r[k][i]) / (Q * b * b + R);
      const double lower = std::max(qp.u_lower[k][i], (qp.x_lower[k + 1][i] - c) / b);
      const double upper = std::min(qp.u_upper[k][i], (qp.x_upper[k + 1][i] - c) / b);
      expected[k * n + i] = std::clamp(free, lower, upper);
      clipped += expected[k * n + i] != free;
    }
  }
  ASSERT_GE(clipped, 6) << "the case must make bounds bind";
  ASSERT_LE(clipped, N * n - 4) << "and leave some free";
  const Solution s = SolveCold<TypeParam>(qp);
  ASSERT_EQ(s.status, QpStatus::kSolved);
  EXPECT_LE((s.u - expected).cwiseAbs().maxCoeff(), 1e-12);
  if constexpr (TypeParam::kHasMultipliers) {
    ExpectKktOfTheNaiveCondensing(qp, s.u, s.yu, s.yx);
  }
}

TYPED_TEST(QpContract, WarmStartsReachTheColdSolutionInFewerIterations) {
  // A sequence of QPs with the initial state and the cost moving a little, as the NMPC's calls:
  // started from the previous active set, the solution is the cold one.
  Rng rng(47);
  const OcpQp base = OcpPulledAgainstItsStateBounds(10, 6, 3, {0, 3}, rng);
  TypeParam warm(base.dims, {});
  int warm_iterations = 0, cold_iterations = 0;
  for (int step = 0; step < 10; ++step) {
    SCOPED_TRACE(::testing::Message() << "step " << step);
    OcpQp qp = base;
    qp.x0 = base.x0 + 0.02 * step * Eigen::VectorXd::Ones(6);
    for (int k = 0; k <= 10; ++k) qp.q[k] += 0.01 * step * Eigen::VectorXd::Ones(6);
    warm.Load(qp);
    const Solution w = warm.Solve();
    const Solution c = SolveCold<TypeParam>(qp);
    ASSERT_EQ(w.status, QpStatus::kSolved);
    ASSERT_EQ(c.status, QpStatus::kSolved);
    EXPECT_EQ(w.start, step == 0 ? QpStart::kCold : QpStart::kWarm);
    EXPECT_EQ(c.start, QpStart::kCold);
    EXPECT_LE((w.u - c.u).cwiseAbs().maxCoeff(), 1e-9);
    if (step > 0) {
      warm_iterations += w.iterations;
      cold_iterations += c.iterations;
    }
  }
  EXPECT_LT(warm_iterations, cold_iterations / 2);
}

TYPED_TEST(QpContract, ReportsInfeasibilityAndBadDataWithFiniteOutputs) {
  Rng rng(59);
  const OcpQp base = OcpPulledAgainstItsStateBounds(5, 4, 2, {0}, rng);
  TypeParam solver(base.dims, {});
  const auto expect = [&](const OcpQp& qp, QpStatus status, const char* what) {
    solver.Load(qp);
    const Solution& s = solver.Solve();
    EXPECT_EQ(s.status, status) << what;
    EXPECT_TRUE(s.u.allFinite()) << what;
  };
  {
    OcpQp qp = base;
    qp.u_lower[2][1] = 1.0;
    qp.u_upper[2][1] = 0.5;
    expect(qp, QpStatus::kInfeasible, "crossed bounds");
  }
  {  // x_1 depends on u_0 alone, |u_0| <= 0.6
    OcpQp qp = base;
    const double reachable = (qp.A[0] * qp.x0 + qp.c[0])[0] + qp.B[0].row(0).cwiseAbs().sum() * 0.6;
    qp.x_lower[1][0] = reachable + 1.0;
    qp.x_upper[1][0] = reachable + 2.0;
    expect(qp, QpStatus::kInfeasible, "a state bound no admissible input reaches");
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int bad = 0; bad < 4; ++bad) {
    OcpQp qp = base;
    if (bad == 0) qp.A[3](1, 2) = nan;
    if (bad == 1) qp.u_lower[0][0] = nan;
    if (bad == 2) qp.x0[1] = nan;
    if (bad == 3) qp.q[2][0] = nan;
    expect(qp, QpStatus::kNumericalFailure, "NaN data");
  }
  {
    OcpQp qp = base;
    qp.R[4] = -Eigen::MatrixXd::Identity(2, 2);
    qp.Q[5].setZero();
    expect(qp, QpStatus::kNumericalFailure, "an indefinite Hessian");
  }
  expect(base, QpStatus::kSolved, "solvable again after the failures");
}

TYPED_TEST(QpContract, StopsAtTheIterationCap) {
  Rng rng(43);
  const OcpQp qp = OcpPulledAgainstItsStateBounds(10, 6, 3, {0, 3}, rng);
  const Solution free = SolveCold<TypeParam>(qp);
  ASSERT_EQ(free.status, QpStatus::kSolved);
  ASSERT_GT(free.iterations, 3);
  ActiveSetOptions capped;
  capped.max_iterations = 3;
  const Solution s = SolveCold<TypeParam>(qp, capped);
  EXPECT_EQ(s.status, QpStatus::kMaxIterations);
  EXPECT_EQ(s.iterations, 3);
  EXPECT_TRUE(s.u.allFinite());
}

#ifdef ROTORGUARD_COUNTS_ALLOCATIONS
TYPED_TEST(QpContract, SolvesAllocateNothing) {
  Rng rng(53);
  const OcpQp base = OcpPulledAgainstItsStateBounds(12, 17, 4, {0, 3, 10}, rng);
  TypeParam solver(base.dims, {});
  EXPECT_GT(rotorguard::testing::CountAllocations([] { Eigen::VectorXd v(100); v.setZero(); }), 0)
      << "the counter must see an allocation";
  long allocations = 0;
  for (int step = 0; step < 6; ++step) {
    OcpQp qp = base;
    qp.x0 += 0.01 * step * Eigen::VectorXd::Ones(17);
    solver.Load(qp);  // not counted: the adaptor's copy or condensing
    const long n = rotorguard::testing::CountAllocations([&] {
      const Solution& s = solver.Solve();
      EXPECT_EQ(s.status, QpStatus::kSolved);
    });
    if (step > 0) allocations += n;  // the first solve may size what is sized lazily
  }
  EXPECT_EQ(allocations, 0);
}
#endif

}  // namespace
}  // namespace rotorguard::control

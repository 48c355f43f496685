
#include <cmath>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/modular/allocation.h"
#include "rotorguard/vehicle/effectiveness.h"
#include "assembly_fixture.h"
#include "test_util.h"

namespace rotorguard::modular {
namespace {

/// Independent oracle for  min 1/2 |t|^2  s.t.  B t = w,  lo <= t <= hi: the dual. For a multiplier
/// lambda the box-constrained minimiser is t(lambda) = clip(B' lambda, lo, hi), and the concave dual
/// d(lambda) = min_t 1/2|t|^2 - lambda'(B t - w) has gradient w - B t(lambda) and (generalised)
/// Hessian -B D B' with D the unclipped entries: Newton with backtracking on |w - B t| finds the
/// multiplier, and t(lambda) is then the primal optimum (strong duality).
Eigen::VectorXd DualOracle(const Eigen::MatrixXd& B, const Eigen::Vector4d& w, const Eigen::VectorXd& lo,
                           const Eigen::VectorXd& hi) {
  const auto primal = [&](const Eigen::Vector4d& l) {
    return Eigen::VectorXd((B.transpose() * l).cwiseMax(lo).cwiseMin(hi));
  };
  Eigen::Vector4d lambda = (B * B.transpose()).ldlt().solve(w);
  for (int it = 0; it < 200; ++it) {
    const Eigen::VectorXd t = primal(lambda);
    const Eigen::Vector4d r = w - B * t;
    if (r.norm() < 1e-13) break;
    Eigen::MatrixXd D = Eigen::MatrixXd::Zero(t.size(), t.size());
    const Eigen::VectorXd u = B.transpose() * lambda;
    for (int k = 0; k < t.size(); ++k) D(k, k) = (u[k] > lo[k] && u[k] < hi[k]) ? 1.0 : 0.0;
    const Eigen::Matrix4d H = B * D * B.transpose() + 1e-12 * Eigen::Matrix4d::Identity();
    const Eigen::Vector4d step = H.ldlt().solve(r);
    double a = 1.0;
    while (a > 1e-10 && (w - B * primal(lambda + a * step)).norm() >= r.norm()) a *= 0.5;
    lambda += a * step;
  }
  return primal(lambda);
}

double Variance(const Eigen::VectorXd& t) { return (t.array() - t.mean()).square().mean(); }

/// The delivered thrusts of the rotors that deliver (eta > 0) and their bounds.
struct Delivered {
  Eigen::MatrixXd B;
  Eigen::VectorXd t, hi;
};
Delivered DeliveredBy(const Assembly& a, const RotorVector& eta, const RotorVector& command) {
  const EffectivenessMatrix B = vehicle::ComputeEffectivenessMatrix(a.vehicle.rotors);
  std::vector<int> alive;
  for (int k = 0; k < eta.size(); ++k)
    if (eta[k] > 0.0) alive.push_back(k);
  Delivered d{Eigen::MatrixXd(4, alive.size()), Eigen::VectorXd(alive.size()), Eigen::VectorXd(alive.size())};
  for (std::size_t j = 0; j < alive.size(); ++j) {
    d.B.col(j) = B.col(alive[j]);
    d.t[j] = eta[alive[j]] * command[alive[j]];
    d.hi[j] = eta[alive[j]] * a.vehicle.rotors[alive[j]].max_thrust_n;
  }
  return d;
}

TEST(AssemblyAllocator, FaultFreeIsTheMinimumNormAllocationWhenNothingSaturates) {
  const Assembly a = testing::MarsAssembly("3x2");
  AssemblyAllocator alloc(a, {});
  const Eigen::Vector4d w(a.vehicle.weight_n() * 1.1, 0.2, -0.3, 0.05);
  RotorVector u;
  ASSERT_TRUE(alloc.Allocate(w, &u).attainable);
  // The minimum-norm solution of B t = w by an independent factorisation.
  const Eigen::MatrixXd B = vehicle::ComputeEffectivenessMatrix(a.vehicle.rotors);
  const Eigen::VectorXd expected = B.completeOrthogonalDecomposition().solve(w);
  EXPECT_TRUE(testing::MatricesNear(u, expected, 1e-10));
}

TEST(AssemblyAllocator, FullReallocationMatchesTheDualOracleUnderTableOneFaults) {
  const Assembly a = testing::MarsAssembly("3x2");
  AssemblyAllocator alloc(a, {});
  Rng rng(7);
  for (const std::vector<int>& half : std::vector<std::vector<int>>{{5}, {4, 5}, {4, 5, 6}}) {
    RotorVector eta = RotorVector::Ones(24);
    for (const int k : half) eta[k] = 0.5;  // unit No. 2 (index 1), rotors 1, 2 (paper's eta_{2,1..})
    alloc.SetEffectiveness(eta);
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::Vector4d w(a.vehicle.weight_n() * rng.Uniform(0.6, 1.6), rng.Uniform(-1.0, 1.0),
                              rng.Uniform(-1.0, 1.0), rng.Uniform(-0.15, 0.15));
      RotorVector u;
      const AllocationSummary& s = alloc.Allocate(w, &u);
      ASSERT_TRUE(s.attainable) << trial;
      const Delivered d = DeliveredBy(a, eta, u);
      EXPECT_TRUE(testing::MatricesNear(d.B * d.t, w, 1e-8));
      EXPECT_GE(d.t.minCoeff(), -1e-9);
      EXPECT_TRUE(((d.hi - d.t).array() >= -1e-9).all());
      const Eigen::VectorXd oracle = DualOracle(d.B, w, Eigen::VectorXd::Zero(d.t.size()), d.hi);
      EXPECT_TRUE(testing::MatricesNear(d.t, oracle, 1e-7)) << "trial " << trial;
    }
  }
}

TEST(AssemblyAllocator, NoFeasiblePerturbationLowersTheVariance) {
  const Assembly a = testing::MarsAssembly("4x1");
  AssemblyAllocator alloc(a, {});
  RotorVector eta = RotorVector::Ones(16);
  eta.segment(12, 4).setZero();  // unit No. 4 dead: dead weight at the end of the row
  alloc.SetEffectiveness(eta);
  const Eigen::Vector4d w(a.vehicle.weight_n(), 0.0, 0.0, 0.0);
  RotorVector u;
  ASSERT_TRUE(alloc.Allocate(w, &u).attainable);
  EXPECT_TRUE(testing::MatricesNear(u.segment(12, 4), Eigen::Vector4d::Zero(), 0.0));
  const Delivered d = DeliveredBy(a, eta, u);
  // The rotors at neither bound, and the directions among them that keep B t = w: any small step
  // along those stays feasible, so none may lower the variance.
  std::vector<int> free;
  for (int k = 0; k < d.t.size(); ++k)
    if (d.t[k] > 1e-6 && d.t[k] < d.hi[k] - 1e-6) free.push_back(k);
  ASSERT_GT(free.size(), 4u);
  Eigen::MatrixXd b_free(4, free.size());
  for (std::size_t j = 0; j < free.size(); ++j) b_free.col(j) = d.B.col(free[j]);
  const Eigen::MatrixXd N = b_free.fullPivLu().kernel();
  Rng rng(3);
  const double best = Variance(d.t);
  int feasible = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::VectorXd z(N.cols());
    for (int i = 0; i < z.size(); ++i) z[i] = rng.Normal();
    const Eigen::VectorXd dz = 1e-3 * rng.Uniform() * N * z;
    Eigen::VectorXd t = d.t;
    for (std::size_t j = 0; j < free.size(); ++j) t[free[j]] += dz[j];
    if (t.minCoeff() < 0.0 || ((d.hi - t).array() < 0.0).any()) continue;
    ++feasible;
    EXPECT_GE(Variance(t), best - 1e-12);
  }
  EXPECT_GT(feasible, 1000);
}

TEST(AssemblyAllocator, BoundsHoldAndSaturatedDemandsAreReportedNotMet) {
  const Assembly a = testing::MarsAssembly("3x2");
  AssemblyAllocator alloc(a, {});
  RotorVector eta = RotorVector::Ones(24);
  // The four corner units dead: the two in the middle column cannot lift six, but they can hold
  // the attitude (they sit symmetrically about the centre of mass).
  for (const int unit : {0, 2, 3, 5}) eta.segment(4 * unit, 4).setZero();
  alloc.SetEffectiveness(eta);
  RotorVector u;
  const AllocationSummary& s = alloc.Allocate(Eigen::Vector4d(a.vehicle.weight_n(), 0, 0, 0), &u);
  EXPECT_FALSE(s.attainable);
  EXPECT_TRUE(u.allFinite());
  EXPECT_LT(s.residual[0], -0.25 * a.vehicle.weight_n());  // the thrust falls short ...
  EXPECT_LT(s.residual.segment(1, 2).cwiseAbs().maxCoeff(), 0.02);  // ... roll and pitch held first
  for (int k = 0; k < 24; ++k) {
    EXPECT_GE(u[k], 0.0);
    EXPECT_LE(u[k], a.vehicle.rotors[k].max_thrust_n + 1e-12);
  }
}

TEST(AssemblyAllocator, PartialKeepsTheFaultyUnitsNominalShareAndTheHealthyUnitsMakeUpTheRest) {
  const Assembly a = testing::MarsAssembly("3x2");
  AllocatorOptions o;
  o.method = Reallocation::kPartial;
  AssemblyAllocator partial(a, o);
  RotorVector eta = RotorVector::Ones(24);
  eta[4] = eta[5] = 0.5;
  partial.SetEffectiveness(eta);
  const Eigen::Vector4d w(a.vehicle.weight_n(), 0.1, 0.1, 0.0);
  RotorVector u;
  ASSERT_TRUE(partial.Allocate(w, &u).attainable);
  const Eigen::MatrixXd B = vehicle::ComputeEffectivenessMatrix(a.vehicle.rotors);
  const Eigen::VectorXd nominal = B.completeOrthogonalDecomposition().solve(w);
  EXPECT_TRUE(testing::MatricesNear(u.segment(4, 4), nominal.segment(4, 4), 1e-10));
  EXPECT_TRUE(testing::MatricesNear(B * eta.cwiseProduct(u), w, 1e-8));
}

TEST(AssemblyAllocator, WithoutReallocationTheFaultIsIgnoredAndTheWrenchMissed) {
  const Assembly a = testing::MarsAssembly("3x2");
  AllocatorOptions o;
  o.method = Reallocation::kNone;
  AssemblyAllocator none(a, o);
  RotorVector eta = RotorVector::Ones(24);
  eta[5] = 0.5;
  none.SetEffectiveness(eta);
  const Eigen::Vector4d w(a.vehicle.weight_n(), 0, 0, 0);
  RotorVector u;
  const AllocationSummary& s = none.Allocate(w, &u);
  EXPECT_TRUE(testing::MatricesNear(u, RotorVector::Constant(24, a.vehicle.weight_n() / 24.0), 1e-10));
  // Half of one rotor's hover thrust is missing, at its arm: roll and pitch torques appear.
  EXPECT_NEAR(s.residual[0], -0.5 * a.vehicle.weight_n() / 24.0, 1e-10);
  EXPECT_GT(s.residual.segment(1, 2).norm(), 1e-3);
}

TEST(AssemblyAllocator, BeforeASeparationTheUnitCarriesExactlyItsOwnShare) {
  const Assembly a = testing::MarsAssembly("3x1");
  AssemblyAllocator alloc(a, {});
  RotorVector eta = RotorVector::Ones(12);
  eta[5] = 0.3;  // the middle unit's rotor weakened: the min-variance allocation leans on unit No. 1
  alloc.SetEffectiveness(eta);
  const Eigen::Vector4d w(a.vehicle.weight_n() * 1.05, 0.05, -0.02, 0.01);
  const EffectivenessMatrix B = vehicle::ComputeEffectivenessMatrix(a.vehicle.rotors);
  // The unit's own wrench about its centre, from its four rotors.
  const auto unit_wrench = [&](const RotorVector& u) {
    Eigen::Vector4d f = Eigen::Vector4d::Zero();
    for (int k = 0; k < 4; ++k) {
      vehicle::Rotor r = a.vehicle.rotors[k];
      r.p_B -= a.unit_position_B[0];
      f += vehicle::ComputeEffectivenessMatrix({r}).col(0) * eta[k] * u[k];
    }
    return f;
  };
  RotorVector u;
  ASSERT_TRUE(alloc.Allocate(w, &u).attainable);
  EXPECT_GT(unit_wrench(u).segment(1, 3).norm(), 1e-3);  // min variance: torque through the latch
  alloc.SetDetaching(0, 1.0);
  ASSERT_TRUE(alloc.Allocate(w, &u).attainable);
  EXPECT_TRUE(testing::MatricesNear(unit_wrench(u), Eigen::Vector4d(w[0] / 3.0, 0, 0, 0), 1e-9));
  EXPECT_TRUE(testing::MatricesNear(B * eta.cwiseProduct(u), w, 1e-8));
  alloc.SetDetaching(0, 0.5);
  ASSERT_TRUE(alloc.Allocate(w, &u).attainable);
  EXPECT_TRUE(testing::MatricesNear(B * eta.cwiseProduct(u), w, 1e-8));
  RG_EXPECT_THROW_WITH(alloc.SetDetaching(3, 1.0), std::invalid_argument, "unit = 3");
  RG_EXPECT_THROW_WITH(alloc.SetDetaching(0, 1.5), std::invalid_argument, "blend = 1.5");
}

TEST(AssemblyAllocator, BadInputIsAClearErrorOrAFiniteFallback) {
  const Assembly a = testing::MarsAssembly("3x1");
  AssemblyAllocator alloc(a, {});
  RotorVector eta = RotorVector::Ones(12);
  eta[7] = 1.5;
  RG_EXPECT_THROW_WITH(alloc.SetEffectiveness(eta), std::invalid_argument, "eta[7] = 1.5");
  RG_EXPECT_THROW_WITH(alloc.SetEffectiveness(RotorVector::Ones(8)), std::invalid_argument, "12 rotors");
  RotorVector u;
  EXPECT_FALSE(alloc.Allocate(Eigen::Vector4d(NAN, 0, 0, 0), &u).attainable);
  EXPECT_TRUE(testing::MatricesNear(u, RotorVector::Zero(12), 0.0));
  AllocatorOptions o;
  o.priority[2] = 0.0;
  RG_EXPECT_THROW_WITH(AssemblyAllocator(a, o), ValidationError, "priority");
  EXPECT_EQ(FromName<Reallocation>("partial"), Reallocation::kPartial);
  EXPECT_FALSE(FromName<Reallocation>("hybrid").has_value());
  EXPECT_STREQ(ToName(Reallocation::kNone), "none");
}

}  // namespace
}  // namespace rotorguard::modular


#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/modular/allocation.h"
#include "rotorguard/vehicle/effectiveness.h"

namespace rotorguard::modular {

void AllocatorOptions::Validate() const {
  if (!(priority.allFinite() && priority.minCoeff() > 0.0)) {
    ThrowValidation("AllocatorOptions", "priority", "(a non-positive or non-finite weight)", "four weights > 0");
  }
  if (!(std::isfinite(regularisation) && regularisation > 0.0 && regularisation <= 1.0)) {
    ThrowValidation("AllocatorOptions", "regularisation", regularisation, "a weight in (0, 1]");
  }
  if (!(dead_eta >= 0.0 && dead_eta < 1.0)) ThrowValidation("AllocatorOptions", "dead_eta", dead_eta, "in [0, 1)");
  qp.Validate();
}

AssemblyAllocator::AssemblyAllocator(const Assembly& assembly, const AllocatorOptions& options)
    : assembly_(assembly), options_(options) {
  options_.Validate();
  B_ = vehicle::ComputeEffectivenessMatrix(assembly.vehicle.rotors);
  pinv_ = vehicle::PseudoInverse(B_);
  const int n = assembly.vehicle.num_rotors();
  max_thrust_.resize(n);
  for (int k = 0; k < n; ++k) max_thrust_[k] = assembly.vehicle.rotors[k].max_thrust_n;
  SetEffectiveness(RotorVector::Ones(n));
}

void AssemblyAllocator::SetEffectiveness(const RotorVector& eta) {
  const int n = assembly_.vehicle.num_rotors();
  if (eta.size() != n) ThrowInvalidArgument("AssemblyAllocator::SetEffectiveness", "eta.size()", eta.size(), fmt::format("{} rotors", n));
  for (int k = 0; k < n; ++k) {
    if (!(eta[k] >= 0.0 && eta[k] <= 1.0)) {
      ThrowInvalidArgument("AssemblyAllocator::SetEffectiveness", fmt::format("eta[{}]", k), eta[k], "in [0, 1]");
    }
  }
  eta_ = eta;
  unit_faulty_.assign(assembly_.num_units, false);
  std::vector<int> alive, healthy;
  for (int k = 0; k < n; ++k) {
    if (eta[k] < 1.0) unit_faulty_[assembly_.UnitOfRotor(k)] = true;
  }
  any_faulty_ = std::find(unit_faulty_.begin(), unit_faulty_.end(), true) != unit_faulty_.end();
  for (int k = 0; k < n; ++k) {
    if (eta[k] > options_.dead_eta) alive.push_back(k);
    if (!unit_faulty_[assembly_.UnitOfRotor(k)]) healthy.push_back(k);
  }
  Prepare(alive, &alive_);
  Prepare(healthy, &healthy_);
  if (detaching_ >= 0) {
    const int unit = detaching_;
    detaching_ = -1;  // re-prepared for the new effectiveness
    SetDetaching(unit, blend_);
  }
}

void AssemblyAllocator::SetDetaching(int unit, double blend) {
  if (unit < -1 || unit >= assembly_.num_units) {
    ThrowInvalidArgument("AssemblyAllocator::SetDetaching", "unit", unit,
                         fmt::format("-1 (none) or a unit in [0, {}]", assembly_.num_units - 1));
  }
  if (!(blend >= 0.0 && blend <= 1.0)) ThrowInvalidArgument("AssemblyAllocator::SetDetaching", "blend", blend, "in [0, 1]");
  blend_ = unit < 0 ? 0.0 : blend;
  if (unit == detaching_) return;
  detaching_ = unit;
  if (unit < 0) return;
  // The unit's rotors about its own centre: its own multirotor allocation.
  const auto first = assembly_.vehicle.rotors.begin() + assembly_.FirstRotor(unit);
  std::vector<vehicle::Rotor> local(first, first + assembly_.rotors_per_unit);
  for (vehicle::Rotor& r : local) r.p_B -= assembly_.unit_position_B[static_cast<std::size_t>(unit)];
  unit_pinv_ = vehicle::PseudoInverse(vehicle::ComputeEffectivenessMatrix(local));
  std::vector<int> others;
  for (const int k : alive_.cols) {
    if (assembly_.UnitOfRotor(k) != unit) others.push_back(k);
  }
  Prepare(others, &others_);
}

void AssemblyAllocator::Prepare(const std::vector<int>& cols, Subset* s) const {
  s->cols = cols;
  const int m = static_cast<int>(cols.size());
  s->exact_solver.reset();
  s->fallback_solver.reset();
  if (m == 0) return;
  Eigen::MatrixXd b(4, m);
  for (int j = 0; j < m; ++j) b.col(j) = B_.col(cols[j]);
  // Variables: the delivered thrusts t_j in [0, eta T_bar].
  s->exact = control::DenseQp(m, 4);
  s->exact.H.setIdentity();
  s->exact.g.setZero();
  s->exact.C = b;
  s->fallback = control::DenseQp(m, 0);
  const Eigen::Matrix4d W = options_.priority.asDiagonal();
  s->weighted_b = b.transpose() * W;
  s->fallback.H = s->weighted_b * b + options_.regularisation * Eigen::MatrixXd::Identity(m, m);
  for (int j = 0; j < m; ++j) {
    const double ub = eta_[cols[j]] * max_thrust_[cols[j]];
    s->exact.lb[j] = s->fallback.lb[j] = 0.0;
    s->exact.ub[j] = s->fallback.ub[j] = ub;
  }
  s->exact_solver.emplace(m, 4, options_.qp);
  s->fallback_solver.emplace(m, 0, options_.qp);
  // The Hessians depend only on which rotors deliver: factorised once here, not per call.
  s->exact_solver->Factorize(s->exact.H);
  s->fallback_solver->Factorize(s->fallback.H);
}

void AssemblyAllocator::Scatter(const Subset& s, const Eigen::VectorXd& t, RotorVector* command) const {
  for (std::size_t j = 0; j < s.cols.size(); ++j) {
    const int k = s.cols[j];
    (*command)[k] = std::clamp(t[static_cast<Eigen::Index>(j)] / eta_[k], 0.0, max_thrust_[k]);
  }
}

Eigen::VectorXd AssemblyAllocator::SolveSubset(Subset* s, const Eigen::Vector4d& w) {
  s->exact.lc = w;
  s->exact.uc = w;
  const control::DenseQpSummary& exact = s->exact_solver->SolveFactorized(s->exact);
  summary_.iterations += exact.iterations;
  summary_.status = exact.status;
  if (exact.IsSolutionUsable()) {
    summary_.attainable = true;
    return s->exact_solver->z();
  }
  // Beyond reach: the bounded thrusts closest to w in the priority's metric.
  s->fallback.g = -s->weighted_b * w;
  const control::DenseQpSummary& fb = s->fallback_solver->SolveFactorized(s->fallback);
  summary_.iterations += fb.iterations;
  summary_.status = fb.status;
  summary_.attainable = false;
  if (fb.IsSolutionUsable()) return s->fallback_solver->z();
  return Eigen::VectorXd::Zero(static_cast<Eigen::Index>(s->cols.size()));
}

const AllocationSummary& AssemblyAllocator::Allocate(const Eigen::Vector4d& wrench, RotorVector* command) {
  const Stopwatch clock;
  const int n = assembly_.vehicle.num_rotors();
  summary_ = AllocationSummary{};
  command->setZero(n);
  if (!wrench.allFinite()) {
    summary_.solve_time_s = clock.seconds();
    return summary_;
  }
  Reallocation method = options_.method;
  // Partial reallocation needs a healthy unit to hand the missing wrench to; without a fault it
  // is the full reallocation over all rotors.
  if (method == Reallocation::kPartial && (!any_faulty_ || healthy_.cols.empty())) method = Reallocation::kFull;
  if (method == Reallocation::kFull) {
    if (!alive_.cols.empty()) Scatter(alive_, SolveSubset(&alive_, wrench), command);
  } else {
    // The fault-free allocation, clipped: the method kNone, and the faulty units' share in kPartial.
    const RotorVector unclipped = pinv_ * wrench;
    const RotorVector nominal = unclipped.cwiseMax(0.0).cwiseMin(max_thrust_);
    if (method == Reallocation::kNone) {
      *command = nominal;
      summary_.attainable = (unclipped - nominal).cwiseAbs().maxCoeff() < 1e-12;
      summary_.status = control::QpStatus::kSolved;
    } else {  // kPartial: eqs. (3)-(4), then the healthy units' minimum-variance share
      Eigen::Vector4d remaining = wrench;
      for (int k = 0; k < n; ++k) {
        if (!unit_faulty_[assembly_.UnitOfRotor(k)]) continue;
        (*command)[k] = nominal[k];
        remaining -= B_.col(k) * eta_[k] * nominal[k];
      }
      Scatter(healthy_, SolveSubset(&healthy_, remaining), command);
    }
  }
  if (detaching_ >= 0 && blend_ > 0.0 && !others_.cols.empty()) {
    // The split allocation (SetDetaching), blended in: both satisfy B t = w within the bounds when
    // attainable, and so does their convex combination.
    const int first = assembly_.FirstRotor(detaching_);
    const double share = 1.0 / assembly_.num_units;  // identical units: its mass over the assembly's
    const RotorVector own = unit_pinv_ * Eigen::Vector4d(share * wrench[0], 0.0, 0.0, 0.0);
    RotorVector split = RotorVector::Zero(n);
    Eigen::Vector4d rest = wrench;
    for (int j = 0; j < assembly_.rotors_per_unit; ++j) {
      const int k = first + j;
      const double t = std::clamp(own[j], 0.0, eta_[k] * max_thrust_[k]);
      split[k] = eta_[k] > options_.dead_eta ? t / eta_[k] : 0.0;
      rest -= B_.col(k) * t;
    }
    const bool attainable = summary_.attainable;
    Scatter(others_, SolveSubset(&others_, rest), &split);
    summary_.attainable = attainable && summary_.attainable;
    *command = (1.0 - blend_) * *command + blend_ * split;
  }
  summary_.residual = B_ * eta_.cwiseProduct(*command) - wrench;
  if (!command->allFinite()) command->setZero(n);
  summary_.solve_time_s = clock.seconds();
  return summary_;
}

}  // namespace rotorguard::modular

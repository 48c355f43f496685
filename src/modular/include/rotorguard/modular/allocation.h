#pragma once
/// Fault-tolerant force/torque reallocation over an assembly's rotors (paper 002, Sec. II).
///
/// The controller asks for a wrench w = [T; tau_x; tau_y; tau_z] about the assembly's centre of
/// mass; rotor k, commanded u_k, delivers t_k = eta_k u_k with eta_k its known effectiveness
/// (eta_{i,j} of Table I: 1 healthy, 0.5 half, 0 dead). The allocation that spreads the load
/// evenly is eq. (1)/(6):
///
///   minimise Var(t)  subject to  B t = w  (force and torque balance, eqs. 1b-1d / 6b-6c),
///                                0 <= t_k <= eta_k T_bar_k  (the rotors' reach),
///
/// over the rotors that still deliver. The thrust row of B sums t, so sum t = T is fixed and
/// Var(t) = |t|^2 / N - (T / N)^2: the minimum-variance allocation is the minimum-norm one, a
/// strictly convex QP solved by the project's dual active-set solver (exact bounds, where eq. (5)'s
/// per-unit scaling E_i is a closed-form approximation without them).
#include <optional>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "rotorguard/control/dense_qp.h"
#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"
#include "rotorguard/modular/assembly.h"

namespace rotorguard::modular {

enum class Reallocation {
  /// The fault-free allocation (pseudo-inverse over all rotors, clipped), blind to eta: the
  /// "without FTC" rows of Table I.
  kNone,
  /// Eqs. (3)-(5): the units with a faulty rotor keep their fault-free commands; the healthy
  /// units together take what those miss (F_normal = sum F_i + dF_failed, M likewise), minimum
  /// variance among themselves.
  kPartial,
  /// Eq. (6) at the rotor level: every rotor that still delivers, faulty units included, shares
  /// the wrench with minimum variance of the delivered thrusts.
  kFull,
};
inline constexpr EnumName<Reallocation> kReallocationNames[] = {
    {Reallocation::kNone, "none"}, {Reallocation::kPartial, "partial"}, {Reallocation::kFull, "full"}};
constexpr std::span<const EnumName<Reallocation>> NamesOf(const Reallocation*) { return kReallocationNames; }

struct AllocatorOptions {
  Reallocation method = Reallocation::kFull;
  /// When no rotor thrusts within the bounds meet the wrench: weights of the residual of
  /// [T, tau_x, tau_y, tau_z] in the least-squares fallback (roll and pitch first: an assembly
  /// that keeps its attitude can still trade height; yaw last, as PX4's allocators do). > 0.
  Eigen::Vector4d priority = Eigen::Vector4d(1.0, 100.0, 100.0, 0.01);
  /// Weight of |t|^2 in that fallback, keeping it strictly convex [> 0, small].
  double regularisation = 1e-6;
  /// Rotors whose eta is at most this deliver nothing and are left out (dead units, lost props).
  double dead_eta = 1e-3;
  control::ActiveSetOptions qp;
  /// Throws ValidationError naming the field.
  void Validate() const;
  /// The keys of this struct in config files (core/config_schema.h).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("reallocation", &method,
             {.meaning = "full: min-variance over every rotor that delivers; partial: eqs. 3-5 of paper 002; none: the "
                         "fault-blind pseudo-inverse"});
  }
};

struct AllocationSummary {
  bool attainable = false;  ///< the wrench is met within the rotors' bounds (else the fallback)
  /// Delivered minus demanded wrench, as the allocator's eta predicts it.
  Eigen::Vector4d residual = Eigen::Vector4d::Zero();
  control::QpStatus status = control::QpStatus::kNotSolved;  ///< of the last QP solved
  int iterations = 0;        ///< active-set changes, all QPs of the call
  double solve_time_s = 0.0; ///< wall time of the call
};

class AssemblyAllocator {
 public:
  AssemblyAllocator(const Assembly& assembly, const AllocatorOptions& options);
  /// What is known of the rotors (from FDD or the scenario): eta per rotor in [0, 1]. Rebuilds
  /// the QPs (their sizes and Hessians depend on which rotors deliver). Throws
  /// std::invalid_argument naming the rotor for a wrong size or an eta outside [0, 1].
  void SetEffectiveness(const RotorVector& eta);
  const RotorVector& effectiveness() const { return eta_; }
  const Assembly& assembly() const { return assembly_; }
  /// Prepares `unit`'s separation (-1: none): with weight `blend` in [0, 1] the allocation moves
  /// towards the split one, where the unit's rotors give it exactly its own share of the
  /// collective thrust (its mass over the assembly's) with no torque about its own centre and the
  /// other rotors deliver the rest with the least variance. At blend 1 nothing acts through the
  /// latch, so releasing it leaves both bodies' accelerations as they were (for a small angular
  /// acceleration, the assembly's). Throws std::invalid_argument for a unit or blend out of range.
  void SetDetaching(int unit, double blend);
  /// Rotor commands [N] (what each motor is asked to drive, before its eta) for `wrench`; never
  /// non-finite (a non-finite wrench yields zero thrust and summary().attainable false).
  const AllocationSummary& Allocate(const Eigen::Vector4d& wrench, RotorVector* command);
  const AllocationSummary& summary() const { return summary_; }
  const EffectivenessMatrix& effectiveness_matrix() const { return B_; }

 private:
  /// Minimum-variance delivered thrusts on the rotors `cols` for `w`: the equality QP, or the
  /// prioritised least squares when it is infeasible.
  struct Subset {
    std::vector<int> cols;
    control::DenseQp exact{0, 0}, fallback{0, 0};
    std::optional<control::DenseQpSolver> exact_solver, fallback_solver;
    Eigen::MatrixXd weighted_b;  ///< B_s' W, for the fallback's gradient
  };
  void Prepare(const std::vector<int>& cols, Subset* s) const;
  Eigen::VectorXd SolveSubset(Subset* s, const Eigen::Vector4d& w);
  /// The commands of the rotors of `s` that deliver the thrusts `t` (t / eta, within the bounds).
  void Scatter(const Subset& s, const Eigen::VectorXd& t, RotorVector* command) const;

  Assembly assembly_;
  AllocatorOptions options_;
  EffectivenessMatrix B_;
  AllocationMatrix pinv_;
  RotorVector max_thrust_, eta_;
  Subset alive_;    ///< every rotor that delivers (kFull)
  Subset healthy_;  ///< the rotors of units without a fault (kPartial)
  Subset others_;   ///< the rotors that deliver, but the detaching unit's
  int detaching_ = -1;
  double blend_ = 0.0;
  AllocationMatrix unit_pinv_;  ///< the detaching unit's own allocation, about its centre
  std::vector<bool> unit_faulty_;
  bool any_faulty_ = false;  ///< a unit has a rotor with eta < 1
  AllocationSummary summary_;
};

}  // namespace rotorguard::modular

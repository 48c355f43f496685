#pragma once
/// The dual active-set method of Goldfarb and Idnani (Math. Programming 27, 1983), written once for
/// the QP solvers that differ only in how they factorise the active set: DenseQpSolver (J = L^-T Q
/// and R, updated by Givens rotations) and RiccatiQpSolver (the Cholesky factor of the Schur
/// complement N' H^-1 N over a Riccati recursion's responses). As HPIPM shares one core across its
/// dense and OCP solvers, `DualActiveSet` holds what the method is (the active sides and their
/// multipliers, the most violated side, the step lengths t1 and t2, the multiplier update, the
/// drops of negative multipliers, the warm start's memory) and asks the factorisation, a class
/// passed to its templates, for the three things it varies: a direction, an add and a drop.
///
/// A factorisation `F` provides, for the set as it stands (`set.size()` sides, before a change):
///   void ScanViolations(ViolationSearch& search);     // search.Scan(values, lower, upper, first)
///                                                      // over each block of constraint values
///   Direction MakeDirection(const Side& p, Eigen::Ref<Eigen::VectorXd> r);
///       // the primal step of side p (kept by F), the dual direction r (size q) and whether the
///       // step exists: p's normal independent of the active ones
///   void TakeStep(double t);                           // the iterate += t * step
///   double Slack(const Side& p) const;                 // s' z - b of side p at the iterate
///   bool IterateIsFinite() const;
///   bool AddToFactor(const Side& p);                   // p, whose direction was the last made,
///                                                      // joins the factorisation; false: refused
///   void DropFromFactor(int position);                 // the factorisation without that side
///   void MinimiseOnFactor(Eigen::Ref<Eigen::VectorXd> multipliers);
///       // the iterate at the minimum with the active sides held as equalities, and their
///       // multipliers (size q)
/// The set's own bookkeeping (which sides are active, the multipliers' order) follows each add and
/// drop here; the factorisation never touches it.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rotorguard::control {

/// Options of the dual active-set method, the same for every factorisation.
struct ActiveSetOptions {
  /// Largest violation of a constraint accepted at the solution (absolute, in the constraint's
  /// units); > 0.
  double feasibility_tolerance = 1e-9;
  /// Cap on active-set changes (adds plus drops); >= 1.
  int max_iterations = 1000;
  /// Start each solve from the previous successful solve's active set (Goldfarb and Idnani's
  /// method may start from any set whose equality-constrained minimum has non-negative
  /// multipliers). How much of the factorisation is kept is the solver's (its header says). The
  /// solution is a cold start's up to feasibility_tolerance (the iterations stop at the first point
  /// within it); only the work to reach it differs (docs/control.md).
  bool warm_start = true;
  void Validate() const;
};

enum class QpStatus {
  kNotSolved,          ///< Solve() was not called
  kSolved,             ///< optimal within tolerance
  kMaxIterations,      ///< stopped at max_iterations; the iterate is not optimal
  kInfeasible,         ///< the constraints admit no point
  kNumericalFailure,   ///< H not positive definite, or non-finite data
};
std::string_view ToString(QpStatus status);

/// How a solve started (ActiveSetOptions::warm_start).
enum class QpStart {
  kCold,  ///< from the unconstrained minimum
  kWarm,  ///< from the previous active set added to a new factorisation
  kHot,   ///< from the previous active set and its kept factorisation
};
std::string_view ToString(QpStart start);

namespace internal {

/// A one-sided constraint s a' z >= s b, the side of a two-sided one: `index` numbers the
/// solver's constraints (its bounds, then its rows), sign is +1 for the lower side and -1 for the
/// upper side.
struct Side {
  int index;
  double sign;
  /// Its slot among the 2 x constraints sides.
  std::size_t slot() const { return 2 * static_cast<std::size_t>(index) + (sign < 0); }
};

/// The most violated side that is not active, over the blocks of constraint values a
/// factorisation scans: a side counts when it is violated by more than the tolerance.
class ViolationSearch {
 public:
  ViolationSearch(double tolerance, const std::vector<char>& is_active) : worst_(-tolerance), is_active_(is_active) {}
  /// Constraints first, first + 1, ... with values `values` and bounds `lower`, `upper`.
  template <typename V, typename L, typename U>
  void Scan(const V& values, const L& lower, const U& upper, int first) {
    for (int i = 0; i < static_cast<int>(values.size()); ++i) {
      const std::size_t slot = 2 * static_cast<std::size_t>(first + i);
      if (values[i] - lower[i] < worst_ && !is_active_[slot]) {
        worst_ = values[i] - lower[i];
        side_ = {first + i, 1.0};
      }
      if (upper[i] - values[i] < worst_ && !is_active_[slot + 1]) {
        worst_ = upper[i] - values[i];
        side_ = {first + i, -1.0};
      }
    }
  }
  bool found() const { return side_.index >= 0; }
  const Side& side() const { return side_; }
  /// Its slack (negative).
  double slack() const { return worst_; }

 private:
  Side side_{-1, 0.0};
  double worst_;
  const std::vector<char>& is_active_;
};

/// What a factorisation says of a side's step (MakeDirection).
struct Direction {
  /// The side's normal is independent of the active ones: a primal step exists.
  bool independent;
  /// s a' step: how fast the step reduces the side's violation (> 0 for a primal step).
  double normal_dot_step;
};

/// The active set and the iterations of the method; sizes fixed at construction.
class DualActiveSet {
 public:
  DualActiveSet() = default;
  /// For `constraints` two-sided constraints of which at most `max_active` sides are active at once.
  DualActiveSet(int constraints, int max_active)
      : is_active_(2 * static_cast<std::size_t>(std::max(constraints, 0)), 0),
        multipliers_(std::max(max_active, 0)),
        direction_(std::max(max_active, 0)) {
    active_.reserve(static_cast<std::size_t>(std::max(max_active, 0)));
    previous_.reserve(static_cast<std::size_t>(std::max(max_active, 0)));
  }

  int size() const { return static_cast<int>(active_.size()); }
  const Side& operator[](int j) const { return active_[static_cast<std::size_t>(j)]; }
  bool IsActive(const Side& c) const { return is_active_[c.slot()] != 0; }
  /// The multipliers of the active sides (size()), >= 0 at a solution.
  Eigen::Ref<const Eigen::VectorXd> multipliers() const { return multipliers_.head(size()); }
  Eigen::Ref<Eigen::VectorXd> multipliers() { return multipliers_.head(size()); }
  /// Active-set changes since ResetIterations.
  int iterations() const { return iterations_; }
  void ResetIterations() { iterations_ = 0; }

  /// No active side (the factorisation is the caller's to clear).
  void Clear() {
    active_.clear();
    std::fill(is_active_.begin(), is_active_.end(), 0);
  }
  /// Appends c to the bookkeeping only: for a factorisation that built c's part itself.
  void Push(const Side& c) {
    active_.push_back(c);
    is_active_[c.slot()] = 1;
  }
  /// Adds c, whose direction was the last the factorisation made; false when it refuses c.
  template <typename F>
  bool Add(F& factor, const Side& c) {
    if (!factor.AddToFactor(c)) return false;
    Push(c);
    return true;
  }
  /// Drops the side at `position` and its multiplier.
  template <typename F>
  void Drop(F& factor, int position) {
    factor.DropFromFactor(position);
    is_active_[active_[static_cast<std::size_t>(position)].slot()] = 0;
    active_.erase(active_.begin() + position);
    const int q = size();
    for (int j = position; j < q; ++j) multipliers_[j] = multipliers_[j + 1];
  }
  /// Drops every side for which `binds_no_more(side)` holds, last first.
  template <typename F, typename Pred>
  void DropWhere(F& factor, Pred binds_no_more) {
    for (int j = size() - 1; j >= 0; --j) {
      if (binds_no_more(active_[static_cast<std::size_t>(j)])) Drop(factor, j);
    }
  }

  /// The start of Goldfarb and Idnani's iterations (an S-pair): the minimum with the active sides
  /// held as equalities, dropping the most negative multiplier's side until none is negative (at
  /// most size() rounds).
  template <typename F>
  void MinimiseOnActiveSet(F& factor) {
    while (true) {
      factor.MinimiseOnFactor(multipliers());
      int most_negative = -1;
      for (int j = 0; j < size(); ++j) {
        if (multipliers_[j] < 0.0 && (most_negative < 0 || multipliers_[j] < multipliers_[most_negative])) {
          most_negative = j;
        }
      }
      if (most_negative < 0) return;
      Drop(factor, most_negative);
    }
  }

  /// The iterations from the current S-pair: add the most violated side, with partial steps that
  /// drop the side whose multiplier would turn negative first (t1) before the added side's
  /// constraint holds (t2), until no side is violated.
  template <typename F>
  QpStatus Iterate(F& factor, const ActiveSetOptions& options) {
    constexpr double kInf = std::numeric_limits<double>::infinity();
    while (true) {
      ViolationSearch search(options.feasibility_tolerance, is_active_);
      factor.ScanViolations(search);
      if (!search.found()) return QpStatus::kSolved;
      const Side p = search.side();
      double slack = search.slack();
      double u_p = 0.0;  // p's multiplier as it grows
      while (true) {
        if (iterations_ >= options.max_iterations) return QpStatus::kMaxIterations;
        const int q = size();
        auto r = direction_.head(q);
        const Direction d = factor.MakeDirection(p, r);
        // t1: the largest dual step before an active multiplier reaches zero (its side drops).
        double t1 = kInf;
        int drop = -1;
        for (int j = 0; j < q; ++j) {
          if (r[j] > 0.0 && multipliers_[j] / r[j] < t1) {
            t1 = multipliers_[j] / r[j];
            drop = j;
          }
        }
        // t2: the primal step that makes p hold, when p's normal leaves the active span.
        const bool primal_step = d.independent && d.normal_dot_step > 0.0;
        const double t2 = primal_step ? -slack / d.normal_dot_step : kInf;
        const double t = std::min(t1, t2);
        if (!std::isfinite(t)) return QpStatus::kInfeasible;  // no step reduces p's violation
        ++iterations_;
        multipliers_.head(q) -= t * r;
        u_p += t;
        if (!primal_step) {
          Drop(factor, drop);  // a dual step only: make room for p
          continue;
        }
        factor.TakeStep(t);
        if (t2 <= t1) {
          if (!Add(factor, p)) return QpStatus::kNumericalFailure;
          multipliers_[q] = u_p;
          break;
        }
        Drop(factor, drop);
        slack = factor.Slack(p);
      }
      if (!factor.IterateIsFinite()) return QpStatus::kNumericalFailure;
    }
  }

  /// The warm start's memory: the active sides of the last successful solve.
  const std::vector<Side>& previous() const { return previous_; }
  void Remember() { previous_.assign(active_.begin(), active_.end()); }
  void Forget() { previous_.clear(); }

 private:
  std::vector<Side> active_;
  std::vector<char> is_active_;  // per Side::slot()
  Eigen::VectorXd multipliers_, direction_;
  int iterations_ = 0;
  std::vector<Side> previous_;
};

}  // namespace internal
}  // namespace rotorguard::control

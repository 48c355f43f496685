#include "rotorguard/control/disturbance_observer.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::control {

namespace {
using vehicle::StateIndex;

// A measurement later than this after the previous one restarts the velocity and rate estimates.
constexpr double kMaxGapS = 0.1;

Eigen::Vector3d Clamped(const Eigen::Vector3d& v, double max_norm) {
  const double n = v.norm();
  return n > max_norm ? Eigen::Vector3d(v * (max_norm / n)) : v;
}
}  // namespace

void DisturbanceObserverOptions::Validate() const { CheckDeclaredRanges("DisturbanceObserverOptions", *this); }

DisturbanceObserver::DisturbanceObserver(const NmpcModel& model, const DisturbanceObserverOptions& options)
    : model_(model), options_((options.Validate(), options)) {
  Reset();
}

void DisturbanceObserver::Reset() {
  have_prev_ = false;
  torque_slowed_ = false;
  d_a_.setZero();
  d_alpha_.setZero();
  history_.resize(kHistory);
  history_next_ = 0;
  history_size_ = 0;
}

void DisturbanceObserver::Update(const Eigen::VectorXd& x, double t) {
  if (!options_.enabled || x.size() != model_.nx() || !x.allFinite() || !std::isfinite(t) ||
      x[StateIndex::kPosition + 2] <= options_.min_altitude_m) {
    have_prev_ = false;
    return;
  }
  const Eigen::Vector3d v = x.segment<3>(StateIndex::kVelocity), w = x.segment<3>(StateIndex::kBodyRate);
  const double dt = t - t_prev_;
  if (have_prev_ && dt == 0.0) return;  // the same instant again: nothing new
  if (have_prev_ && dt > 0.0 && dt <= kMaxGapS) {
    auto step = [dt](double bandwidth, const Eigen::Vector3d& measured, const Eigen::Vector3d& model_rate,
                     Eigen::Vector3d* hat, Eigen::Vector3d* d) {
      const double p = std::exp(-bandwidth * dt);
      const Eigen::Vector3d e = measured - (*hat + dt * (model_rate + *d));
      *hat = measured - p * p * e;  // v- + (1 - p²) e
      *d += ((1.0 - p) * (1.0 - p) / dt) * e;
    };
    step(options_.force_bandwidth_rad_s, v, a_prev_, &v_hat_, &d_a_);
    if (!torque_slowed_) {
      step(options_.torque_bandwidth_rad_s, w, alpha_prev_, &w_hat_, &d_alpha_);
    } else if (options_.torque_bandwidth_after_failure_rad_s > 0.0) {
      step(options_.torque_bandwidth_after_failure_rad_s, w, alpha_prev_, &w_hat_, &d_alpha_);
    }
    d_a_ = Clamped(d_a_, options_.max_acceleration_m_s2);
    d_alpha_ = Clamped(d_alpha_, options_.max_angular_acceleration_rad_s2);
  } else {
    v_hat_ = v;
    w_hat_ = w;
  }
  model_.ModelAccelerations(x, &a_prev_, &alpha_prev_);
  t_prev_ = t;
  have_prev_ = true;
  history_[history_next_] = {t, d_a_, d_alpha_};
  history_next_ = (history_next_ + 1) % kHistory;
  history_size_ = std::min(history_size_ + 1, kHistory);
}

void DisturbanceObserver::RewindTo(double t) {
  if (history_size_ == 0) return;
  // Newest to oldest: the first entry at or before t, else the oldest.
  int at = 0;
  for (int back = 1; back <= history_size_; ++back) {
    at = (history_next_ - back + kHistory) % kHistory;
    if (history_[at].t <= t) break;
  }
  d_a_ = history_[at].d_a;
  d_alpha_ = history_[at].d_alpha;
}

}  // namespace rotorguard::control

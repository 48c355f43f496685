#include "rotorguard/perception/deskew.h"

#include <algorithm>
#include <cmath>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"

namespace rotorguard::perception {

void DeskewOptions::Validate() const {
  if (!sensor_position_m.allFinite()) {
    ThrowValidation("DeskewOptions", "sensor_position_m", "(non-finite)", "finite numbers");
  }
  if (!(gyro_history_s > 0.0) || !std::isfinite(gyro_history_s)) {
    ThrowValidation("DeskewOptions", "gyro_history_s", gyro_history_s, "a duration > 0 s");
  }
}

Deskewer::Deskewer(const DeskewOptions& options) : options_(options) { options_.Validate(); }

void Deskewer::OnImu(const ImuSample& imu) {
  if (!imu.w_B.allFinite()) return;
  if (!gyro_.empty() && imu.t_ns <= gyro_.back().t_ns) return;  // out of order: keep the history sorted
  gyro_.push_back(imu);
  const TimeNs keep = FromSeconds(options_.gyro_history_s);
  while (gyro_.size() > 2 && gyro_.back().t_ns - gyro_.front().t_ns > keep) gyro_.pop_front();
}

DeskewSummary Deskewer::Deskew(const LidarFrame& frame, const Vector3& v_W, const Quaternion& q_WB_end,
                               std::vector<Eigen::Vector3f>* out) const {
  DeskewSummary summary;
  out->clear();
  out->reserve(frame.points_S.size());
  const TimeNs t_end = frame.t_end_ns;
  // Rotations from the body at knot time k to the body at t_end, R(t_end)^T R(t_k), built
  // backwards: the rate of sample j holds from its time to the next sample's (zero-order hold).
  // Knots are the sample times inside the frame, newest first, starting at t_end.
  struct Knot {
    TimeNs t;
    Matrix3 R_end_from_t;
    Vector3 w;  // the rate held over [previous knot time, t)
  };
  std::vector<Knot> knots;
  knots.push_back({t_end, Matrix3::Identity(), Vector3::Zero()});
  // The rate at time t: the latest sample at or before t (the oldest one before the history).
  const auto rate_before = [&](TimeNs t) -> Vector3 {
    auto it = std::upper_bound(gyro_.begin(), gyro_.end(), t, [](TimeNs v, const ImuSample& s) { return v < s.t_ns; });
    if (it == gyro_.begin()) return gyro_.empty() ? Vector3::Zero() : gyro_.front().w_B;
    return std::prev(it)->w_B;
  };
  // Sample times in (t_start, t_end), newest first.
  std::vector<TimeNs> times;
  for (auto it = gyro_.rbegin(); it != gyro_.rend(); ++it) {
    if (it->t_ns >= t_end) continue;
    if (it->t_ns <= frame.t_start_ns) break;
    times.push_back(it->t_ns);
  }
  times.push_back(frame.t_start_ns);
  for (TimeNs t : times) {
    const Knot& later = knots.back();
    const Vector3 w = rate_before(t);  // the rate over [t, later.t)
    knots.push_back({t, later.R_end_from_t * ExpSO3(-w * ToSeconds(later.t - t)), w});
  }
  const Matrix3 R_end_T = q_WB_end.normalized().toRotationMatrix().transpose();
  const Vector3 v_end_B = R_end_T * v_W;
  const Vector3& l = options_.sensor_position_m;
  const TimeNs oldest = gyro_.empty() ? t_end : gyro_.front().t_ns;
  // The first knot at or before t, from 1 (knots are newest first), or knots.size() if none: the
  // previous point's, or the one before it, when they fit (a frame's points come in time order,
  // so k only steps down now and then), else a binary search.
  const std::size_t n = knots.size();
  const auto fits = [&](std::size_t k, TimeNs t) {
    return (k == n || knots[k].t <= t) && (k == 1 || knots[k - 1].t > t);
  };
  std::size_t k = n;
  for (std::size_t i = 0; i < frame.points_S.size(); ++i) {
    const TimeNs t = frame.t_start_ns + frame.offset_ns[i];
    const Vector3 p_S = frame.points_S[i].cast<double>();
    if (!p_S.allFinite()) continue;
    if (!fits(k, t)) {
      if (k > 1 && fits(k - 1, t)) {
        --k;
      } else {
        const auto later = [t](const Knot& kn) { return kn.t > t; };
        k = static_cast<std::size_t>(std::partition_point(knots.begin() + 1, knots.end(), later) - knots.begin());
      }
    }
    // Rotate from t up to the knot just after it, then on to t_end.
    const Knot& after = knots[k - 1];
    const Vector3 w = k < n ? knots[k].w : rate_before(t);
    const Vector3 p_end_B =
        after.R_end_from_t * ExpSO3Times(-w * ToSeconds(after.t - t), l + p_S) - v_end_B * ToSeconds(t_end - t);
    out->push_back((p_end_B - l).cast<float>());
    ++summary.points;
    if (t < oldest) ++summary.extrapolated;
  }
  return summary;
}

}  // namespace rotorguard::perception

#pragma once
/// Flight metrics as defined in DESIGN.md ("Metrics"), accumulated sample by sample.
#include <limits>

#include "rotorguard/core/types.h"

namespace rotorguard::bench {

/// Tracking error over [t1, t2]: RMSE = sqrt( (1/(t2-t1)) * integral |p - p_ref|^2 dt ), and
/// paper 000's eq. (37), which divides outside the root: sqrt( integral |p - p_ref|^2 dt ) / (t2-t1).
/// Integrated with the rectangle rule at the sampling step.
class TrackingErrorAccumulator {
 public:
  void Add(double dt, const Vector3& p, const Vector3& p_ref);
  double rmse() const;
  double rmse_eq37() const;
  double max_error() const { return max_error_; }
  double duration() const { return duration_; }

 private:
  double integral_ = 0.0;
  double duration_ = 0.0;
  double max_error_ = 0.0;
};

}  // namespace rotorguard::bench

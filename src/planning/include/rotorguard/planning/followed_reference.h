#pragma once
/// FollowedReference: what a navigator hands the controller, as a value: an immutable copy of the
/// path it follows, or the point it holds. The navigators change what they follow only when they
/// plan (Replanner::Update, FlatnessNavigator's legs), and each change makes a new one, so the
/// controller evaluates its reference over its horizon without touching the navigator: onboard,
/// the planner's thread publishes it and the control thread reads it (docs/runtime.md).
#include <limits>
#include <optional>

#include "rotorguard/core/trajectory.h"

namespace rotorguard::planning {

template <typename Path>
class FollowedReference final : public ReferenceTrajectory {
 public:
  /// `path`: the path followed, if any; `hold`: the reference without one.
  FollowedReference(std::optional<Path> path, const ReferencePoint& hold) : path_(std::move(path)), hold_(hold) {}
  ReferencePoint Evaluate(double t) const override { return path_ ? path_->Evaluate(t) : hold_; }
  /// As the navigators say: never constant for good (a new plan may come).
  double duration() const override { return std::numeric_limits<double>::infinity(); }

 private:
  std::optional<Path> path_;
  ReferencePoint hold_;
};

}  // namespace rotorguard::planning

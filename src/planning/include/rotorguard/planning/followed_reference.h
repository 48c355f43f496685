#pragma once
/// FollowedReference: what a navigator hands the controller, as a value: an immutable copy of the
/// path it follows, or the point it holds. The navigators change what they follow only when they
/// plan (Replanner::Update, FlatnessNavigator's legs), and each change makes a new one, so the
/// controller evaluates its reference over its horizon without touching the navigator: onboard,
/// the planner's thread publishes it and the control thread reads it (docs/runtime.md).
#include <limits>
#include <optional>
#include <vector>

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

/// Of paths followed in turn, each from its start_time() until the next one's (the first also
/// before its own), the one in effect at t.
template <typename Path>
const Path& PathInEffect(const std::vector<Path>& paths, double t) {
  std::size_t i = 0;
  while (i + 1 < paths.size() && t >= paths[i + 1].start_time()) ++i;
  return paths[i];
}

/// Paths followed in turn (PathInEffect): a plan made at t to start at t + its expected
/// computation time, from the state the path followed until then predicts for that start, so
/// that the switch is continuous however late within that budget the plan is published
/// (docs/runtime.md, "Late results").
template <typename Path>
class PathsInTurn {
 public:
  explicit PathsInTurn(std::vector<Path> paths) : paths_(std::move(paths)) {}
  ReferencePoint Evaluate(double t) const { return PathInEffect(paths_, t).Evaluate(t); }

 private:
  std::vector<Path> paths_;
};

}  // namespace rotorguard::planning

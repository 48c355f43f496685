#include "rotorguard/planning/replanner.h"

#include <cmath>
#include <functional>

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "test_util.h"

namespace rotorguard::planning {
namespace {

perception::VoxelMap EmptyMap() {
  perception::VoxelMapOptions o;
  o.window_size_m = Vector3(12.8, 12.8, 6.4);
  o.inflation_radius_m = 0.2;
  return perception::VoxelMap(o);
}

/// A wall x in [x0, x0 + 0.2] across y in [-5, 5] (z 0-3 m) with a 1 m gap at y in [2, 3], or
/// across the whole window (y in [-6.4, 6.4], above the planner's altitude band) without one.
void AddWall(perception::VoxelMap* map, double x0, bool gap) {
  const double half = gap ? 5.0 : 6.4;
  for (double x = x0 + 0.05; x < x0 + 0.2; x += 0.1) {
    for (double y = -half + 0.05; y < half; y += 0.1) {
      if (gap && y > 2.0 && y < 3.0) continue;
      for (double z = 0.05; z < 3.0; z += 0.1) map->MarkOccupied(Vector3(x, y, z));
    }
  }
}

/// Runs the replanner at 10 Hz from t0 to t1, with `before(t)` called ahead of each update; checks
/// at every update that the reference is continuous in p, v and a across it.
template <typename Before>
void Fly(Replanner* r, const perception::VoxelMap& map, double t0, double t1, Before before) {
  for (double t = t0; t <= t1 + 1e-9; t += 0.1) {
    before(t);
    const ReferencePoint a = r->Reference(t);
    r->Update(t, map);
    const ReferencePoint b = r->Reference(t);
    ASSERT_LT((a.p_W - b.p_W).norm(), 1e-9) << "t = " << t;
    ASSERT_LT((a.v_W - b.v_W).norm(), 1e-9) << "t = " << t;
    ASSERT_LT((a.a_W - b.a_W).norm(), 1e-9) << "t = " << t;
  }
}

bool EntersInflated(const Replanner& r, const perception::VoxelMap& map, double t0, double t1) {
  for (double t = t0; t <= t1; t += 0.01) {
    if (map.IsInflated(r.Reference(t).p_W)) return true;
  }
  return false;
}

int Count(const Replanner& r, const std::string& reason) {
  int n = 0;
  for (const Replanner::Event& e : r.events()) n += e.reason == reason;
  return n;
}

TEST(LocalGoal, AGoalInsideTheWindowIsItself) {
  perception::VoxelMap map = EmptyMap();
  map.Recenter(Vector3(0, 0, 1.5));
  const Vector3 goal(3, -2, 1.5);
  EXPECT_EQ(*LocalGoal(map, Vector3::Zero() + Vector3(0, 0, 1.5), goal, 1.0), goal);
}

TEST(LocalGoal, AGoalBeyondTheWindowBecomesTheSegmentsExitPointWithTheMargin) {
  perception::VoxelMap map = EmptyMap();
  map.Recenter(Vector3(0, 0, 1.5));
  const Vector3 start(0, 0, 1.5), goal(30, 10, 1.5);
  const std::optional<Vector3> g = LocalGoal(map, start, goal, 1.0);
  ASSERT_TRUE(g.has_value());
  // On the segment (closed form: parallel to goal - start) ...
  EXPECT_NEAR((*g - start).normalized().dot((goal - start).normalized()), 1.0, 1e-12);
  // ... exactly one margin inside the window along x, the axis it leaves by.
  EXPECT_NEAR(g->x(), map.window_max_W().x() - 1.0, 1e-9);
  EXPECT_LE(g->y(), map.window_max_W().y() - 1.0);
}

TEST(LocalGoal, AnObstacleAtTheExitPointIsWalkedBackPast) {
  perception::VoxelMap map = EmptyMap();
  map.Recenter(Vector3(0, 0, 1.5));
  const Vector3 start(0, 0, 1.5), goal(30, 0, 1.5);
  const double exit_x = map.window_max_W().x() - 1.0;
  for (double x = exit_x - 0.55; x < exit_x + 0.05; x += 0.1) map.MarkOccupied(Vector3(x, 0.05, 1.55));
  const std::optional<Vector3> g = LocalGoal(map, start, goal, 1.0);
  ASSERT_TRUE(g.has_value());
  EXPECT_FALSE(map.IsInflated(*g));
  EXPECT_LT(g->x(), exit_x - 0.55);
  EXPECT_GT(g->x(), exit_x - 0.55 - 0.2 - 0.3);  // just past the inflation, not further
  // Everything between the start and the edge blocked: no local goal.
  for (double x = 0.05; x < exit_x; x += 0.1) map.MarkOccupied(Vector3(x, 0.05, 1.55));
  EXPECT_FALSE(LocalGoal(map, start, goal, 1.0).has_value());
}

// A goal in free space: planned at once, replanned periodically, reached and held, and the
// reference never jumps.
TEST(Replanner, PlansOnAGoalReplansPeriodicallyAndArrives) {
  const perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5));
  EXPECT_EQ(r.mode(), Replanner::Mode::kIdle);
  r.SetGoal(Vector3(5, 1, 1.5));
  Fly(&r, map, 0.0, 15.0, [](double) {});
  ASSERT_GE(r.events().size(), 2u);
  EXPECT_EQ(r.events().front().reason, "goal");
  EXPECT_GE(Count(r, "periodic"), 1);
  EXPECT_EQ(r.mode(), Replanner::Mode::kHolding);
  EXPECT_TRUE(r.arrived());
  EXPECT_LT((r.Reference(15.0).p_W - Vector3(5, 1, 1.5)).norm(), 1e-6);
  EXPECT_LT(r.Reference(15.0).v_W.norm(), 1e-9);
}

// What the replanner follows, as a value (FollowedReference): a copy made at a path serial
// evaluates as the replanner does, to the bit, until the serial changes; then it keeps the path
// it copied (a controller reading it is never disturbed by the planner's next plan).
TEST(Replanner, TheFollowedReferenceIsTheReplannersReferenceAsAValue) {
  const perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5), 0.7);
  const std::shared_ptr<const ReferenceTrajectory> hold = r.Followed();
  EXPECT_EQ(hold->Evaluate(3.0).p_W, Vector3(0, 0, 1.5));
  EXPECT_EQ(hold->Evaluate(3.0).yaw, 0.7);
  r.SetGoal(Vector3(5, 1, 1.5));
  std::shared_ptr<const ReferenceTrajectory> copy;
  std::uint64_t serial = r.path_serial(), changes = 0;
  for (double t = 0.0; t <= 12.0; t += 0.05) {
    r.Update(t, map);
    if (r.path_serial() != serial || !copy) {
      // A new path: the copy made before it no longer agrees somewhere ahead.
      if (copy && r.path_serial() != serial) {
        ++changes;
        bool differs = false;
        for (double s = t; s <= t + 2.0; s += 0.1) differs = differs || copy->Evaluate(s).p_W != r.Evaluate(s).p_W;
        EXPECT_TRUE(differs) << "t = " << t;
      }
      serial = r.path_serial();
      copy = r.Followed();
    }
    for (double s = t; s <= t + 1.0; s += 0.1) {
      const ReferencePoint a = copy->Evaluate(s), b = r.Evaluate(s);
      ASSERT_TRUE(a.p_W == b.p_W && a.v_W == b.v_W && a.a_W == b.a_W && a.yaw == b.yaw) << "t = " << t << ", s = " << s;
    }
  }
  EXPECT_GE(changes, 2u) << "the goal's plan and the periodic replans";
  EXPECT_EQ(hold->Evaluate(3.0).p_W, Vector3(0, 0, 1.5)) << "the first copy still holds";
}

// Onboard, a plan made at t starts at t + the planning's expected computation time, from the
// reference then: until then the path followed is the one before, to the bit, whenever within
// that budget the new one is published; at the switch the reference is continuous in p, v and a.
// The followed copy evaluates as the replanner does, earlier paths included.
TEST(Replanner, APlanStartedAheadKeepsThePathFollowedUntilItsStart) {
  const perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5));
  r.set_plan_ahead_s(0.05);
  r.SetGoal(Vector3(5, 1, 1.5));
  int replans = 0;
  for (double t = 0.0; t <= 8.0; t += 0.05) {
    const std::uint64_t serial = r.path_serial();
    const std::shared_ptr<const ReferenceTrajectory> before = r.Followed();
    r.Update(t, map);
    if (r.path_serial() == serial) continue;
    ++replans;
    const std::shared_ptr<const ReferenceTrajectory> after = r.Followed();
    for (double s = t; s < t + 0.05 - 1e-9; s += 0.005) {
      const ReferencePoint a = before->Evaluate(s), b = after->Evaluate(s);
      ASSERT_TRUE(a.p_W == b.p_W && a.v_W == b.v_W && a.a_W == b.a_W) << "t = " << t << ", s = " << s;
    }
    const ReferencePoint a = before->Evaluate(t + 0.05), b = after->Evaluate(t + 0.05);
    ASSERT_LT((a.p_W - b.p_W).norm(), 1e-9) << "t = " << t;
    ASSERT_LT((a.v_W - b.v_W).norm(), 1e-9) << "t = " << t;
    ASSERT_LT((a.a_W - b.a_W).norm(), 1e-9) << "t = " << t;
    for (double s = t; s <= t + 1.0; s += 0.01) {
      const ReferencePoint x = after->Evaluate(s), y = r.Evaluate(s);
      ASSERT_TRUE(x.p_W == y.p_W && x.v_W == y.v_W) << "t = " << t << ", s = " << s;
    }
  }
  EXPECT_GE(replans, 3) << "the goal's plan and the periodic replans";
  EXPECT_TRUE(r.arrived());
  EXPECT_LT((r.Reference(8.0).p_W - Vector3(5, 1, 1.5)).norm(), 1e-6);
}

// The heading given at construction is held before and through every plan.
TEST(Replanner, KeepsTheHeadingItWasGiven) {
  const perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5), 2.5);
  EXPECT_EQ(r.Reference(0.0).yaw, 2.5);
  r.SetGoal(Vector3(2, 0, 1.5));
  Fly(&r, map, 0.0, 6.0, [](double) {});
  for (double t = 0.0; t <= 6.0; t += 0.5) EXPECT_EQ(r.Reference(t).yaw, 2.5) << t;
}

// A wall (with a gap) appears across the trajectory after it was planned: the next update sees it
// ahead, replans from the current reference, and the reference keeps clear of it.
TEST(Replanner, AnObstacleAppearingAheadTriggersAReplanAroundIt) {
  perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5));
  r.SetGoal(Vector3(5, 0, 1.5));
  Fly(&r, map, 0.0, 20.0, [&](double t) {
    if (std::abs(t - 0.5) < 1e-6) AddWall(&map, 1.5, true);
  });
  EXPECT_GE(Count(r, "obstacle ahead"), 1);
  EXPECT_FALSE(EntersInflated(r, map, 0.5, 20.0));
  EXPECT_EQ(r.mode(), Replanner::Mode::kHolding);
  EXPECT_LT((r.Reference(20.0).p_W - Vector3(5, 0, 1.5)).norm(), 1e-6);
}

// FDD reports a failure mid-flight: the next update replans from the current state with the
// post-failure acceleration limit, which the new trajectory respects (beyond the head's own
// acceleration at the switch).
TEST(Replanner, AFailureReplansWithThePostFailureAccelerationLimit) {
  const perception::VoxelMap map = EmptyMap();
  ReplannerOptions o;
  o.post_failure_a_max = 0.3;
  Replanner r(o, Vector3(0, 0, 1.5));
  r.SetGoal(Vector3(6, 0, 1.5));
  double switch_t = -1.0, head_a = 0.0;
  Fly(&r, map, 0.0, 25.0, [&](double t) {
    if (std::abs(t - 1.0) < 1e-6) {
      r.OnFailure();
      switch_t = t;
      head_a = r.Reference(t).a_W.norm();
    }
  });
  ASSERT_EQ(Count(r, "failure"), 1);
  EXPECT_EQ(r.limits().a_max, 0.3);
  double a_max = 0.0;
  for (double t = switch_t; t <= 25.0; t += 0.005) a_max = std::max(a_max, r.Reference(t).a_W.norm());
  EXPECT_LE(a_max, std::max(0.3, head_a) * 1.001);
  EXPECT_LT((r.Reference(25.0).p_W - Vector3(6, 0, 1.5)).norm(), 1e-6);
}

// A partial loss lowers the acceleration limit (never raises it); the trajectory being flown is
// kept, and the next periodic replan keeps to the new limit.
TEST(Replanner, APartialLossLimitsTheAccelerationFromTheNextReplanOn) {
  const perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5));
  r.SetGoal(Vector3(6, 0, 1.5));
  const double nominal = r.limits().a_max;
  Fly(&r, map, 0.0, 40.0, [&](double t) {
    if (std::abs(t - 1.0) < 1e-6) {
      r.LimitAcceleration(0.3);
      r.LimitAcceleration(2.0 * nominal);  // a higher one changes nothing
    }
  });
  EXPECT_EQ(r.limits().a_max, 0.3);
  EXPECT_EQ(Count(r, "failure"), 0);
  const auto next = std::find_if(r.events().begin(), r.events().end(),
                                 [](const Replanner::Event& e) { return e.t > 1.0 && e.reason == "periodic"; });
  ASSERT_NE(next, r.events().end());
  const double head_a = r.Reference(next->t).a_W.norm();
  double a_max = 0.0;
  for (double t = next->t; t <= 40.0; t += 0.005) a_max = std::max(a_max, r.Reference(t).a_W.norm());
  EXPECT_LE(a_max, std::max(0.3, head_a) * 1.001);
  EXPECT_LT((r.Reference(40.0).p_W - Vector3(6, 0, 1.5)).norm(), 1e-6);
}

// The clearance kept before a failure holds the failure's transient, which lasts until the
// attitude has recovered; after that the post-failure clearance applies. A pillar 0.55 m beside
// the straight way: planned for 0.9 m of clearance the trajectory swings wide of it, and so it
// does when replanned after a failure, until the recovery; replanned after the recovery for 0.3 m
// it passes close. A recovery reported before the failure is no recovery from it.
TEST(Replanner, AFailureSwitchesToThePostFailureClearanceOnceRecovered) {
  perception::VoxelMap map = EmptyMap();
  for (double x = 2.95; x < 3.1; x += 0.1) {
    for (double y = 0.55; y < 0.7; y += 0.1) {
      for (double z = 0.05; z < 3.0; z += 0.1) map.MarkOccupied(Vector3(x, y, z));
    }
  }
  ReplannerOptions o;
  o.planner.optimizer.clearance_m = 0.9;
  o.planner.plane_search_m = 1.0;
  o.post_failure_clearance_m = 0.3;
  // `events` is called at every update ahead of Update; recovered_s is when OnRecovered is (never
  // when negative), from when the events must have 0.3 m, before it 0.9 m, each in one attempt.
  const auto closest = [&](const std::function<void(Replanner&, double)>& events, double recovered_s) {
    Replanner r(o, Vector3(0, 0, 1.5));
    r.SetGoal(Vector3(6, 0, 1.5));
    double d = 1e9;  // the reference's least distance to the pillar, sampled as it is flown
    Fly(&r, map, 0.0, 20.0, [&](double t) {
      events(r, t);
      for (double s = t - 0.1; s < t; s += 0.01) {
        if (const auto n = map.Nearest(r.Reference(s).p_W, 2.0)) d = std::min(d, n->distance_m);
      }
    });
    EXPECT_TRUE(r.arrived());
    for (const Replanner::Event& e : r.events()) {
      const bool after = recovered_s >= 0.0 && e.t >= recovered_s - 1e-9;
      EXPECT_EQ(e.clearance_m, after ? 0.3 : 0.9) << "t = " << e.t;
      EXPECT_EQ(e.attempts, 1) << "t = " << e.t;
    }
    return d;
  };
  const auto at_start = [](bool fail, bool recover) {
    return [=](Replanner& r, double t) {
      if (t > 0.0) return;
      if (recover) r.OnRecovered();
      if (fail) r.OnFailure();
    };
  };
  EXPECT_GT(closest(at_start(false, false), -1.0), 0.85);  // about the 0.9 m asked for
  EXPECT_GT(closest(at_start(false, true), -1.0), 0.85);   // no failure: nothing to recover from
  EXPECT_GT(closest(at_start(true, true), -1.0), 0.85);    // a recovery before the failure is none
  EXPECT_GT(closest(at_start(true, false), -1.0), 0.85);   // failed, still in the transient
  const auto recovered_at = [](double recovery_s) {
    return [=](Replanner& r, double t) {
      if (t == 0.0) r.OnFailure();
      if (std::abs(t - recovery_s) < 1e-9) r.OnRecovered();
    };
  };
  EXPECT_LT(closest(recovered_at(0.0), 0.0), 0.6);  // recovered: the straight way, 0.55 m from the voxels
  EXPECT_LT(closest(recovered_at(1.0), 1.0), 0.7);  // recovered on the way: well inside the 0.9 m
  o.post_failure_clearance_m = 1.5;  // beyond the planes' search radius
  RG_EXPECT_THROW_WITH(Replanner(o, Vector3::Zero()), std::invalid_argument, "post_failure_clearance_m");
}

// The collision check's spacing and horizon set how many map lookups a check makes: a step of
// a micrometre or a horizon of hours would make each a long loop, and the options refuse them.
TEST(Replanner, RefusesCheckSpacingsAndHorizonsThatWouldMakeTheCheckUnbounded) {
  ReplannerOptions o;
  o.check_step_m = 1e-6;
  RG_EXPECT_THROW_WITH(o.Validate(), std::invalid_argument, "check_step_m");
  o = ReplannerOptions{};
  o.check_horizon_s = 3600.0;
  RG_EXPECT_THROW_WITH(o.Validate(), std::invalid_argument, "check_horizon_s");
  o = ReplannerOptions{};
  o.planner.check_step_m = 0.0;
  RG_EXPECT_THROW_WITH(o.Validate(), std::invalid_argument, "check_step_m");
  EXPECT_NO_THROW(ReplannerOptions{}.Validate());
}

// A wall without a gap closes the way: no plan exists, so the replanner brakes to rest within
// its limits before the wall, then holds (and keeps trying).
TEST(Replanner, AGoalBeyondTheMapIsReachedThroughLocalGoalsAsTheWindowMoves) {
  perception::VoxelMap map = EmptyMap();
  map.Recenter(Vector3(0, 0, 1.5));
  ReplannerOptions o;
  Replanner r(o, Vector3(0, 0, 1.5));
  const Vector3 goal(20, 0, 1.5);  // beyond the 12.8 m window
  r.SetGoal(goal);
  Fly(&r, map, 0.0, 40.0, [&](double t) { map.Recenter(r.Reference(t).p_W); });
  for (const Replanner::Event& e : r.events()) EXPECT_EQ(e.status, PlanSummary::Status::kSuccess) << e.t;
  EXPECT_TRUE(r.arrived());
  EXPECT_LT((r.Reference(40.0).p_W - goal).norm(), 1e-6);
}

TEST(Replanner, NoWayThroughBrakesToRestAndHolds) {
  perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5));
  r.SetGoal(Vector3(6, 0, 1.5));
  double closed_at = -1.0;
  Fly(&r, map, 0.0, 12.0, [&](double t) {
    if (closed_at < 0.0 && r.Reference(t).v_W.norm() > 0.8) {  // closed while cruising
      AddWall(&map, r.Reference(t).p_W.x() + 2.0, false);
      closed_at = t;
    }
  });
  ASSERT_GT(closed_at, 0.0);
  bool braked = false;
  for (const Replanner::Event& e : r.events()) braked |= e.mode_after == Replanner::Mode::kBraking;
  EXPECT_TRUE(braked);
  EXPECT_EQ(r.mode(), Replanner::Mode::kHolding);
  EXPECT_FALSE(r.arrived());
  EXPECT_LT(r.Reference(12.0).v_W.norm(), 1e-9);
  EXPECT_FALSE(EntersInflated(r, map, closed_at, 12.0));
  double a_max = 0.0;
  for (double t = closed_at; t <= 12.0; t += 0.005) a_max = std::max(a_max, r.Reference(t).a_W.norm());
  EXPECT_LE(a_max, r.limits().a_max * 1.001);
  EXPECT_GE(Count(r, "periodic"), 1) << "keeps trying while holding";
}

// A wall closing the way nearer than a brake within the limits needs (0.6 m of free space ahead
// at 1 m/s, where a_max = 2 m/s^2 needs v^2 / a = 1 m for the minimum-jerk stop): the brake comes
// harder and stops short of the wall's inflation.
TEST(Replanner, AWallTooCloseForTheLimitsIsBrakedForHarderRatherThanReached) {
  perception::VoxelMap map = EmptyMap();
  Replanner r(ReplannerOptions{}, Vector3(0, 0, 1.5));
  r.SetGoal(Vector3(6, 0, 1.5));
  double closed_at = -1.0;
  Fly(&r, map, 0.0, 12.0, [&](double t) {
    if (closed_at < 0.0 && r.Reference(t).v_W.norm() > 0.95) {
      AddWall(&map, r.Reference(t).p_W.x() + 0.6 + 0.2, false);  // 0.6 m to the inflation
      closed_at = t;
    }
  });
  ASSERT_GT(closed_at, 0.0);
  EXPECT_FALSE(EntersInflated(r, map, closed_at, 12.0));
  EXPECT_LT(r.Reference(12.0).v_W.norm(), 1e-9);
}

// LayerExit against the distances to a hand-made wall: voxel centres at x = 1.05 (and 1.15), the
// inflation radius 0.2 m, a start 0.17 m from the nearest centre (inside the layer). Away from the
// wall and along it the path is clear (along it the nearest centre stays 0.17 m or more away);
// 0.02 m closer is not (beyond the 0.01 m tolerance); once out of the layer, back into it is not.
TEST(LayerExit, LeavesTheLayerItStartedInButNeverCloserToItsObstacle) {
  perception::VoxelMap map = EmptyMap();
  AddWall(&map, 1.0, false);
  const Vector3 start(0.88, 0.05, 1.55);
  ASSERT_TRUE(map.IsInflated(start));
  {
    LayerExit away(map, start);
    for (double x = 0.88; x > 0.5; x -= 0.01) EXPECT_TRUE(away.Clear(Vector3(x, 0.05, 1.55))) << x;
    EXPECT_FALSE(away.leaving());
    EXPECT_FALSE(away.Clear(Vector3(0.88, 0.05, 1.55))) << "back into the layer once out of it";
  }
  {
    LayerExit along(map, start);
    for (double y = 0.05; y < 2.0; y += 0.01) EXPECT_TRUE(along.Clear(Vector3(0.88, y, 1.55))) << y;
    EXPECT_TRUE(along.leaving());
  }
  {
    LayerExit closer(map, start);
    EXPECT_TRUE(closer.Clear(Vector3(0.885, 0.05, 1.55))) << "within the tolerance";
    EXPECT_FALSE(closer.Clear(Vector3(0.90, 0.05, 1.55)));
  }
  {
    LayerExit outside(map, Vector3(0.5, 0.05, 1.55));  // a free start: the layer is an obstacle
    EXPECT_FALSE(outside.leaving());
    EXPECT_FALSE(outside.Clear(Vector3(0.88, 0.05, 1.55)));
  }
}

// A vehicle held inside a wall's inflation layer (it stopped there, or the wall was mapped beside
// it) with a goal along the free side: the plan leaves the layer, and the replanner keeps it (its
// look-ahead applies the planner's rule) instead of condemning every plan at the next tick as an
// obstacle ahead; the reference stays within the limits and never comes closer to the wall.
TEST(Replanner, AVehicleHeldInsideAnInflationLayerLeavesItOnOnePlan) {
  perception::VoxelMap map = EmptyMap();
  AddWall(&map, 1.0, false);
  const Vector3 start(0.88, 0.05, 1.55);
  ASSERT_TRUE(map.IsInflated(start));
  Replanner r(ReplannerOptions{}, start);
  r.SetGoal(Vector3(0.4, 3.0, 1.55));
  Fly(&r, map, 0.0, 10.0, [](double) {});
  EXPECT_EQ(Count(r, "obstacle ahead"), 0);
  EXPECT_TRUE(r.arrived());
  double a_max = 0.0, x_max = 0.0;
  for (double t = 0.0; t <= 10.0; t += 0.005) {
    a_max = std::max(a_max, r.Reference(t).a_W.norm());
    x_max = std::max(x_max, r.Reference(t).p_W.x());
  }
  EXPECT_LE(a_max, r.limits().a_max * 1.001);
  EXPECT_LE(x_max, start.x() + 0.01) << "never closer to the wall than it started";
}

}  // namespace
}  // namespace rotorguard::planning

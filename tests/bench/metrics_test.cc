#include "rotorguard/bench/metrics.h"

#include <cmath>

#include <gtest/gtest.h>

namespace rotorguard::bench {
namespace {

TEST(TrackingError, RmseAndPaperEq37OnAHandMadeLog) {
  // 1 s at error 0.3 m then 3 s at error 0.1 m: integral = 0.09 + 0.03 = 0.12 over 4 s.
  TrackingErrorAccumulator acc;
  for (int i = 0; i < 100; ++i) acc.Add(0.01, Vector3(0.3, 0, 0), Vector3::Zero());
  for (int i = 0; i < 300; ++i) acc.Add(0.01, Vector3(0, 0.06, 0.08), Vector3::Zero());
  EXPECT_NEAR(acc.duration(), 4.0, 1e-12);
  EXPECT_NEAR(acc.rmse(), std::sqrt(0.12 / 4.0), 1e-12);
  EXPECT_NEAR(acc.rmse_eq37(), std::sqrt(0.12) / 4.0, 1e-12);
  EXPECT_NEAR(acc.max_error(), 0.3, 1e-15);
}

TEST(TrackingError, EmptyIsZeroNotNan) {
  const TrackingErrorAccumulator acc;
  EXPECT_EQ(acc.rmse(), 0.0);
  EXPECT_EQ(acc.rmse_eq37(), 0.0);
}

}  // namespace
}  // namespace rotorguard::bench

#include "rotorguard/bench/ftc_bench.h"

namespace rotorguard::bench {
namespace {

TEST(FtcCell, MetricArithmeticOnHandMadeTrials) {
  // Four faulty trials: two correct isolations (0.02 s, 0.04 s), one detected 1.5 s late (counts as
  // missed), one false alarm before the onset; three successes; least altitude -0.2 m.
  std::vector<FtcTrial> t(4);
  for (auto& x : t) x.has_fdd = true;
  t[0] = {true, true, true, false, 0.02, 1.9, "", 11};
  t[1] = {true, true, true, false, 0.04, 1.8, "", 12};
  t[2] = {true, true, true, false, 1.5, 1.5, "", 13};
  t[3] = {false, true, false, true, -1.0, -0.2, "crash: ground impact at 3.00 m/s", 14};
  const nlohmann::json c = AggregateFtcCell(t, /*faulty=*/true);
  EXPECT_EQ(c["trials"], 4);
  EXPECT_NEAR(c["fdd_latency_s_mean"].get<double>(), (0.02 + 0.04 + 1.5) / 3.0, 1e-12);
  EXPECT_NEAR(c["fdd_latency_s_max"].get<double>(), 1.5, 1e-12);
  EXPECT_NEAR(c["sucr"].get<double>(), 0.75, 1e-12);
  EXPECT_NEAR(c["mdr"].get<double>(), 0.5, 1e-12);  // the late one and the false alarm
  EXPECT_NEAR(c["far"].get<double>(), 0.25, 1e-12);
  EXPECT_NEAR(c["mini_alt_m"].get<double>(), -0.2, 1e-12);
  ASSERT_EQ(c["failures"].size(), 1u);
  EXPECT_EQ(c["failures"][0]["seed"], 14);
}

TEST(FtcCell, MetricsWithoutFaultDetectionAreNull) {
  std::vector<FtcTrial> t(2);
  t[0].success = true;
  const nlohmann::json c = AggregateFtcCell(t, /*faulty=*/true);
  EXPECT_TRUE(c["mdr"].is_null());
  EXPECT_TRUE(c["far"].is_null());
  EXPECT_TRUE(c["fdd_latency_s_mean"].is_null());
  EXPECT_NEAR(c["sucr"].get<double>(), 0.5, 1e-12);
  EXPECT_TRUE(AggregateFtcCell({FtcTrial{true, true, false, false, -1.0, 1.0, "", 1}}, false)["mdr"].is_null());
}

}  // namespace
}  // namespace rotorguard::bench

namespace rotorguard::bench {
namespace {

fdd::RotorStatus Diagnosed(fdd::RotorHealth h, double t) {
  fdd::RotorStatus s;
  s.health = h;
  s.detected_s = t;
  s.detector = "test";
  return s;
}

TEST(ScoreFdd, CorrectLateWrongAndFalseDiagnosesOnHandMadeCases) {
  const std::vector<sim::FaultEvent> prop0 = {{0, vehicle::FaultKind::kPropellerLoss, 2.0}};
  std::vector<fdd::RotorStatus> rotors(4);
  EXPECT_FALSE(ScoreFdd(rotors, prop0).detected);  // missed
  rotors[0] = Diagnosed(fdd::RotorHealth::kPropellerFailed, 2.04);
  FddRecord r = ScoreFdd(rotors, prop0);
  EXPECT_TRUE(r.correct);
  EXPECT_NEAR(r.latency_s, 0.04, 1e-12);
  rotors[0] = Diagnosed(fdd::RotorHealth::kMotorFailed, 2.04);  // right rotor, wrong kind
  EXPECT_FALSE(ScoreFdd(rotors, prop0).correct);
  rotors[0] = fdd::RotorStatus{};
  rotors[2] = Diagnosed(fdd::RotorHealth::kPropellerFailed, 2.1);  // wrong rotor
  r = ScoreFdd(rotors, prop0);
  EXPECT_FALSE(r.correct);
  EXPECT_FALSE(r.false_alarm);
  rotors[2] = Diagnosed(fdd::RotorHealth::kPropellerFailed, 1.5);  // before the onset
  EXPECT_TRUE(ScoreFdd(rotors, prop0).false_alarm);
  EXPECT_TRUE(ScoreFdd(rotors, {}).false_alarm);  // no fault at all
  // The earliest diagnosis counts.
  rotors[1] = Diagnosed(fdd::RotorHealth::kMotorFailed, 1.0);
  EXPECT_EQ(ScoreFdd(rotors, prop0).rotor, 1);
}

// Nearest rank on a hand-made sample (unsorted on input): 1..101 shuffled.
TEST(Percentile, NearestRankOfTheSortedSample) {
  std::vector<double> v;
  for (int k = 101; k >= 1; --k) v.push_back(k % 2 ? k : 102 - k);  // every value 1..101 once
  EXPECT_EQ(Percentile(v, 0.0), 1.0);
  EXPECT_EQ(Percentile(v, 0.5), 51.0);
  EXPECT_EQ(Percentile(v, 0.99), 100.0);
  EXPECT_EQ(Percentile(v, 1.0), 101.0);
  EXPECT_EQ(Percentile({}, 0.5), 0.0);
  EXPECT_EQ(Percentile({4.0, 1.0}, 0.5), 4.0) << "index round(0.5) = 1";
}

}  // namespace
}  // namespace rotorguard::bench

#include "rotorguard/harness/flight_metrics.h"

#include <cmath>

#include <gtest/gtest.h>

namespace rotorguard::harness {
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

}  // namespace
}  // namespace rotorguard::harness

// Fault detection scored against injected faults (docs/metrics.md), on hand-made diagnoses.
#include "rotorguard/harness/fdd_score.h"

#include <gtest/gtest.h>

namespace rotorguard::harness {
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
  EXPECT_FALSE(ScoreFdd(rotors, prop0).detected());  // missed
  rotors[0] = Diagnosed(fdd::RotorHealth::kPropellerFailed, 2.04);
  FddRecord r = ScoreFdd(rotors, prop0);
  EXPECT_TRUE(r.correct);
  EXPECT_NEAR(r.latency_s.value_or(-1.0), 0.04, 1e-12);
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
  EXPECT_EQ(ScoreFdd(rotors, prop0).diagnosis->rotor, 1);
}

TEST(ScoreFdd, ReconfigurationLatencyIsTheFirstControlCycleWithoutTheDiagnosedRotor) {
  // Propeller 0 lost at 2.0 s, isolated at 2.04 s; the controller flew without rotor 3 (a known
  // fault) from 1.0 s and without rotor 0 from the cycle at 2.045 s.
  const std::vector<sim::FaultEvent> prop0 = {{0, vehicle::FaultKind::kPropellerLoss, 2.0}};
  std::vector<fdd::RotorStatus> rotors(4);
  rotors[0] = Diagnosed(fdd::RotorHealth::kPropellerFailed, 2.04);
  FddRecord r = ScoreFdd(rotors, prop0);
  AddReconfigurationLatency({{3, 1.0}, {0, 2.045}}, prop0, &r);
  EXPECT_NEAR(r.reconfiguration_latency_s.value_or(-1.0), 0.045, 1e-12);
  AddReconfigurationLatency({{3, 1.0}}, prop0, &r);  // never reconfigured for rotor 0
  EXPECT_FALSE(r.reconfiguration_latency_s.has_value());
  rotors[0] = Diagnosed(fdd::RotorHealth::kMotorFailed, 2.04);  // wrong kind: no latency of either sort
  r = ScoreFdd(rotors, prop0);
  AddReconfigurationLatency({{0, 2.045}}, prop0, &r);
  EXPECT_FALSE(r.reconfiguration_latency_s.has_value());
}

}  // namespace
}  // namespace rotorguard::harness

#include "rotorguard/sim/fault_injector.h"

#include <gtest/gtest.h>

#include "rotorguard/core/error.h"
#include "test_util.h"

namespace rotorguard::sim {
namespace {

using vehicle::FaultKind;

FaultSpec Spec(int rotor, FaultKind kind, FaultOnset::Kind onset, double value) {
  FaultSpec s;
  s.rotor = rotor;
  s.kind = kind;
  s.onset = {onset, value};
  return s;
}

TEST(FaultInjector, TriggersAtTimeAltitudeAndAfterLiftoff) {
  FaultInjector inj({Spec(0, FaultKind::kMotorStop, FaultOnset::Kind::kAtTime, 0.5),
                     Spec(1, FaultKind::kPropellerLoss, FaultOnset::Kind::kAtAltitude, 1.0),
                     Spec(2, FaultKind::kStuck, FaultOnset::Kind::kDuringTakeoff, 0.1)},
                    4);
  vehicle::RotorFaults f(4);
  // On the ground until t = 0.2 s, then climbing at 2 m/s.
  for (TimeNs t = 0; t <= 2'000'000'000; t += 1'000'000) {
    const double s = ToSeconds(t);
    const bool airborne = s >= 0.2;
    inj.Update(t, airborne ? 2.0 * (s - 0.2) : 0.0, airborne, &f);
  }
  ASSERT_EQ(inj.events().size(), 3u);
  EXPECT_EQ(inj.events()[0].rotor, 2);  // lift-off 0.2 s + 0.1 s
  EXPECT_NEAR(inj.events()[0].onset_s, 0.3, 1e-9);
  EXPECT_EQ(inj.events()[1].rotor, 0);
  EXPECT_NEAR(inj.events()[1].onset_s, 0.5, 1e-9);
  EXPECT_EQ(inj.events()[2].rotor, 1);  // 1 m reached at 0.7 s
  EXPECT_NEAR(inj.events()[2].onset_s, 0.7, 1e-9);
  EXPECT_EQ(f[0].kind, FaultKind::kMotorStop);
  EXPECT_EQ(f[3].kind, FaultKind::kNone);
}

TEST(FaultInjector, AltitudeOnsetNeedsAnUpwardCrossingAndTakeoffOnsetALiftoff) {
  FaultInjector inj({Spec(0, FaultKind::kMotorStop, FaultOnset::Kind::kAtAltitude, 0.5),
                     Spec(1, FaultKind::kMotorStop, FaultOnset::Kind::kDuringTakeoff, 0.0)},
                    4);
  vehicle::RotorFaults f(4);
  // Starts airborne at 1 m (above the onset altitude), descends to 0.2 m, climbs back to 1 m.
  for (int k = 0; k <= 300; ++k) {
    const double z = k < 100 ? 1.0 - 0.008 * k : 0.2 + 0.004 * (k - 100);
    inj.Update(FromSeconds(0.01 * k), z, true, &f);
  }
  ASSERT_EQ(inj.events().size(), 1u);  // never landed: no take-off onset
  EXPECT_EQ(inj.events()[0].rotor, 0);
  EXPECT_NEAR(inj.events()[0].onset_s, 1.75, 1e-9);  // 0.2 + 0.004 (k - 100) = 0.5 at k = 175
}

TEST(FaultInjector, IntermittentFaultsToggleWithTheirPeriods) {
  FaultSpec s = Spec(3, FaultKind::kLossOfEffectiveness, FaultOnset::Kind::kAtTime, 1.0);
  s.eta = 0.5;
  s.intermittent = IntermittentPattern{0.2, 0.3};
  FaultInjector inj({s}, 4);
  vehicle::RotorFaults f(4);
  const auto active_at = [&](double t) {
    inj.Update(FromSeconds(t), 1.0, true, &f);
    return f[3].kind == FaultKind::kLossOfEffectiveness;
  };
  EXPECT_FALSE(active_at(0.9));
  EXPECT_TRUE(active_at(1.0));
  EXPECT_TRUE(active_at(1.19));
  EXPECT_FALSE(active_at(1.2));
  EXPECT_FALSE(active_at(1.49));
  EXPECT_TRUE(active_at(1.5));
  EXPECT_EQ(f[3].eta, 0.5);
  EXPECT_EQ(inj.events().size(), 1u);  // one onset, however often it toggles
}

TEST(FaultSpec, ValidationNamesTheKeyPath) {
  FaultSpec s = Spec(4, FaultKind::kMotorStop, FaultOnset::Kind::kAtTime, 1.0);
  RG_EXPECT_THROW_WITH(s.Validate(2, 4, 10.0), ValidationError, "faults.2.rotor = 4");
  s.rotor = 0;
  s.onset.value = 12.0;
  RG_EXPECT_THROW_WITH(s.Validate(0, 4, 10.0), ValidationError, "faults.0.onset.at_time_s = 12");
  s.onset.value = 1.0;
  s.kind = FaultKind::kLossOfEffectiveness;
  s.eta = 1.0;
  RG_EXPECT_THROW_WITH(s.Validate(0, 4, 10.0), ValidationError, "faults.0.eta");
}

}  // namespace
}  // namespace rotorguard::sim

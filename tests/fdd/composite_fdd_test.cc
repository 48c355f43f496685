// The composite FDD on synthetic sensor streams of a hovering reference quadrotor, where the truth
// is known exactly: speeds from the drive thrusts, specific force and rates from the thrusts that
// actually act.

#include "rotorguard/fdd/composite_fdd.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rotorguard/core/error.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/fdd/fixed_time_fdd.h"
#include "rotorguard/vehicle/effectiveness.h"
#include "vehicle_fixture.h"

namespace rotorguard::fdd {
namespace {

using rotorguard::testing::ReferenceQuad;

/// The bench below drives its motors' telemetry straight from the drive thrusts, faster than any
/// motor: the motor shortfall rule, which bounds how fast a healthy motor can slow, is off on it
/// (FlyLaggingMotors below flies it).
CompositeFddOptions WithoutShortfall() {
  CompositeFddOptions o;
  o.motor_shortfall_threshold = 1.0;
  return o;
}

template <typename Options>
Options BenchDefaults() {
  return Options{};
}
template <>
CompositeFddOptions BenchDefaults() {
  return WithoutShortfall();
}

/// A vehicle hovering at 1 m whose rotors drive `drive` thrusts while `actual` thrusts act (they
/// differ by the fault); integrates the rotation the torque imbalance causes and feeds the FDD
/// IMU (333 Hz, polled at 1 kHz), telemetry (1 kHz) and estimates (200 Hz).
template <typename Detector, typename Options>
class BenchOf {
 public:
  explicit BenchOf(double noise = 0.0, Options options = BenchDefaults<Options>())
      : vehicle_(ReferenceQuad()), fdd_(vehicle_, options), rng_(3), noise_(noise) {
    hover_ = RotorVector::Constant(4, vehicle_.weight_n() / 4.0);
    drive_ = actual_ = hover_;
    effectiveness_ = vehicle::ComputeEffectivenessMatrix(vehicle_.rotors);
  }
  /// Runs for `seconds`; returns the time of the first isolation, if any.
  std::optional<double> Run(double seconds, double altitude = 1.0) {
    const TimeNs end = t_ + FromSeconds(seconds);
    for (; t_ < end; t_ += 1'000'000) {
      const double dt = 1e-3;
      const Eigen::Vector4d wrench = effectiveness_ * actual_;
      // Euler's equation, eq. (3) of paper 000, for the rotation the imbalance causes.
      const Matrix3& I = vehicle_.inertia_kg_m2;
      const Vector3 alpha =
          I.inverse() * (wrench.tail<3>() - w_.cross(I * w_) - Vector3(0, 0, vehicle_.yaw_damping_n_m_s * w_.z()));
      w_ += alpha * dt;
      if (t_ % 1'000'000 == 0) {
        EscTelemetry esc;
        esc.t_ns = t_;
        esc.motor_speed_rad_s = (drive_ / vehicle_.thrust_coefficient_n_s2).cwiseSqrt();
        for (int i = 0; i < 4; ++i) esc.motor_speed_rad_s[i] += noise_ * 2.0 * rng_.Normal();
        fdd_.OnEscTelemetry(esc);
      }
      if (t_ % 3'000'000 == 0) {
        ImuSample imu;
        imu.t_ns = t_;
        imu.specific_force_B = Vector3(0, 0, wrench[0] / vehicle_.mass_kg + force_bias_);
        imu.w_B = w_;
        for (int i = 0; i < 3; ++i) {
          imu.specific_force_B[i] += noise_ * 0.05 * rng_.Normal();
          imu.w_B[i] += noise_ * 0.005 * rng_.Normal();
        }
        fdd_.OnImu(imu);
      }
      if (t_ % 5'000'000 == 0) {
        StateEstimate e;
        e.t_ns = t_;
        e.valid = true;
        e.p_W = Vector3(0, 0, altitude);
        fdd_.SetEstimate(e);
        fdd_.SetCommand(RotorCommand{t_, drive_});
      }
      for (int i = 0; i < 4; ++i) {
        if (fdd_.rotors()[i].detected_s && !first_) first_ = *fdd_.rotors()[i].detected_s;
      }
    }
    return first_;
  }
  double now() const { return ToSeconds(t_); }

  vehicle::VehicleParams vehicle_;
  Detector fdd_;
  Rng rng_;
  double noise_;
  RotorVector hover_, drive_, actual_;
  EffectivenessMatrix effectiveness_;
  Vector3 w_ = Vector3::Zero();
  double force_bias_ = 0.0;  ///< added to the accelerometer's z [m/s^2]
  TimeNs t_ = 0;
  std::optional<double> first_;
};

using Bench = BenchOf<CompositeFdd, CompositeFddOptions>;

TEST(CompositeFdd, NoDetectionOnNoiseOnly) {
  Bench b(1.0);
  EXPECT_FALSE(b.Run(5.0));
}

TEST(CompositeFdd, IsolatesAStoppedMotorOfEveryRotorFromTelemetry) {
  for (int rotor = 0; rotor < 4; ++rotor) {
    Bench b(1.0);
    ASSERT_FALSE(b.Run(1.0));
    const double onset = b.now();
    b.drive_[rotor] = 0.0;  // the motor stops: no speed, no thrust
    b.actual_[rotor] = 0.0;
    const auto detected = b.Run(0.5);
    ASSERT_TRUE(detected) << "rotor " << rotor;
    EXPECT_EQ(b.fdd_.rotors()[rotor].health, RotorHealth::kMotorFailed);
    EXPECT_EQ(b.fdd_.rotors()[rotor].detector, "motor_index");
    EXPECT_LE(*detected - onset, 0.003);  // two telemetry samples (debounce) after the collapse
    EXPECT_EQ(b.fdd_.TakeNewIsolations(), std::vector<int>{rotor});
    EXPECT_TRUE(b.fdd_.TakeNewIsolations().empty());  // reported once
  }
}

TEST(CompositeFdd, IsolatesAnEjectedPropellerOfEveryRotorFromTheMotion) {
  for (int rotor = 0; rotor < 4; ++rotor) {
    Bench b(1.0);
    ASSERT_FALSE(b.Run(1.0));
    const double onset = b.now();
    b.actual_[rotor] = 0.0;  // telemetry unchanged: only the motion tells
    const auto detected = b.Run(0.5);
    ASSERT_TRUE(detected) << "rotor " << rotor;
    EXPECT_EQ(b.fdd_.rotors()[rotor].health, RotorHealth::kPropellerFailed) << "rotor " << rotor;
    EXPECT_EQ(b.fdd_.rotors()[rotor].detector, "thrust_loss_observer");
    EXPECT_LT(*detected - onset, 0.1);
    ASSERT_TRUE(b.fdd_.rotors()[rotor].onset_s);
    EXPECT_GE(*b.fdd_.rotors()[rotor].onset_s, onset);
    EXPECT_LE(*b.fdd_.rotors()[rotor].onset_s, *detected);
    for (int other = 0; other < 4; ++other) {
      if (other != rotor) {
        EXPECT_EQ(b.fdd_.rotors()[other].health, RotorHealth::kOk);
      }
    }
  }
}

/// Rotor 0's motor stops; the others move to the post-failure split through the motor lag.
void AfterAFailureOfRotor0(Bench* b) {
  const double w = b->vehicle_.weight_n();
  const RotorVector target = (RotorVector(4) << 0.0, 0.0, w / 2.0, w / 2.0).finished();
  b->drive_[0] = b->actual_[0] = 0.0;
  for (int k = 0; k < 300; ++k) {
    b->drive_ += (1.0 - std::exp(-1e-3 / b->vehicle_.motor_time_constant_s)) * (target - b->drive_);
    b->actual_ = b->drive_;
    b->Run(1e-3);
  }
}

TEST(CompositeFdd, AfterAnIsolationTheObserverIsolatesASecondPropellerLossInTheSpin) {
  for (int second : {2, 3}) {
    Bench b(1.0);
    ASSERT_FALSE(b.Run(1.0));
    // Rotor 0's motor stops; its diagonal twin (1) idles and 2 and 3 carry half the weight each,
    // the post-failure split: no roll or pitch torque, and a yaw torque that spins the vehicle up.
    // The others follow through the motor lag, as their telemetry would.
    AfterAFailureOfRotor0(&b);
    ASSERT_TRUE(b.Run(4.0));
    ASSERT_EQ(b.fdd_.TakeNewIsolations(), std::vector<int>{0});
    EXPECT_GT(b.w_.z(), 9.0);  // spinning, as paper 000's vehicle at 11 rad/s
    for (int i = 1; i < 4; ++i) EXPECT_EQ(b.fdd_.rotors()[i].health, RotorHealth::kOk) << "rotor " << i;
    const double onset = b.now();
    b.actual_[second] = 0.0;  // its propeller is lost: telemetry unchanged
    b.Run(0.5);
    const RotorStatus& status = b.fdd_.rotors()[second];
    EXPECT_EQ(status.health, RotorHealth::kPropellerFailed) << "rotor " << second;
    EXPECT_EQ(status.detector, "thrust_loss_observer");
    ASSERT_TRUE(status.detected_s);
    EXPECT_LT(*status.detected_s - onset, 0.1);
    EXPECT_EQ(b.fdd_.TakeNewIsolations(), std::vector<int>{second});
    EXPECT_EQ(b.fdd_.rotors()[1].health, RotorHealth::kOk);
    EXPECT_EQ(b.fdd_.rotors()[5 - second].health, RotorHealth::kOk);
  }
}

// The blind time after an isolation is the reconfiguration's step through the motor lag and the
// filters, a tenth of a second: a second loss 0.3 s after the isolation is isolated at once.
TEST(CompositeFdd, ASecondLossAFewTenthsAfterTheIsolationIsIsolatedAtOnce) {
  Bench b(1.0);
  ASSERT_FALSE(b.Run(2.0));   // past the first learning in the air (three baseline time constants)
  AfterAFailureOfRotor0(&b);  // isolated within milliseconds, then 0.3 s of reconfiguration
  ASSERT_EQ(b.fdd_.TakeNewIsolations(), std::vector<int>{0});
  const double onset = b.now();
  b.actual_[2] = 0.0;
  b.Run(0.3);
  const RotorStatus& status = b.fdd_.rotors()[2];
  ASSERT_EQ(status.health, RotorHealth::kPropellerFailed);
  EXPECT_LT(*status.detected_s - onset, 0.1);
  EXPECT_EQ(b.fdd_.rotors()[3].health, RotorHealth::kOk);
}

// A lost propeller on a vehicle spinning on three rotors reads P_i between 0.74 and 0.98: it dips
// below gamma_P and comes back. The second-failure rule asks that most of the last 50 ms be above
// gamma_P, not all of it: a loss that lets the rotor's thrust back for 10 ms in every 45 (its P_i
// under 0.8 in each period) is isolated, where a rule restarting at every dip never would be.
TEST(CompositeFdd, ASecondLossWhoseIndexDipsBelowTheThresholdIsIsolatedByMostOfItsWindow) {
  Bench b(1.0);
  ASSERT_FALSE(b.Run(2.0));
  AfterAFailureOfRotor0(&b);
  ASSERT_EQ(b.fdd_.TakeNewIsolations(), std::vector<int>{0});
  const double onset = b.now();
  double lowest = 1.0;
  for (int period = 0; period < 10 && b.fdd_.rotors()[2].health == RotorHealth::kOk; ++period) {
    b.actual_[2] = 0.0;
    b.Run(0.035);
    b.actual_[2] = b.drive_[2];
    for (int ms = 0; ms < 10; ++ms) {
      b.Run(1e-3);
      lowest = std::min(lowest, b.fdd_.rotors()[2].propeller_index);
    }
  }
  EXPECT_LT(lowest, 0.8) << "the index must dip below gamma_P for the case to mean anything";
  const RotorStatus& status = b.fdd_.rotors()[2];
  ASSERT_EQ(status.health, RotorHealth::kPropellerFailed);
  EXPECT_LT(*status.detected_s - onset, 0.15);
  EXPECT_EQ(b.fdd_.rotors()[3].health, RotorHealth::kOk);
  EXPECT_EQ(b.fdd_.rotors()[1].health, RotorHealth::kOk);
}

// In the air a spinning vehicle's force balance swings (its thrust model errors at strongly unequal
// rotor speeds): the accelerometer reading a third of the weight more than the rotors give, while
// they carry the weight, is not the ground. Taken for it, the observer would disarm and relearn,
// blind to a second loss that follows.
TEST(CompositeFdd, AForceBalanceSwingInTheAirIsNotTakenForTheGround) {
  Bench b(1.0);
  ASSERT_FALSE(b.Run(1.0));
  AfterAFailureOfRotor0(&b);
  b.Run(1.0);
  b.force_bias_ = 0.33 * kGravity;
  b.Run(0.1);
  b.force_bias_ = 0.0;
  b.Run(0.1);
  const double onset = b.now();
  b.actual_[3] = 0.0;
  b.Run(0.3);
  const RotorStatus& status = b.fdd_.rotors()[3];
  ASSERT_EQ(status.health, RotorHealth::kPropellerFailed);
  EXPECT_LT(*status.detected_s - onset, 0.1);
}

TEST(CompositeFdd, ASecondLossWithinTheRelearningIsNotJudgedUntilItEnds) {
  for (double relearn : {2.0, 0.0}) {
    CompositeFddOptions o = WithoutShortfall();
    o.post_isolation_relearn_s = relearn;
    Bench b(1.0, o);
    ASSERT_FALSE(b.Run(1.0));
    AfterAFailureOfRotor0(&b);
    b.Run(0.7);  // isolated within milliseconds, then relearning until about 3 s
    b.actual_[2] = 0.0;
    b.Run(0.5);
    // Within the relearning the loss is not judged; without it, it is isolated.
    EXPECT_EQ(b.fdd_.rotors()[2].health, relearn > 0.0 ? RotorHealth::kOk : RotorHealth::kPropellerFailed);
  }
}

TEST(CompositeFdd, HealthyExtremesAreTheIndicesMostAlarmingValuesUntilTheFirstIsolation) {
  Bench b(1.0);
  ASSERT_FALSE(b.Run(2.0));
  const IndexExtremes healthy = b.fdd_.healthy_extremes();
  // Telemetry noise of 2 rad/s on ~1400 rad/s moves M_i by about 0.1 %; P_i stays near 0.
  EXPECT_LT(healthy.min_motor_index, 1.0);
  EXPECT_GT(healthy.min_motor_index, 0.99);
  EXPECT_GT(healthy.max_propeller_index, 0.0);
  EXPECT_LT(healthy.max_propeller_index, 0.15);
  EXPECT_EQ(healthy.max_takeoff_index, 0.0);  // hovering at 1 m: no take-off
  b.drive_[1] = b.actual_[1] = 0.0;
  ASSERT_TRUE(b.Run(0.1));
  const IndexExtremes at_isolation = b.fdd_.healthy_extremes();
  EXPECT_LT(at_isolation.min_motor_index, 0.2);  // the stop's first low sample came before it
  b.actual_[2] = 0.0;                            // what follows the isolation no longer counts
  b.Run(1.0);
  EXPECT_EQ(b.fdd_.healthy_extremes().max_propeller_index, at_isolation.max_propeller_index);
}

// Each rule's statistic in healthy_extremes is exactly where its threshold starts to fire: the
// same flight, flown again with the threshold just past the statistic's extreme, isolates by that
// rule; just short of it, it isolates nothing. The three flights: telemetry noise 30x the
// default (the motor index), a 50 % loss of rotor 1 in hover (the propeller index held 15 ms), a
// 70 % loss of rotor 1 at 0.3 m within the take-off window (the take-off index through its gates).
TEST(CompositeFdd, EachRulesStatisticIsExactlyItsAlarmBoundary) {
  struct Case {
    const char* detector;
    double CompositeFddOptions::*threshold;
    double IndexExtremes::*statistic;
    bool alarm_when_low;
    double noise, altitude, remaining_thrust;
  };
  const Case cases[] = {
      {"motor_index", &CompositeFddOptions::motor_index_threshold, &IndexExtremes::debounced_motor_index, true, 30.0,
       1.0, 1.0},
      {"motor_shortfall", &CompositeFddOptions::motor_shortfall_threshold, &IndexExtremes::debounced_motor_shortfall,
       false, 30.0, 1.0, 1.0},
      {"thrust_loss_observer", &CompositeFddOptions::propeller_index_threshold,
       &IndexExtremes::persistent_propeller_index, false, 1.0, 1.0, 0.5},
      {"takeoff", &CompositeFddOptions::takeoff_index_threshold, &IndexExtremes::gated_takeoff_index, false, 1.0, 0.3,
       0.3},
  };
  for (const Case& c : cases) {
    // Every rule out of reach but the one under test; the flight does not depend on thresholds
    // until an isolation.
    const auto fly = [&](std::optional<double> threshold) {
      CompositeFddOptions o = CompositeFddOptions{}.Disarmed();
      if (threshold) o.*c.threshold = *threshold;
      auto b = std::make_unique<Bench>(c.noise, o);
      b->Run(0.3, c.altitude);
      b->actual_[1] *= c.remaining_thrust;
      b->Run(0.7, c.altitude);
      return b;
    };
    const IndexExtremes e = fly(std::nullopt)->fdd_.healthy_extremes();
    const double extreme = e.*c.statistic;
    ASSERT_GT(extreme, 0.0) << c.detector;
    ASSERT_LT(extreme, c.alarm_when_low ? 1.0 : 1e6) << c.detector;
    // The motor rule fires at or below gamma_M, the others above their thresholds.
    const double fires = c.alarm_when_low ? extreme : extreme * (1.0 - 1e-9);
    const double silent = c.alarm_when_low ? extreme * (1.0 - 1e-9) : extreme * (1.0 + 1e-9);
    const auto alarmed = fly(fires);
    ASSERT_TRUE(alarmed->fdd_.first_isolated_rotor()) << c.detector << " at " << fires;
    EXPECT_EQ(alarmed->fdd_.rotors()[*alarmed->fdd_.first_isolated_rotor()].detector, c.detector);
    EXPECT_FALSE(fly(silent)->fdd_.first_isolated_rotor()) << c.detector << " at " << silent;
    // The rule's statistic is never more alarming than the index itself.
    EXPECT_GE(e.debounced_motor_index, e.min_motor_index);
    EXPECT_LE(e.persistent_propeller_index, e.max_propeller_index);
    EXPECT_LE(e.gated_takeoff_index, e.max_takeoff_index);
  }
}

// The second-failure rule's statistic likewise: rotor 0's motor stops (the motor rule isolates
// it), then rotor 2 loses 60 % of its thrust; gamma_P just under the statistic isolates rotor 2,
// just over it isolates nothing more. gamma_P is also the first failure's threshold, which the
// healthy hover before the stop stays far from.
TEST(CompositeFdd, TheSecondFailuresStatisticIsExactlyItsAlarmBoundary) {
  const auto fly = [](double threshold) {
    CompositeFddOptions o = WithoutShortfall();
    o.propeller_index_threshold = threshold;
    auto b = std::make_unique<Bench>(1.0, o);
    b->Run(2.0);
    AfterAFailureOfRotor0(b.get());
    b->actual_[2] *= 0.4;
    b->Run(0.5);
    return b;
  };
  const auto unarmed = fly(1.0);
  ASSERT_EQ(unarmed->fdd_.first_isolated_rotor(), 0);
  const double extreme = unarmed->fdd_.healthy_extremes().second_failure_index;
  ASSERT_GT(extreme, 0.3);
  ASSERT_LT(extreme, 1.0);
  EXPECT_EQ(fly(extreme * (1.0 - 1e-9))->fdd_.rotors()[2].health, RotorHealth::kPropellerFailed);
  const auto silent = fly(extreme * (1.0 + 1e-9));
  for (int i = 1; i < 4; ++i) EXPECT_EQ(silent->fdd_.rotors()[i].health, RotorHealth::kOk) << "rotor " << i;
}

TEST(CompositeFdd, ThresholdsAreInUnitsOfTheVehiclesHoverThrustAndOneRotorsTurn) {
  // X layout, arms a along x and y: losing a rotor's W/4 turns the vehicle at a W/4 / I_xx about x
  // and a W/4 / I_yy about y (eq. 3 at rest).
  const vehicle::VehicleParams v = ReferenceQuad();
  const CompositeFdd fdd(v, {});
  const double a = std::abs(v.rotors[0].p_B.x()), share = v.weight_n() / 4.0;
  EXPECT_NEAR(fdd.hover_thrust_per_rotor_n(), share, 1e-12);
  EXPECT_NEAR(fdd.one_rotor_angular_acceleration_rad_s2(),
              std::hypot(a * share / v.inertia_kg_m2(0, 0), a * share / v.inertia_kg_m2(1, 1)), 1e-9);
  // Twice as heavy and as stiff, with rotors twice as strong: the same thresholds, in newtons and
  // rad/s^2 twice and once the reference's.
  vehicle::VehicleParams heavy = v;
  heavy.mass_kg *= 2.0;
  heavy.inertia_kg_m2 *= 2.0;
  for (vehicle::Rotor& r : heavy.rotors) r.max_thrust_n *= 2.0;
  const CompositeFdd scaled(heavy, {});
  EXPECT_NEAR(scaled.hover_thrust_per_rotor_n(), 2.0 * share, 1e-12);
  EXPECT_NEAR(scaled.one_rotor_angular_acceleration_rad_s2(), fdd.one_rotor_angular_acceleration_rad_s2(), 1e-9);
}

TEST(CompositeFdd, ReportsAPersistentPartialLossAsDegradationWithItsEta) {
  Bench b(1.0);
  ASSERT_FALSE(b.Run(2.0));  // past the baseline's learning (3 x 0.5 s in the air)
  const double onset = b.now();
  b.actual_[2] = 0.6 * b.hover_[2];  // eta = 0.4, a ramp-free step
  b.Run(2.0);
  const RotorStatus& r = b.fdd_.rotors()[2];
  EXPECT_EQ(r.health, RotorHealth::kDegraded);
  EXPECT_NEAR(r.eta, 0.4, 0.05);
  ASSERT_TRUE(r.onset_s);
  EXPECT_GE(*r.onset_s, onset);                     // dated by the first sample past the threshold ...
  EXPECT_LT(*r.onset_s, onset + 0.05);              // ... through the observer's 20 Hz filters
  EXPECT_TRUE(b.fdd_.TakeNewIsolations().empty());  // degradation does not isolate the rotor
}

TEST(CompositeFdd, MeasuresLossesFromTheResidualOfTheVehicleAsItFlies) {
  // Rotor 0's telemetry reads 25 % more thrust than it gives (a thrust coefficient the file has
  // wrong): to the file's model rotor 0 loses a fifth of its thrust, from the start. The baseline
  // learns that residual; a later true partial loss of rotor 2 is measured from it.
  for (const double time_constant : {0.5, 0.0}) {
    CompositeFddOptions o = WithoutShortfall();
    o.baseline_time_constant_s = time_constant;
    Bench b(1.0, o);
    b.drive_[0] = 1.25 * b.hover_[0];
    const auto detected = b.Run(3.0);
    if (time_constant == 0.0) {  // the file's model alone: a false partial loss
      EXPECT_EQ(b.fdd_.rotors()[0].health, RotorHealth::kDegraded);
      continue;
    }
    EXPECT_FALSE(detected);
    // The residual: thrust 0.25 T_h missing along z, and its torque at rotor 0.
    const Eigen::Vector4d expected = b.effectiveness_.col(0) * 0.25 * b.hover_[0];
    EXPECT_LT((b.fdd_.baseline() - expected).norm(), 0.05 * expected.norm()) << b.fdd_.baseline().transpose();
    b.actual_[2] = 0.6 * b.hover_[2];
    b.Run(2.0);
    EXPECT_EQ(b.fdd_.rotors()[2].health, RotorHealth::kDegraded);
    EXPECT_NEAR(b.fdd_.rotors()[2].eta, 0.4, 0.05);
    EXPECT_EQ(b.fdd_.rotors()[0].health, RotorHealth::kOk);
  }
}

TEST(CompositeFdd, TakeoffDetectorIgnoresATurnThatCostsNoThrust) {
  // Just after lift-off rotor 0 gives 1 N more and rotor 1, its diagonal twin, 1 N less than
  // their telemetry says (as a centre of gravity off the file's does): the vehicle turns as if
  // rotor 1 were lost, at 18 rad/s², but no thrust is missing.
  for (const double fraction : {0.5, 0.0}) {
    CompositeFddOptions o = WithoutShortfall();
    o.takeoff_missing_thrust_fraction = fraction;
    Bench b(1.0, o);
    ASSERT_FALSE(b.Run(0.2, 0.02));
    b.actual_[0] += 1.0;
    b.actual_[1] -= 1.0;
    const auto detected = b.Run(0.2, 0.02);
    if (fraction == 0.0) {  // the direction and magnitude alone would isolate rotor 1
      EXPECT_TRUE(detected);
      EXPECT_EQ(b.fdd_.rotors()[1].detector, "takeoff");
    } else {
      EXPECT_FALSE(detected) << b.fdd_.rotors()[1].detector;
    }
  }
}

TEST(CompositeFdd, ATouchdownsBounceDoesNotOpenTheTakeoffWindowALiftOffFromRestDoes) {
  // On the ground the rotors lift half the weight and the accelerometer reads the rest (the ground
  // carries it); in the air they lift it all. A rotor lost 50 ms after leaving the ground is the
  // take-off detector's case when the vehicle rested there 0.5 s, not after a 50 ms bounce (a
  // touchdown rocks the vehicle on its feet as a lost rotor turns it).
  for (const double rest_s : {0.05, 0.5}) {
    CompositeFddOptions o = WithoutShortfall();
    o.propeller_persistence_s = 1.0;  // keep the observer's own isolation out of the way
    Bench b(1.0, o);
    ASSERT_FALSE(b.Run(4.0, 0.02));  // low hover: the window of the flight's start has closed
    b.drive_ = b.actual_ = 0.5 * b.hover_;
    b.force_bias_ = 0.5 * kGravity;
    ASSERT_FALSE(b.Run(rest_s, 0.0));
    b.drive_ = b.actual_ = b.hover_;
    b.force_bias_ = 0.0;
    ASSERT_FALSE(b.Run(0.05, 0.02));
    b.actual_[0] = 0.0;
    const auto detected = b.Run(0.2, 0.02);
    if (rest_s >= o.takeoff_rest_s) {
      ASSERT_TRUE(detected);
      EXPECT_EQ(b.fdd_.rotors()[0].detector, "takeoff");
    } else {
      EXPECT_FALSE(detected) << b.fdd_.rotors()[0].detector;
    }
  }
}

TEST(CompositeFdd, BackInTheGroundBandTheObserverHoldsAndTheMotorIndexWatches) {
  // A touchdown rocks the vehicle on its legs as a lost rotor would turn it, while the rotors still
  // lift the weight: the observer holds within 5 cm of the ground once the flight has been above
  // the take-off detector's altitude.
  // The same turn at 10 cm is a lost propeller; a motor that stops in the band is still isolated.
  Bench b(1.0);
  ASSERT_FALSE(b.Run(1.0, 1.0));
  ASSERT_FALSE(b.Run(0.05, 0.03));
  b.actual_[0] = 0.0;
  EXPECT_FALSE(b.Run(0.2, 0.03)) << b.fdd_.rotors()[0].detector;
  ASSERT_TRUE(b.Run(0.3, 0.10));  // within takeoff_rest_s of touching down: no take-off window
  EXPECT_EQ(b.fdd_.rotors()[0].detector, "thrust_loss_observer");

  Bench m(1.0);
  ASSERT_FALSE(m.Run(1.0, 1.0));
  ASSERT_FALSE(m.Run(0.2, 0.03));
  m.drive_[1] = m.actual_[1] = 0.0;
  ASSERT_TRUE(m.Run(0.1, 0.03));
  EXPECT_EQ(m.fdd_.rotors()[1].detector, "motor_index");

  // A take-off whose estimate crosses the band's edge and back (it lags the climb) is no touchdown:
  // below the take-off detector's altitude the band does not hold the observer.
  Bench c(1.0);
  ASSERT_FALSE(c.Run(0.2, 0.08));
  ASSERT_FALSE(c.Run(0.05, 0.03));
  c.actual_[2] = 0.0;
  ASSERT_TRUE(c.Run(0.3, 0.03));
  EXPECT_EQ(c.fdd_.rotors()[2].health, RotorHealth::kPropellerFailed);
}

TEST(CompositeFdd, TheFlightsFirstLiftOffOpensTheTakeoffWindowHoweverShortTheRest) {
  // A take-off whose motors spin up at once leaves the ground 0.1 s after the start.
  CompositeFddOptions o = WithoutShortfall();
  o.propeller_persistence_s = 1.0;
  Bench b(1.0, o);
  b.drive_ = b.actual_ = 0.5 * b.hover_;
  b.force_bias_ = 0.5 * kGravity;
  ASSERT_FALSE(b.Run(0.1, 0.0));
  b.drive_ = b.actual_ = b.hover_;
  b.force_bias_ = 0.0;
  ASSERT_FALSE(b.Run(0.05, 0.02));
  b.actual_[2] = 0.0;
  ASSERT_TRUE(b.Run(0.2, 0.02));
  EXPECT_EQ(b.fdd_.rotors()[2].detector, "takeoff");
}

TEST(CompositeFdd, ARampLossCrossesIntoPropellerFailure) {
  Bench b(1.0);
  ASSERT_FALSE(b.Run(1.0));
  for (int k = 1; k <= 20; ++k) {  // loses 5 % of its thrust every 50 ms
    b.actual_[1] = (1.0 - 0.05 * k) * b.hover_[1];
    b.Run(0.05);
  }
  b.Run(0.2);
  EXPECT_EQ(b.fdd_.rotors()[1].health, RotorHealth::kPropellerFailed);
}

TEST(CompositeFdd, TakeoffDetectorIsolatesEveryRotorJustAfterLiftOff) {
  for (int rotor = 0; rotor < 4; ++rotor) {
    CompositeFddOptions o = WithoutShortfall();
    o.propeller_persistence_s = 1.0;  // keep the observer's own isolation out of the way
    Bench b(1.0, o);
    ASSERT_FALSE(b.Run(0.2, 0.02));  // lifting off: thrust at weight, 2 cm up
    const double onset = b.now();
    b.actual_[rotor] = 0.0;
    const auto detected = b.Run(0.2, 0.02);
    ASSERT_TRUE(detected) << "rotor " << rotor;
    EXPECT_EQ(b.fdd_.rotors()[rotor].detector, "takeoff") << "rotor " << rotor;
    EXPECT_EQ(b.fdd_.rotors()[rotor].health, RotorHealth::kPropellerFailed);
    EXPECT_LT(*detected - onset, 0.03);
  }
}

TEST(FixedTimeFdd, IsolatesEveryRotorFromTheObserverWithoutTelemetry) {
  // The FixedA baseline sees only commands, IMU and estimates: it isolates the rotor, not the kind.
  for (int rotor = 0; rotor < 4; ++rotor) {
    for (bool motor : {false, true}) {
      BenchOf<FixedTimeFdd, FixedTimeFddOptions> b(1.0);
      ASSERT_FALSE(b.Run(1.0));
      const double onset = b.now();
      b.actual_[rotor] = 0.0;
      if (motor) b.drive_[rotor] = 0.0;
      const auto detected = b.Run(1.0);
      ASSERT_TRUE(detected) << "rotor " << rotor;
      EXPECT_EQ(b.fdd_.rotors()[rotor].health, RotorHealth::kFailed);
      EXPECT_LT(*detected - onset, 0.3);
    }
  }
  BenchOf<FixedTimeFdd, FixedTimeFddOptions> quiet(1.0);
  EXPECT_FALSE(quiet.Run(5.0));  // noise only
}

TEST(FixedTimeFdd, FiltersAtTheCompositeFddsCutOff) {
  // A fair comparison: the baseline's filters pass what ours pass.
  EXPECT_EQ(FixedTimeFddOptions{}.estimate_cutoff_hz, CompositeFddOptions{}.filter_cutoff_hz);
}

/// Motors that follow their commands through eq. (6) with their own time constant (sigma_ratio
/// times the file's) and delay, integrated exactly in 0.1 ms steps; telemetry at 1 kHz with speed
/// noise, commands at 200 Hz whose level per rotor steps every 20 ms between 0.3 and 1.5 of the
/// hover thrust per rotor (a vehicle manoeuvring hard). Only telemetry and commands: the motor
/// rules alone judge. `stop_rotor`, held at hover, coasts down from stop_at_s with its own time
/// constant (a motor stop, as the simulator draws it).
struct LaggingMotors {
  double sigma_ratio = 1.0;
  double delay_s = 0.0;
  int stop_rotor = -1;
  double stop_at_s = 0.0, stop_time_constant_s = 0.05;
};

struct LaggingFlight {
  std::optional<double> detected_s;
  std::string detector;
  IndexExtremes extremes;
};

LaggingFlight FlyLaggingMotors(const LaggingMotors& m, const CompositeFddOptions& options, std::uint64_t seed) {
  const vehicle::VehicleParams vehicle = ReferenceQuad();
  CompositeFdd fdd(vehicle, options);
  Rng rng(seed);
  const double hover = vehicle.weight_n() / 4.0, sigma = m.sigma_ratio * vehicle.motor_time_constant_s;
  RotorVector level = RotorVector::Constant(4, hover), thrust = level;
  std::vector<std::pair<double, RotorVector>> commands;  // (instant, thrusts), all of the flight
  std::size_t acting = 0;
  LaggingFlight out;
  constexpr double kStep = 1e-4;
  for (int k = 0; k <= 20000; ++k) {  // 2 s
    const double t = k * kStep;
    if (k % 200 == 0) {
      for (int i = 0; i < 4; ++i) level[i] = i == m.stop_rotor ? hover : hover * rng.Uniform(0.3, 1.5);
    }
    if (k % 50 == 0) {
      commands.emplace_back(t, level);
      fdd.SetCommand(RotorCommand{FromSeconds(t), level});
    }
    if (k % 10 == 0) {
      EscTelemetry esc;
      esc.t_ns = FromSeconds(t);
      esc.motor_speed_rad_s = (thrust / vehicle.thrust_coefficient_n_s2).cwiseSqrt();
      for (int i = 0; i < 4; ++i) esc.motor_speed_rad_s[i] += 2.0 * rng.Normal();
      fdd.OnEscTelemetry(esc);
      if (const auto rotor = fdd.first_isolated_rotor(); rotor && !out.detected_s) {
        out.detected_s = *fdd.rotors()[*rotor].detected_s;
        out.detector = fdd.rotors()[*rotor].detector;
      }
    }
    // The command in force over the next step: the latest whose instant plus the delay has come.
    while (acting + 1 < commands.size() && commands[acting + 1].first + m.delay_s <= t + 1e-12) ++acting;
    for (int i = 0; i < 4; ++i) {
      if (i == m.stop_rotor && t >= m.stop_at_s) {
        thrust[i] *= std::exp(-kStep / m.stop_time_constant_s);
      } else {
        thrust[i] = commands[acting].second[i] + (thrust[i] - commands[acting].second[i]) * std::exp(-kStep / sigma);
      }
    }
  }
  out.extremes = fdd.healthy_extremes();
  return out;
}

TEST(CompositeFdd, HealthyMotorsFasterAndLaterThanTheFileStayAboveTheShortfallFloor) {
  const CompositeFddOptions o;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    // 20 % faster than the file and 6 ms late (within the 30 % and the delay span the floor allows),
    // and 20 % slower with no delay.
    for (const auto& [ratio, delay] : {std::pair{0.8, 0.006}, std::pair{1.2, 0.0}}) {
      const LaggingFlight f = FlyLaggingMotors({.sigma_ratio = ratio, .delay_s = delay}, o, seed);
      EXPECT_FALSE(f.detected_s) << "seed " << seed << ", sigma x" << ratio << ": " << f.detector;
      EXPECT_LT(f.extremes.debounced_motor_shortfall, 0.02) << "seed " << seed << ", sigma x" << ratio;
      EXPECT_GT(f.extremes.debounced_motor_shortfall, -1.0);
    }
  }
  // Motors twice as fast as the file fall faster than the floor allows: the floor is what bounds.
  const LaggingFlight fast = FlyLaggingMotors({.sigma_ratio = 0.5}, o, 1);
  EXPECT_GT(fast.extremes.debounced_motor_shortfall, o.motor_shortfall_threshold);
}

TEST(CompositeFdd, AStoppingMotorIsIsolatedByItsShortfallBeforeItsIndexFalls) {
  const CompositeFddOptions o;
  CompositeFddOptions index_only = o;
  index_only.motor_shortfall_threshold = 1.0;
  // The simulator's motor stops coast down with a time constant of 5 to 50 ms.
  for (const auto& [coast, bound] : {std::pair{0.05, 0.010}, std::pair{0.005, 0.003}}) {
    for (int rotor = 0; rotor < 4; ++rotor) {
      const LaggingMotors m{.sigma_ratio = 0.8, .delay_s = 0.006, .stop_rotor = rotor, .stop_at_s = 1.0,
                            .stop_time_constant_s = coast};
      const LaggingFlight f = FlyLaggingMotors(m, o, 7);
      ASSERT_TRUE(f.detected_s) << "coast " << coast << ", rotor " << rotor;
      EXPECT_EQ(f.detector, "motor_shortfall");
      EXPECT_GE(*f.detected_s, 1.0);
      EXPECT_LE(*f.detected_s - 1.0, bound) << "coast " << coast << ", rotor " << rotor;
      const LaggingFlight by_index = FlyLaggingMotors(m, index_only, 7);
      ASSERT_TRUE(by_index.detected_s);
      EXPECT_EQ(by_index.detector, "motor_index");
      EXPECT_GT(*by_index.detected_s - 1.0, 3.0 * (*f.detected_s - 1.0)) << "coast " << coast;
    }
  }
}

TEST(CompositeFdd, OptionsValidationNamesTheField) {
  CompositeFddOptions o;
  o.motor_index_threshold = 1.5;
  EXPECT_THROW(CompositeFdd(ReferenceQuad(), o), ValidationError);
  o = CompositeFddOptions{};
  o.filter_cutoff_hz = 400.0;
  EXPECT_THROW(CompositeFdd(ReferenceQuad(), o), ValidationError);
}

}  // namespace
}  // namespace rotorguard::fdd

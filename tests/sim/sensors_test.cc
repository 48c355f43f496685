#include "rotorguard/sim/sensors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "rotorguard/core/error.h"
#include "rotorguard/vehicle/vehicle_params.h"
#include "test_util.h"

namespace rotorguard::sim {
namespace {

vehicle::StateVector SpinningState(double r) {
  vehicle::StateVector x = vehicle::StateVector::Zero(17);
  x[vehicle::StateIndex::kQuaternion] = 1.0;
  x[vehicle::StateIndex::kBodyRate + 2] = r;
  return x;
}

/// A sample captured now and delivered at once (the model's latency must be zero).
OdometrySample MeasureNow(OdometryModel* odometry, const TruthSample& truth) {
  odometry->Measure(truth);
  OdometrySample out;
  EXPECT_TRUE(odometry->Deliver(truth.t_ns, &out));
  return out;
}

TEST(Imu, SeesCentrifugalAccelerationWhileSpinning) {
  ImuOptions o;
  o.position_m = Vector3(0.02, -0.01, 0.03);
  o.accel_noise_density = o.gyro_noise_density = 0.0;
  o.accel_bias_random_walk = o.gyro_bias_random_walk = 0.0;
  o.accel_bias_initial = o.gyro_bias_initial = 0.0;
  ImuModel imu(o, 7);
  const double r = 11.0;  // the post-failure spin
  const vehicle::StateVector x = SpinningState(r);
  TruthSample truth;
  truth.x = &x;  // CoG not accelerating, no angular acceleration
  const ImuSample s = imu.Sample(truth);
  // w x (w x p) for w = r z: -r^2 (p_x, p_y, 0); plus +g along body z.
  EXPECT_NEAR(s.specific_force_B.x(), -r * r * 0.02, 1e-12);
  EXPECT_NEAR(s.specific_force_B.y(), r * r * 0.01, 1e-12);
  EXPECT_NEAR(s.specific_force_B.z(), kGravity, 1e-12);
  EXPECT_NEAR(s.w_B.z(), r, 1e-12);
}

TEST(Imu, TangentialAccelerationFromAngularAcceleration) {
  ImuOptions o;
  o.position_m = Vector3(0.1, 0.0, 0.0);
  o.accel_noise_density = o.gyro_noise_density = o.accel_bias_random_walk = 0.0;
  o.gyro_bias_random_walk = o.accel_bias_initial = o.gyro_bias_initial = 0.0;
  ImuModel imu(o, 7);
  const vehicle::StateVector x = SpinningState(0.0);
  TruthSample truth;
  truth.x = &x;
  truth.acc.alpha_B = Vector3(0, 0, 5.0);  // alpha x p = (0, 0.5, 0)
  EXPECT_NEAR(imu.Sample(truth).specific_force_B.y(), 0.5, 1e-12);
}

/// A noiseless IMU at the centre of gravity, vibrating `amplitude` per rotor at `reference` rad/s.
ImuOptions VibratingImu(double amplitude, double reference) {
  ImuOptions o;
  o.position_m.setZero();
  o.accel_noise_density = o.gyro_noise_density = o.accel_bias_random_walk = 0.0;
  o.gyro_bias_random_walk = o.accel_bias_initial = o.gyro_bias_initial = 0.0;
  o.vibration_m_s2 = amplitude;
  o.vibration_reference_speed_rad_s = reference;
  return o;
}

/// RMS of the accelerometer's x and y over n samples, the specific force of gravity removed.
double VibrationRms(ImuModel* imu, const RotorVector& speeds, const vehicle::RotorFaults* faults, int n) {
  const vehicle::StateVector x = SpinningState(0.0);
  TruthSample truth;
  truth.x = &x;
  truth.motor_speed_rad_s = speeds;
  truth.faults = faults;
  double sum = 0.0;
  for (int k = 0; k < n; ++k) {
    const Vector3 f = imu->Sample(truth).specific_force_B;
    sum += f.x() * f.x() + f.y() * f.y();
  }
  return std::sqrt(sum / n);
}

TEST(Imu, ARotorsImbalanceShakesItWithAmplitudeGrowingAsSpeedSquared) {
  // One rotor at the reference speed: a vector of length A rotating in the rotor plane, so the
  // in-plane RMS is A whatever the aliasing. At twice the speed the centrifugal force is four
  // times larger; a propeller lost multiplies it by the fault factor (10).
  ImuModel at_reference(VibratingImu(0.8, 900.0), 1);
  EXPECT_NEAR(VibrationRms(&at_reference, RotorVector::Constant(1, 900.0), nullptr, 3000), 0.8, 1e-9);
  ImuModel twice(VibratingImu(0.8, 900.0), 1);
  EXPECT_NEAR(VibrationRms(&twice, RotorVector::Constant(1, 1800.0), nullptr, 3000), 3.2, 1e-9);
  vehicle::RotorFaults lost(1);
  lost[0].kind = vehicle::FaultKind::kPropellerLoss;
  ImuModel damaged(VibratingImu(0.8, 900.0), 1);
  EXPECT_NEAR(VibrationRms(&damaged, RotorVector::Constant(1, 900.0), &lost, 3000), 8.0, 1e-9);
  // A stopped rotor does not shake it; two rotors at incommensurate speeds add in power.
  ImuModel two(VibratingImu(0.8, 900.0), 1);
  RotorVector speeds(3);
  speeds << 900.0, 0.0, 900.0 * std::sqrt(2.0);
  EXPECT_NEAR(VibrationRms(&two, speeds, nullptr, 200000), std::sqrt(0.8 * 0.8 + 1.6 * 1.6), 0.01);
}

/// The amplitude of the sinusoid of frequency f [Hz] in x sampled at fs [Hz]: 2 |Σ x_k e^(-i 2π f k / fs)| / n.
double AmplitudeAt(const std::vector<double>& x, double f, double fs) {
  std::complex<double> sum = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    sum += x[k] * std::exp(std::complex<double>(0.0, -2.0 * std::numbers::pi * f * static_cast<double>(k) / fs));
  }
  return 2.0 * std::abs(sum) / static_cast<double>(x.size());
}

/// Where a frequency f lands when sampled at fs: in [0, fs / 2].
double AliasOf(double f, double fs) {
  const double folded = std::fmod(f, fs);
  return folded > 0.5 * fs ? fs - folded : folded;
}

// The vibration reaches every channel (docs/truth.md): the accelerometer in the rotor plane at the
// rotor's frequency and along its axis at the blade pass (twice it); the gyro through the rocking
// these forces make on a rigid body: the axial force m b at the hub r = (0.1, 0, 0) is a pitch
// torque of 0.1 m b, I_yy⁻¹ of it an angular acceleration, whose rate oscillates at the blade pass
// with amplitude α / 2Ω; the in-plane force m a a yaw torque 0.1 m a at the rotor's frequency, rate
// amplitude α / Ω. Each lands where sampling at 333 Hz aliases it: 143.2 Hz stays, the blade pass
// at 286.5 Hz folds to 46.5 Hz.
TEST(Imu, VibrationReachesEveryChannelWhereSamplingAliasesItsFrequencies) {
  ImuOptions o = VibratingImu(0.8, 900.0);
  o.axial_vibration_m_s2 = 0.5;
  o.gyro_vibration_gain = 1.0;
  o.rotor_positions_m = {Vector3(0.1, 0.0, 0.0)};
  o.airframe_mass_kg = 1.2;
  o.airframe_inverse_inertia = Vector3(1.0 / 0.007, 1.0 / 0.007, 1.0 / 0.009).asDiagonal();
  ImuModel imu(o, 1);
  const vehicle::StateVector x = SpinningState(0.0);
  TruthSample truth;
  truth.x = &x;
  const double omega = 900.0;
  truth.motor_speed_rad_s = RotorVector::Constant(1, omega);
  std::vector<double> ax, az, gx, gy, gz;
  for (int k = 0; k < 33300; ++k) {
    const ImuSample s = imu.Sample(truth);
    ax.push_back(s.specific_force_B.x());
    az.push_back(s.specific_force_B.z() - kGravity);
    gx.push_back(s.w_B.x());
    gy.push_back(s.w_B.y());
    gz.push_back(s.w_B.z());
  }
  const double fs = 333.0, rotor = omega / (2.0 * std::numbers::pi);
  const double f1 = AliasOf(rotor, fs), f2 = AliasOf(2.0 * rotor, fs);
  ASSERT_NEAR(f2, 46.5, 0.1);
  // Leakage between the two tones over 100 s of samples is below 1e-3 of their amplitudes.
  EXPECT_NEAR(AmplitudeAt(ax, f1, fs), 0.8, 0.01);
  EXPECT_NEAR(AmplitudeAt(az, f2, fs), 0.5, 0.01);
  EXPECT_NEAR(AmplitudeAt(az, f1, fs), 0.0, 0.01) << "the axial force is at the blade pass only";
  const double pitch_rate = 0.1 * 1.2 * 0.5 / 0.007 / (2.0 * omega), yaw_rate = 0.1 * 1.2 * 0.8 / 0.009 / omega;
  EXPECT_NEAR(AmplitudeAt(gy, f2, fs), pitch_rate, 0.01 * pitch_rate);
  EXPECT_NEAR(AmplitudeAt(gz, f1, fs), yaw_rate, 0.01 * yaw_rate);
  EXPECT_LT(AmplitudeAt(gx, f2, fs) + AmplitudeAt(gx, f1, fs), 1e-3 * pitch_rate) << "an arm along x rocks about y and z";
}

TEST(Imu, EachAxisSaturatesAtItsRange) {
  ImuOptions o = VibratingImu(0.0, 1.0);
  o.accel_range_m_s2 = 5.0;
  o.gyro_range_rad_s = 3.0;
  ImuModel imu(o, 1);
  const vehicle::StateVector x = SpinningState(-11.0);  // spinning past the gyro's range
  TruthSample truth;
  truth.x = &x;
  const ImuSample s = imu.Sample(truth);
  EXPECT_EQ(s.specific_force_B.z(), 5.0) << "gravity (9.81) clips at the range";
  EXPECT_EQ(s.w_B.z(), -3.0);
  EXPECT_EQ(s.specific_force_B.x(), 0.0);
}

TEST(Imu, WhiteNoiseHasTheConfiguredDensity) {
  ImuOptions o;
  o.position_m.setZero();
  o.accel_bias_random_walk = o.gyro_bias_random_walk = 0.0;
  o.accel_bias_initial = o.gyro_bias_initial = 0.0;
  ImuModel imu(o, 11);
  const vehicle::StateVector x = SpinningState(0.0);
  TruthSample truth;
  truth.x = &x;
  const int n = 20000;
  double sum2 = 0.0;
  for (int i = 0; i < n; ++i) sum2 += std::pow(imu.Sample(truth).w_B.x(), 2);
  const double expected = o.gyro_noise_density * std::sqrt(o.rate_hz);  // density / sqrt(dt)
  EXPECT_NEAR(std::sqrt(sum2 / n), expected, 0.03 * expected);  // ~1 % sampling error at n = 20k
}

TEST(Esc, DeliversEachMeasurementExactlyTheDelayLaterQuantised) {
  EscOptions o;
  o.rate_hz = 200.0;  // a measurement every 5 ms, polled by 1 ms physics steps
  o.noise_rpm = 0.0;
  o.quantization_rpm = 10.0;
  o.delay_s = 0.003;
  EscModel esc(o, 1, 3);
  TruthSample truth;
  truth.motor_speed_rad_s = RotorVector::Constant(1, vehicle::RpmToRadPerSecond(14143.0));
  EscTelemetry out;
  int delivered = 0;
  for (TimeNs t = 0; t <= 30'000'000; t += 1'000'000) {
    truth.t_ns = t;
    if (t % 5'000'000 == 0) esc.Measure(truth);
    if (esc.Deliver(t, &out)) {
      ++delivered;
      EXPECT_EQ(out.t_ns, t - 3'000'000);  // measured exactly 3 ms earlier, whatever the ESC rate
      EXPECT_NEAR(vehicle::RadPerSecondToRpm(out.motor_speed_rad_s[0]), 14140.0, 1e-6);
    }
  }
  EXPECT_EQ(delivered, 6);  // measured at 0, 5, ..., 25 ms; delivered at 3, 8, ..., 28 ms
}

TEST(Esc, EachMotorsGainScalesWhatItReportsAndLostFramesNeverArrive) {
  // Gains 1.02 and 0.99 on two motors at 1000 rad/s, no noise nor quantisation; then a third of
  // the frames lost: of 30000 the count delivered is binomial, 20000 ± 3 standard deviations (245).
  EscOptions o;
  o.noise_rpm = o.quantization_rpm = 0.0;
  o.delay_s = 0.0;
  o.gain = {1.02, 0.99};
  TruthSample truth;
  truth.motor_speed_rad_s = RotorVector::Constant(2, 1000.0);
  EscModel esc(o, 2, 3);
  EscTelemetry out;
  esc.Measure(truth);
  ASSERT_TRUE(esc.Deliver(0, &out));
  EXPECT_NEAR(out.motor_speed_rad_s[0], 1020.0, 1e-9);
  EXPECT_NEAR(out.motor_speed_rad_s[1], 990.0, 1e-9);
  o.dropout_probability = 1.0 / 3.0;
  EscModel lossy(o, 2, 5);
  int delivered = 0;
  for (TimeNs t = 0; t < 30000; ++t) {
    truth.t_ns = t;
    lossy.Measure(truth);
    delivered += lossy.Deliver(t, &out) ? 1 : 0;
  }
  EXPECT_NEAR(delivered, 20000, 245);
  EXPECT_THROW(EscModel(o, 3, 1), std::invalid_argument) << "two gains for three motors";
}

TEST(Odometry, NoiseGrowsWithBodyRate) {
  OdometryOptions o;
  o.rate_noise_gain = 0.2;
  const World empty;
  OdometryModel still(o, empty, 5), spinning(o, empty, 5);
  const vehicle::StateVector x0 = SpinningState(0.0), x1 = SpinningState(10.0);
  TruthSample t0, t1;
  t0.x = &x0;
  t1.x = &x1;
  double e0 = 0.0, e1 = 0.0;
  for (int i = 0; i < 5000; ++i) {
    e0 += MeasureNow(&still, t0).p_W.squaredNorm();
    e1 += MeasureNow(&spinning, t1).p_W.squaredNorm();
  }
  // Same random stream, std scaled by (1 + 0.2 * 10) = 3.
  EXPECT_NEAR(std::sqrt(e1 / e0), 3.0, 1e-9);
}

// The front end reports the pose of the vehicle file's body frame, not of the true centre of
// gravity: a point o away from it in the body, p + R o, moving with v + R (ω x o).
TEST(Odometry, ReportsTheFilesBodyFrameWhereverTheCentreOfGravityIs) {
  OdometryOptions o;
  o.position_noise_m = o.velocity_noise_m_s = o.attitude_noise_rad = 0.0;
  o.body_origin_m = Vector3(-0.006, 0.004, -0.003);
  const World empty;
  OdometryModel odometry(o, empty, 5);
  vehicle::StateVector x = SpinningState(11.0);
  const Quaternion q = Quaternion(Eigen::AngleAxisd(0.7, Vector3(1, 2, 3).normalized()));
  x.segment<4>(vehicle::StateIndex::kQuaternion) << q.w(), q.x(), q.y(), q.z();
  x.segment<3>(vehicle::StateIndex::kPosition) = Vector3(1, 2, 3);
  x.segment<3>(vehicle::StateIndex::kVelocity) = Vector3(0.5, -0.2, 0.1);
  TruthSample truth;
  truth.x = &x;
  odometry.Measure(truth);
  OdometrySample out;
  ASSERT_TRUE(odometry.Deliver(0, &out));
  const Matrix3 R = q.toRotationMatrix();
  const Vector3 w(0, 0, 11.0);
  EXPECT_TRUE(out.p_W.isApprox(Vector3(1, 2, 3) + R * o.body_origin_m, 1e-14));
  EXPECT_TRUE(out.v_W.isApprox(Vector3(0.5, -0.2, 0.1) + R * w.cross(o.body_origin_m), 1e-14));
  EXPECT_NEAR((out.v_W - Vector3(0.5, -0.2, 0.1)).norm(), 11.0 * o.body_origin_m.head<2>().norm(), 1e-12)
      << "at 11 rad/s a 7 mm offset moves at 8 cm/s";
  EXPECT_TRUE(out.q_WB.isApprox(q, 1e-14));
}

TEST(Odometry, ArrivesLateStampedAtCapture) {
  OdometryOptions o;
  o.latency_s = 0.023;
  const World empty;
  OdometryModel odometry(o, empty, 5);
  const vehicle::StateVector x = SpinningState(0.0);
  TruthSample truth;
  truth.x = &x;
  OdometrySample out;
  std::vector<TimeNs> captured, arrived;
  // Captured every 10 ms, polled every 1 ms: each arrives at the first poll 23 ms after capture.
  for (TimeNs t = 0; t <= 100'000'000; t += 1'000'000) {
    truth.t_ns = t;
    if (t % 10'000'000 == 0) odometry.Measure(truth);
    if (odometry.Deliver(t, &out)) {
      captured.push_back(out.t_ns);
      arrived.push_back(t);
    }
  }
  ASSERT_EQ(captured.size(), 8u);  // captures at 0..70 ms arrive by 100 ms; 80..100 ms are in flight
  for (std::size_t i = 0; i < captured.size(); ++i) {
    EXPECT_EQ(captured[i], static_cast<TimeNs>(i) * 10'000'000);
    EXPECT_EQ(arrived[i], captured[i] + 23'000'000);
  }
}

TEST(Odometry, DriftIsARandomWalkOfTheStatedDiffusion) {
  OdometryOptions o;
  o.position_noise_m = o.velocity_noise_m_s = o.attitude_noise_rad = 0.0;
  o.drift_m_per_sqrt_s = 0.02;
  o.yaw_drift_rad_per_sqrt_s = 0.003;
  const World empty;
  const vehicle::StateVector x = SpinningState(0.0);
  TruthSample truth;
  truth.x = &x;
  // After T seconds each axis of a random walk has variance σ² T: over many flights of 4 s the
  // mean squared drift is 3 σ² T in position and σ² T in yaw.
  const int flights = 400;
  const double seconds = 4.0;
  double p2 = 0.0, yaw2 = 0.0;
  for (int f = 0; f < flights; ++f) {
    OdometryModel odometry(o, empty, DeriveSeed(11, static_cast<std::uint64_t>(f)));
    OdometrySample out;
    for (int k = 0; k < static_cast<int>(seconds * o.rate_hz); ++k) out = MeasureNow(&odometry, truth);
    // The vehicle sits at the origin, so what the front end reports is its frame's drift.
    EXPECT_NEAR((out.p_W - odometry.drift_m()).norm(), 0.0, 1e-12);
    p2 += out.p_W.squaredNorm();
    yaw2 += odometry.drift_yaw_rad() * odometry.drift_yaw_rad();
  }
  // Relative std of a mean of 400 χ² values: sqrt(2 / (3·400)) = 4 % and sqrt(2/400) = 7 %.
  EXPECT_NEAR(p2 / flights / (3.0 * o.drift_m_per_sqrt_s * o.drift_m_per_sqrt_s * seconds), 1.0, 0.15);
  EXPECT_NEAR(yaw2 / flights / (o.yaw_drift_rad_per_sqrt_s * o.yaw_drift_rad_per_sqrt_s * seconds), 1.0, 0.25);
}

TEST(Odometry, DriftRotatesTheReportedFrame) {
  OdometryOptions o;
  o.position_noise_m = o.velocity_noise_m_s = o.attitude_noise_rad = 0.0;
  o.yaw_drift_rad_per_sqrt_s = 0.5;
  const World empty;
  OdometryModel odometry(o, empty, 3);
  vehicle::StateVector x = SpinningState(0.0);
  x.segment<3>(vehicle::StateIndex::kPosition) = Vector3(2.0, 0.0, 1.0);
  x.segment<3>(vehicle::StateIndex::kVelocity) = Vector3(0.0, 1.0, 0.0);
  TruthSample truth;
  truth.x = &x;
  const OdometrySample out = MeasureNow(&odometry, truth);
  const double yaw = odometry.drift_yaw_rad();
  ASSERT_GT(std::abs(yaw), 1e-3);
  EXPECT_NEAR(out.p_W.x(), 2.0 * std::cos(yaw), 1e-12);
  EXPECT_NEAR(out.p_W.y(), 2.0 * std::sin(yaw), 1e-12);
  EXPECT_NEAR(out.p_W.z(), 1.0, 1e-12);
  EXPECT_NEAR(out.v_W.x(), -std::sin(yaw), 1e-12);
  // The attitude turns with the frame: the body's x axis points at the drifted yaw.
  const Vector3 x_axis = out.q_WB * Vector3::UnitX();
  EXPECT_NEAR(std::atan2(x_axis.y(), x_axis.x()), yaw, 1e-12);
}

TEST(Odometry, NoiseGrowsWhereFewObstaclesAreInView) {
  OdometryOptions o;
  o.rate_noise_gain = 0.0;
  o.few_features_gain = 2.0;
  o.features_reference = 4;
  o.feature_range_m = 10.0;
  World empty, sparse, dense;
  for (int i = 0; i < 8; ++i) {
    const Cylinder c{.center_m = Eigen::Vector2d(3.0 + i, 0.0), .radius_m = 0.2, .height_m = 5.0};
    dense.cylinders.push_back(c);
    if (i == 0) sparse.cylinders.push_back(c);
    if (i == 7) sparse.cylinders.push_back({.center_m = Eigen::Vector2d(30.0, 0.0), .radius_m = 0.2, .height_m = 5.0});
  }
  OdometryModel a(o, empty, 5), b(o, sparse, 5), c(o, dense, 5);
  const vehicle::StateVector x = SpinningState(0.0);
  TruthSample truth;
  truth.x = &x;
  double ea = 0.0, eb = 0.0, ec = 0.0;
  for (int i = 0; i < 100; ++i) {
    ea += MeasureNow(&a, truth).p_W.squaredNorm();
    eb += MeasureNow(&b, truth).p_W.squaredNorm();
    ec += MeasureNow(&c, truth).p_W.squaredNorm();
  }
  // Same stream; factors 1 + 2 (1 - n/4): none in view 3, one in view (the other is 30 m away) 2.5,
  // eight in view 1.
  EXPECT_NEAR(std::sqrt(ea / ec), 3.0, 1e-9);
  EXPECT_NEAR(std::sqrt(eb / ec), 2.5, 1e-9);
}

TEST(Odometry, LosesTrackAtTheStatedRate) {
  OdometryOptions o;
  o.outage_rate_hz = 0.5;
  o.outage_min_s = 0.1;
  o.outage_max_s = 0.3;
  const World empty;
  OdometryModel odometry(o, empty, 9);
  const TimeNs period = PeriodFromRate(o.rate_hz);
  int outages = 0, lost = 0;
  bool was_lost = false;
  const int samples = 200'000;  // 2000 s
  for (int k = 0; k < samples; ++k) {
    const bool now = odometry.InOutage(k * period);
    outages += now && !was_lost;
    lost += now;
    was_lost = now;
  }
  // About rate · (time tracking) outages of 0.2 s mean: 2000 s · 0.5 Hz / (1 + 0.5 · 0.2) = 909 ± 30.
  EXPECT_NEAR(outages, 909, 100);
  EXPECT_NEAR(lost * 0.01 / outages, 0.2, 0.02);
}

TEST(RateTimer, FiresOnItsGridFromPhysicsSteps) {
  RateTimer timer(333.0);  // 3.003003 ms period polled every 1 ms
  int fired = 0;
  for (TimeNs t = 0; t < 1'000'000'000; t += 1'000'000) fired += timer.Due(t) ? 1 : 0;
  EXPECT_EQ(fired, 333);
}

// Found by generating flights (tests/fuzz): a rate of 4.9e-324 Hz made the period +inf seconds,
// whose conversion to integer nanoseconds was undefined and came out negative, and Due() looped
// forever. Periods now saturate, and rates below kMinRateHz are refused.
TEST(RateTimer, ARateTooSlowToTickAgainFiresOnceAndNeverLoops) {
  EXPECT_EQ(FromSeconds(std::numeric_limits<double>::infinity()), std::numeric_limits<TimeNs>::max());
  EXPECT_EQ(FromSeconds(-1e300), std::numeric_limits<TimeNs>::min());
  EXPECT_EQ(FromSeconds(std::numeric_limits<double>::quiet_NaN()), std::numeric_limits<TimeNs>::max());
  EXPECT_EQ(FromSeconds(9.2e9), 9'200'000'000'000'000'000);  // just inside: 292 years
  RateTimer timer(4.9e-324);
  EXPECT_TRUE(timer.Due(0));
  EXPECT_FALSE(timer.Due(1'000'000'000));
  EXPECT_FALSE(timer.Due(std::numeric_limits<TimeNs>::max() - 1));
  EscOptions esc;
  esc.rate_hz = 4.9e-324;
  RG_EXPECT_THROW_WITH(esc.Validate(1000.0), rotorguard::ValidationError, "rate_hz");
  esc.rate_hz = kMinRateHz;
  EXPECT_NO_THROW(esc.Validate(1000.0));
}

}  // namespace
}  // namespace rotorguard::sim

// The truth draw: the identity in the ideal world, a pure function of the seed, inside its ranges
// and filling them, and a simulated vehicle that obeys the laws the draw changes.
#include "rotorguard/sim/truth.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "rotorguard/core/error.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/vehicle/effectiveness.h"
#include "rotorguard/vehicle/multirotor.h"
#include "test_util.h"
#include "vehicle_fixture.h"

namespace rotorguard::sim {
namespace {

using rotorguard::testing::MatricesNear;
using rotorguard::testing::ReferenceQuad;

TruthOptions Realistic() {
  TruthOptions o;
  o.preset = TruthPreset::kRealistic;
  return o;
}

TEST(Truth, TheIdealWorldIsTheFileExactly) {
  const vehicle::VehicleParams file = ReferenceQuad();
  TruthOptions ideal;
  ideal.preset = TruthPreset::kIdeal;
  const TruthDraw d = DrawTruth(ideal, file, 42);
  EXPECT_EQ(d.mass_ratio, 1.0);
  EXPECT_EQ(d.mass_moment_ratio, Vector3::Ones());
  EXPECT_EQ(d.cog_offset_m, Vector3::Zero());
  EXPECT_EQ(d.thrust_coefficient_ratio, std::vector<double>(4, 1.0));
  EXPECT_EQ(d.motor_stop_time_constant_s, file.motor_stop_time_constant_s);
  EXPECT_EQ(d.external_torque_n_m, Vector3::Zero());
  EXPECT_EQ(d.ground_effect_ratio, 1.0);  // the world's physics, not the file's: nominal, not absent
  EXPECT_EQ(d.battery_capacity_ratio, 1.0);
  EXPECT_EQ(d.battery_resistance_ratio, 1.0);
  const vehicle::VehicleParams v = TruthVehicle(file, d);
  // Bit for bit: the ideal world must reproduce the figures measured before the truth existed.
  EXPECT_EQ(v.mass_kg, file.mass_kg);
  EXPECT_EQ(v.inertia_kg_m2, file.inertia_kg_m2);
  EXPECT_EQ(v.rotor_drag_kg_s, file.rotor_drag_kg_s);
  EXPECT_EQ(v.motor_time_constant_s, file.motor_time_constant_s);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(v.rotors[i].p_B, file.rotors[i].p_B);
    EXPECT_EQ(v.rotors[i].yaw_coefficient_m, file.rotors[i].yaw_coefficient_m);
  }
  EXPECT_EQ(ThrustRatios(d), RotorVector::Ones(4));
  EXPECT_EQ(d.computation_delay_s, 0.0);
  EXPECT_EQ(d.esc_command_latency_s, 0.0);
  // The sensors where the file puts them: nothing moved, turned, delayed, shaken or noisier.
  const SimulatorOptions scenario;
  const SimulatorOptions o = TruthSimulatorOptions(scenario, file, d);
  EXPECT_EQ(o.odometry.body_origin_m, Vector3::Zero());
  EXPECT_EQ(o.lidar.position_m, scenario.lidar.position_m);
  EXPECT_EQ(o.lidar.rotation.coeffs(), Quaternion::Identity().coeffs());
  EXPECT_EQ(o.lidar.clock_offset_s, 0.0);
  EXPECT_EQ(o.imu.accel_noise_density, scenario.imu.accel_noise_density);
  EXPECT_EQ(o.imu.gyro_noise_density, scenario.imu.gyro_noise_density);
  EXPECT_EQ(o.imu.vibration_m_s2 + o.imu.axial_vibration_m_s2 + o.imu.gyro_vibration_gain, 0.0);
  EXPECT_EQ(o.esc.command_latency_s, 0.0);
}

// Every sensor that reports a pose reports the file's body frame, wherever the drawn centre of
// gravity sits: the odometry's origin and the LiDAR's mount move by minus the offset from the true
// centre of gravity (which the simulator's state follows), as the IMU's does.
TEST(Truth, SensorsSitOnTheFilesBodyFrameNotOnTheTrueCentreOfGravity) {
  const vehicle::VehicleParams file = ReferenceQuad();
  const TruthDraw d = DrawTruth(Realistic(), file, 11);
  ASSERT_GT(d.cog_offset_m.norm(), 1e-3);
  SimulatorOptions scenario;
  scenario.lidar.position_m = Vector3(0.01, -0.02, 0.06);
  const SimulatorOptions o = TruthSimulatorOptions(scenario, file, d);
  EXPECT_TRUE(o.odometry.body_origin_m.isApprox(-d.cog_offset_m, 1e-15));
  EXPECT_TRUE(o.lidar.position_m.isApprox(scenario.lidar.position_m - d.cog_offset_m, 1e-15));
  EXPECT_TRUE(o.imu.position_m.isApprox(scenario.imu.position_m - d.cog_offset_m + d.imu_offset_m, 1e-15));
  // The LiDAR's axes turned by the drawn rotation vector; its clock off by the drawn offset.
  EXPECT_NEAR(Eigen::AngleAxisd(o.lidar.rotation).angle(), d.lidar_rotation_rad.norm(), 1e-12);
  EXPECT_EQ(o.lidar.clock_offset_s, d.lidar_clock_offset_s);
  EXPECT_EQ(o.imu.gyro_noise_density, scenario.imu.gyro_noise_density * d.imu_gyro_noise_ratio);
  ASSERT_EQ(o.imu.rotor_positions_m.size(), 4u);
  EXPECT_TRUE(o.imu.rotor_positions_m[0].isApprox(file.rotors[0].p_B - d.cog_offset_m, 1e-12));
  EXPECT_EQ(o.imu.airframe_mass_kg, file.mass_kg * d.mass_ratio);
}

TEST(Truth, ADrawIsAPureFunctionOfItsSeed) {
  const vehicle::VehicleParams file = ReferenceQuad();
  const TruthDraw a = DrawTruth(Realistic(), file, 7), b = DrawTruth(Realistic(), file, 7);
  const TruthDraw c = DrawTruth(Realistic(), file, 8);
  EXPECT_EQ(a.mass_ratio, b.mass_ratio);
  EXPECT_EQ(a.thrust_coefficient_ratio, b.thrust_coefficient_ratio);
  EXPECT_EQ(a.external_torque_n_m, b.external_torque_n_m);
  EXPECT_NE(a.mass_ratio, c.mass_ratio);
  EXPECT_NE(a.thrust_coefficient_ratio, c.thrust_coefficient_ratio);
}

TEST(Truth, RealisticDrawsStayInTheirRangesAndFillThem) {
  const vehicle::VehicleParams file = ReferenceQuad();
  const TruthRanges r = RangesOf(TruthPreset::kRealistic);
  std::vector<double> mass, kn, stop, torque, cog, latency, computation, esc_latency, noise, lidar_turn, lidar_clock,
      ground_effect, capacity, resistance;
  for (std::uint64_t seed = 0; seed < 4000; ++seed) {
    const TruthDraw d = DrawTruth(Realistic(), file, seed);
    ground_effect.push_back(d.ground_effect_ratio);
    capacity.push_back(d.battery_capacity_ratio);
    resistance.push_back(d.battery_resistance_ratio);
    computation.push_back(d.computation_delay_s);
    esc_latency.push_back(d.esc_command_latency_s);
    noise.push_back(d.imu_gyro_noise_ratio);
    lidar_turn.push_back(d.lidar_rotation_rad.y());
    lidar_clock.push_back(d.lidar_clock_offset_s);
    EXPECT_GE(d.imu_axial_vibration_m_s2, 0.5 * r.imu_axial_vibration_m_s2);
    EXPECT_LE(d.imu_axial_vibration_m_s2, r.imu_axial_vibration_m_s2);
    EXPECT_GE(d.gyro_vibration_gain, 1.0);
    EXPECT_LE(d.gyro_vibration_gain, r.gyro_vibration_gain);
    mass.push_back(d.mass_ratio - 1.0);
    kn.insert(kn.end(), d.thrust_coefficient_ratio.begin(), d.thrust_coefficient_ratio.end());
    stop.push_back(d.motor_stop_time_constant_s);
    torque.push_back(d.external_torque_n_m.x());
    cog.push_back(d.cog_offset_m.y());
    latency.push_back(d.odometry_latency_s);
    EXPECT_GE(d.odometry_drift_m_per_sqrt_s, 0.5 * r.odometry_drift_m_per_sqrt_s);
    EXPECT_LE(d.odometry_drift_m_per_sqrt_s, r.odometry_drift_m_per_sqrt_s);
    EXPECT_EQ(d.external_torque_n_m.z(), 0.0);
  }
  // Uniform on [-a, a]: 4000 draws come within 0.5 % of a of both ends with probability > 1 - 1e-8.
  const auto fills = [](const std::vector<double>& x, double centre, double a) {
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    EXPECT_GE(*lo, centre - a);
    EXPECT_LT(*hi, centre + a);
    EXPECT_LT(*lo, centre - 0.995 * a);
    EXPECT_GT(*hi, centre + 0.995 * a);
  };
  fills(mass, 0.0, r.mass_fraction);
  fills(kn, 1.0, r.thrust_coefficient_fraction);
  fills(torque, 0.0, r.external_torque_n_m);
  fills(cog, 0.0, r.cog_offset_m);
  // The ground effect from half to one and a half times Cheeseman and Bennett's.
  EXPECT_GE(r.ground_effect_fraction, 0.5);
  fills(ground_effect, 1.0, r.ground_effect_fraction);
  // Packs that have aged: capacity down to 70 %, resistance up to 1.6 times the label's.
  EXPECT_GE(r.battery_fraction, 0.3);
  fills(capacity, 1.0 - 0.5 * r.battery_fraction, 0.5 * r.battery_fraction);
  fills(resistance, 1.0 + r.battery_fraction, r.battery_fraction);
  const auto fills_interval = [&fills](const std::vector<double>& x, double lo, double hi) {
    fills(x, 0.5 * (lo + hi), 0.5 * (hi - lo));
  };
  fills_interval(latency, r.odometry_latency_min_s, r.odometry_latency_max_s);
  // The loop's delays: computation over at least 1-4 ms, the ESCs' latency over 0.5-2 ms.
  EXPECT_LE(r.computation_delay_min_s, 0.001);
  EXPECT_GE(r.computation_delay_max_s, 0.004);
  EXPECT_LE(r.esc_command_latency_min_s, 0.0005);
  EXPECT_GE(r.esc_command_latency_max_s, 0.002);
  fills_interval(computation, r.computation_delay_min_s, r.computation_delay_max_s);
  fills_interval(esc_latency, r.esc_command_latency_min_s, r.esc_command_latency_max_s);
  fills(noise, 1.0, r.imu_noise_fraction);
  // The LiDAR: turned by ±0.5° about each axis at least, its clock off by ±2 ms at least.
  EXPECT_GE(r.lidar_rotation_rad, 0.5 * std::numbers::pi / 180.0 - 1e-15);
  EXPECT_GE(r.lidar_clock_offset_s, 0.002);
  fills(lidar_turn, 0.0, r.lidar_rotation_rad);
  fills(lidar_clock, 0.0, r.lidar_clock_offset_s);
  // Log-uniform on [5, 50] ms: inside, and its median the geometric mean sqrt(5 * 50) = 15.8 ms
  // (the standard error of a median of 4000 draws is about 2 % of it).
  const auto [lo, hi] = std::minmax_element(stop.begin(), stop.end());
  EXPECT_GE(*lo, *r.motor_stop_time_constant_min_s);
  EXPECT_LE(*hi, *r.motor_stop_time_constant_max_s);
  std::nth_element(stop.begin(), stop.begin() + 2000, stop.end());
  EXPECT_NEAR(stop[2000], std::sqrt(0.005 * 0.050), 0.1 * std::sqrt(0.005 * 0.050));
}

TEST(Truth, AnOverrideReplacesOneRangeOfThePreset) {
  TruthOptions o = Realistic();
  o.mass_fraction = 0.0;
  o.motor_stop_time_constant_min_s = 0.02;
  o.motor_stop_time_constant_max_s = 0.02;
  const TruthDraw d = DrawTruth(o, ReferenceQuad(), 3);
  EXPECT_EQ(d.mass_ratio, 1.0);
  EXPECT_EQ(d.motor_stop_time_constant_s, 0.02);
  EXPECT_NE(d.mass_moment_ratio, Vector3::Ones());  // the rest keeps the preset's spread
}

TEST(Truth, AnIntervalNeedsBothEndsInOrder) {
  TruthOptions o;
  o.motor_stop_time_constant_min_s = 0.01;
  RG_EXPECT_THROW_WITH(o.Validate(), ValidationError, "motor_stop_time_constant_max_s is missing");
  o.motor_stop_time_constant_max_s = 0.005;
  RG_EXPECT_THROW_WITH(o.Validate(), ValidationError, "at least motor_stop_time_constant_min_s = 0.01");
  o = TruthOptions();
  o.odometry_latency_max_s = 0.02;
  RG_EXPECT_THROW_WITH(o.Validate(), ValidationError, "odometry_latency_min_s is missing");
  o = TruthOptions();
  o.computation_delay_min_s = 0.003;
  o.computation_delay_max_s = 0.001;
  RG_EXPECT_THROW_WITH(o.Validate(), ValidationError, "at least computation_delay_min_s = 0.003");
  o = TruthOptions();
  o.esc_command_latency_min_s = 0.001;
  RG_EXPECT_THROW_WITH(o.Validate(), ValidationError, "esc_command_latency_max_s is missing");
}

TEST(Truth, TheDrawnVehicleMovesItsRotorsAboutTheTrueCentreOfGravity) {
  const vehicle::VehicleParams file = ReferenceQuad();
  const TruthDraw d = DrawTruth(Realistic(), file, 11);
  const vehicle::VehicleParams v = TruthVehicle(file, d);
  EXPECT_DOUBLE_EQ(v.mass_kg, file.mass_kg * d.mass_ratio);
  EXPECT_TRUE(MatricesNear(v.inertia_kg_m2, ScaleMassMoments(file.inertia_kg_m2, d.mass_moment_ratio), 0.0));
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(MatricesNear(v.rotors[i].p_B + d.cog_offset_m, file.rotors[i].p_B, 1e-15));
    EXPECT_DOUBLE_EQ(v.rotors[i].yaw_coefficient_m, file.rotors[i].yaw_coefficient_m * d.yaw_coefficient_ratio[i]);
  }
  EXPECT_NO_THROW(v.Validate());
}

// Found by generating flights (tests/fuzz): an IMU at the edge of its range (50 m) was drawn 1 cm
// beyond it, and the simulator refused the realistic world's options of a valid scenario.
TEST(Truth, ABodyPointAtTheEdgeOfItsRangeStaysInsideWhenTheCentreOfGravityMoves) {
  const vehicle::VehicleParams file = ReferenceQuad();
  SimulatorOptions scenario;
  scenario.imu.position_m = Vector3(kMaxBodyOffsetM, -kMaxBodyOffsetM, 0.0);
  int moved_out = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const TruthDraw d = DrawTruth(Realistic(), file, seed);
    const Vector3 unclamped = scenario.imu.position_m - d.cog_offset_m + d.imu_offset_m;
    moved_out += unclamped.cwiseAbs().maxCoeff() > kMaxBodyOffsetM;
    const SimulatorOptions o = TruthSimulatorOptions(scenario, file, d);
    EXPECT_LE(o.imu.position_m.cwiseAbs().maxCoeff(), kMaxBodyOffsetM);
    EXPECT_NO_THROW(o.Validate(TruthVehicle(file, d)));
  }
  EXPECT_GT(moved_out, 0) << "no draw left the range: the test would pass without the clamp";
}

/// The inertia about the origin of point masses m at the columns of `points`: Σ m (|r|² 1 − r rᵀ).
Matrix3 PointMassInertia(const Eigen::Matrix<double, 3, Eigen::Dynamic>& points, double m) {
  Matrix3 inertia = Matrix3::Zero();
  for (Eigen::Index k = 0; k < points.cols(); ++k) {
    const Vector3 r = points.col(k);
    inertia += m * (r.squaredNorm() * Matrix3::Identity() - r * r.transpose());
  }
  return inertia;
}

TEST(Truth, ScalingTheMassMomentsIsStretchingTheBodyAlongItsAxes) {
  // The oracle: a body of point masses stretched by √ratio along each body axis has ∫x² dm, ∫y² dm,
  // ∫z² dm scaled by the ratios; its inertia, summed directly, is what ScaleMassMoments returns. A
  // tilted cloud gives products of inertia too.
  Eigen::Matrix<double, 3, Eigen::Dynamic> body(3, 7);
  body << 0.10, -0.12, 0.03, -0.02, 0.05, 0.00, -0.07,  //
      0.02, 0.04, -0.15, 0.11, -0.01, 0.06, -0.03,      //
      0.01, -0.02, 0.03, 0.00, -0.04, 0.05, 0.02;
  const Vector3 ratio(1.12, 0.9, 1.31);
  const Eigen::Matrix<double, 3, Eigen::Dynamic> stretched = ratio.cwiseSqrt().asDiagonal() * body;
  const Matrix3 scaled = ScaleMassMoments(PointMassInertia(body, 0.3), ratio);
  EXPECT_TRUE(MatricesNear(scaled, PointMassInertia(stretched, 0.3), 1e-15));
  EXPECT_GT(std::abs(scaled(0, 1)), 1e-4);  // the products of inertia were exercised
  const Matrix3 file = ReferenceQuad().inertia_kg_m2;
  EXPECT_EQ(ScaleMassMoments(file, Vector3::Ones()), file);  // exactly: the ideal world's vehicle
}

TEST(Truth, EveryRealisticDrawOfAFlatVehicleStaysFlat) {
  // The reference vehicle's mass spreads farther horizontally than vertically (∫x² dm = 4.39,
  // ∫z² dm = 2.60 g m²), so I_zz - I_xx = ∫x² dm - ∫z² dm > 0 for every draw of ±15 %: the spin
  // after a rotor failure keeps its gyroscopic stiffness. The moments stay within ±15 % of the
  // file's (a weighted mean of the ratios) and fill most of it.
  const vehicle::VehicleParams file = ReferenceQuad();
  const double a = RangesOf(TruthPreset::kRealistic).inertia_fraction;
  double lowest_zz_over_xy = std::numeric_limits<double>::infinity(), widest = 0.0;
  for (std::uint64_t seed = 0; seed < 4000; ++seed) {
    const Matrix3 inertia = TruthVehicle(file, DrawTruth(Realistic(), file, seed)).inertia_kg_m2;
    lowest_zz_over_xy = std::min(lowest_zz_over_xy, inertia(2, 2) / std::max(inertia(0, 0), inertia(1, 1)));
    for (int k = 0; k < 3; ++k) {
      const double ratio = inertia(k, k) / file.inertia_kg_m2(k, k);
      EXPECT_LE(std::abs(ratio - 1.0), a);
      widest = std::max(widest, std::abs(ratio - 1.0));
    }
  }
  // The draw's worst vertex (ratios 1.15, 0.85, 1.15) gives I_zz / I_yy = 1.078; scaling the
  // principal moments independently by ±15 % reached 0.85 · 8.650 / (1.15 · 6.992) = 0.914.
  EXPECT_GE(lowest_zz_over_xy, 1.078);
  EXPECT_GT(widest, 0.9 * a);
}

TEST(Truth, TheDrawnVehicleHoversOnThrustsThatBalanceItsWeightAboutItsCentreOfGravity) {
  // The physical law: applied thrusts sum to m g and their moments about the true CoG vanish.
  const vehicle::VehicleParams file = ReferenceQuad();
  const TruthDraw d = DrawTruth(Realistic(), file, 5);
  const vehicle::MultirotorModel truth(TruthVehicle(file, d), ThrustRatios(d));
  const RotorVector applied = truth.HoverThrusts().cwiseProduct(ThrustRatios(d));
  EXPECT_NEAR(applied.sum(), truth.params().weight_n(), 1e-12);
  Vector3 moment = Vector3::Zero();
  for (int i = 0; i < 4; ++i) moment += truth.params().rotors[i].p_B.cross(Vector3(0, 0, applied[i]));
  EXPECT_NEAR(moment.x(), 0.0, 1e-12);
  EXPECT_NEAR(moment.y(), 0.0, 1e-12);
  // and the model's own thrusts are those: RotorThrusts applies the ratios to the motor states.
  RotorVector thrust;
  truth.RotorThrusts(truth.MakeState(Vector3(0, 0, 1), 0.0, truth.HoverThrusts()), vehicle::RotorFaults(4), &thrust);
  EXPECT_TRUE(MatricesNear(thrust, applied, 1e-12));
}

TEST(Truth, ThrustRatiosChangeThrustButNotTheSpeedTheEscMeasures) {
  // A propeller with a larger k_n makes more thrust at the same speed: the motor state (what the
  // command sets) and the speed it implies stay the file's.
  const vehicle::VehicleParams file = ReferenceQuad();
  RotorVector ratio(4);
  ratio << 1.05, 0.95, 1.0, 1.02;
  const vehicle::MultirotorModel exact(file), spread(file, ratio);
  const vehicle::StateVector x = exact.MakeState(Vector3(0, 0, 1), 0.0, RotorVector::Constant(4, 3.0));
  RotorVector t_exact, t_spread, w_exact, w_spread;
  exact.RotorThrusts(x, vehicle::RotorFaults(4), &t_exact);
  spread.RotorThrusts(x, vehicle::RotorFaults(4), &t_spread);
  exact.MotorSpeeds(x, vehicle::RotorFaults(4), &w_exact);
  spread.MotorSpeeds(x, vehicle::RotorFaults(4), &w_spread);
  EXPECT_TRUE(MatricesNear(t_spread, t_exact.cwiseProduct(ratio), 1e-15));
  EXPECT_EQ(w_spread, w_exact);
  EXPECT_THROW(vehicle::MultirotorModel(file, RotorVector::Ones(3)), std::invalid_argument);
  EXPECT_THROW(vehicle::MultirotorModel(file, RotorVector::Zero(4)), std::invalid_argument);
}

TEST(Truth, AnExternalTorqueSpinsTheBodyAtInertiaInverseTimesTorque) {
  // Euler's equation from rest: the first step's angular velocity is I^-1 tau dt (the hover
  // thrusts add no torque and the rates are zero, so gyroscopic and damping terms vanish).
  const vehicle::MultirotorModel model(ReferenceQuad());
  SimulatorOptions o;
  o.external_torque_n_m = Vector3(0.01, -0.004, 0.0);
  Simulator sim(model, World{}, {}, o, 1, model.MakeState(Vector3(0, 0, 2), 0.0, model.HoverThrusts()));
  RotorCommand hover;
  hover.thrust_n = model.HoverThrusts();
  sim.Step(hover);
  const double dt = ToSeconds(sim.step_ns());
  const Vector3 expected = model.params().inertia_kg_m2.inverse() * o.external_torque_n_m * dt;
  EXPECT_TRUE(MatricesNear(vehicle::StateView(sim.state()).w_B(), expected, 1e-3 * expected.norm()));
}

}  // namespace
}  // namespace rotorguard::sim

#include "rotorguard/sim/contact.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "rotorguard/core/error.h"
#include "vehicle_fixture.h"

namespace rotorguard::sim {
namespace {

using vehicle::StateIndex;
using vehicle::StateView;

constexpr double kDt = 1e-3;  // the simulator's physics step
constexpr double kDeg = std::numbers::pi / 180.0;

/// The reference quadrotor without aerodynamics (its rotor drag would brake a slide), its motors
/// off, on four feet at (+-a, +-b, -h): the closed forms below are a rigid body's on a plane.
struct Block {
  static constexpr double a = 0.10, b = 0.08, h = 0.06;
  explicit Block(double slope_rad, double mu)
      : params([] {
          vehicle::VehicleParams p = testing::ReferenceQuad();
          p.rotor_drag_kg_s.setZero();
          p.yaw_damping_n_m_s = 0.0;
          return p;
        }()),
        model(params),
        integrator(model),
        // The plane rises toward +y: its normal is body z turned by the slope about x.
        plane{.normal_W = Eigen::AngleAxisd(slope_rad, Vector3::UnitX()) * Vector3::UnitZ(), .offset_m = 0.0},
        contact({{a, b, -h}, {a, -b, -h}, {-a, b, -h}, {-a, -b, -h}}, params.mass_kg,
                {.natural_frequency_hz = 25.0, .damping_ratio = 0.7, .friction_coefficient = mu}, plane),
        faults(4) {
    // Standing on the plane, feet on it, at rest.
    x = model.MakeState(Vector3::Zero(), 0.0, RotorVector::Zero(4));
    const Quaternion q(Eigen::AngleAxisd(slope_rad, Vector3::UnitX()));
    x.segment<4>(StateIndex::kQuaternion) << q.w(), q.x(), q.y(), q.z();
    x.segment<3>(StateIndex::kPosition) = h * plane.normal_W;
    contact.Update(x);
  }
  void Run(double seconds) {
    for (int k = 0; k < std::lround(seconds / kDt); ++k) {
      integrator.Step(RotorVector::Zero(4), faults, {}, kDt, &x, &contact);
      contact.Update(x);
    }
  }
  Vector3 p() const { return StateView(x).p_W(); }
  Vector3 v() const { return StateView(x).v_W(); }
  /// The angle between body z and the plane's normal.
  double TiltFromPlane() const {
    const Vector3 z_B = StateView(x).q_WB().toRotationMatrix().col(2);
    return std::acos(std::clamp(z_B.dot(plane.normal_W), -1.0, 1.0));
  }
  /// Down the slope, in the plane.
  Vector3 Downhill() const { return Eigen::AngleAxisd(plane_slope(), Vector3::UnitX()) * -Vector3::UnitY(); }
  double plane_slope() const { return std::atan2(-plane.normal_W.y(), plane.normal_W.z()); }

  vehicle::VehicleParams params;
  vehicle::MultirotorModel model;
  vehicle::Rk4Integrator integrator;
  GroundPlane plane;
  GroundContact contact;
  vehicle::RotorFaults faults;
  vehicle::StateVector x;
};

TEST(GroundContactTest, AVehicleRestsOnItsFeetSunkByItsWeightOverTheirStiffness) {
  Block block(0.0, 0.6);
  block.Run(1.0);
  // Hooke: four springs carry m g, each sinking m g / (4 k).
  const double sink = block.params.mass_kg * kGravity / (4.0 * block.contact.point_stiffness_n_m());
  EXPECT_NEAR(block.p().z(), Block::h - sink, 1e-6);
  EXPECT_LT(block.v().norm(), 1e-5);
  EXPECT_EQ(block.contact.points_in_contact(), 4);
  EXPECT_LT(block.TiltFromPlane(), 1e-6);
  // The ground carries the weight, no more, at the centre of gravity (no torque).
  vehicle::Disturbance d;
  block.contact.AddTo(block.x, &d);
  EXPECT_NEAR(d.force_W.z(), block.params.weight_n(), 1e-3);
  EXPECT_LT(d.torque_B.norm(), 1e-6);
  // And the accelerometer's truth: the body does not accelerate.
  EXPECT_LT(block.model.ComputeAccelerations(block.x, block.faults, d).a_W.norm(), 1e-3);
}

TEST(GroundContactTest, AVehicleDroppedOntoItsFeetStopsWithinABounce) {
  Block block(0.0, 0.6);
  block.x[StateIndex::kVelocity + 2] = -1.0;  // a touchdown at 1 m/s
  block.Run(0.5);
  EXPECT_LT(block.v().norm(), 1e-3);
  EXPECT_GT(block.p().z(), Block::h - 0.01);  // stiff: a touchdown at 1 m/s sinks millimetres
  EXPECT_EQ(block.contact.points_in_contact(), 4);
}

TEST(GroundContactTest, OnASlopeSteeperThanItsFrictionAngleTheVehicleSlidesAtCoulombsAcceleration) {
  // Coulomb: down a slope theta with mu < tan(theta), a = g (sin theta - mu cos theta).
  const double theta = 20.0 * kDeg, mu = 0.2;
  Block block(theta, mu);
  block.Run(0.3);  // settled into the slide
  const Vector3 down = block.Downhill();
  const double v0 = block.v().dot(down);
  block.Run(1.0);
  const double a = block.v().dot(down) - v0;
  const double expected = kGravity * (std::sin(theta) - mu * std::cos(theta));
  EXPECT_NEAR(a, expected, 0.01 * expected);
  EXPECT_LT(block.TiltFromPlane(), 0.5 * kDeg);  // it slides, it does not tip
  EXPECT_EQ(block.contact.points_in_contact(), 4);
}

TEST(GroundContactTest, OnASlopeWithinItsFrictionAngleTheVehicleSticks) {
  // mu = 0.5 > tan(20 deg) = 0.36: static friction holds it; no creep as a viscous model would show.
  Block block(20.0 * kDeg, 0.5);
  block.Run(0.5);
  const Vector3 p0 = block.p();
  block.Run(3.0);
  EXPECT_LT((block.p() - p0).norm(), 1e-6);
  EXPECT_LT(block.v().norm(), 1e-6);
}

TEST(GroundContactTest, TheVehicleTipsOverWhereItsCentreOfGravityPassesItsDownhillFeet) {
  // With friction enough to stop a slide, the body tips over its downhill feet (at y = -b, h below
  // the centre of gravity) once the slope exceeds atan(b / h) = 53.1 deg (within 1.5 deg: the
  // springs sink under the downhill feet, a fraction of a degree).
  const double tip = std::atan2(Block::b, Block::h);
  Block below(tip - 1.5 * kDeg, 2.0), above(tip + 1.5 * kDeg, 2.0);
  below.Run(2.0);
  above.Run(2.0);
  EXPECT_LT(below.TiltFromPlane(), 0.5 * kDeg);
  EXPECT_EQ(below.contact.points_in_contact(), 4);
  EXPECT_GT(above.TiltFromPlane(), 30.0 * kDeg);
}

TEST(GroundContactTest, AYawSpinOnTheGroundIsBrakedByKineticFrictionAtItsFeet) {
  // Four feet at radius r = sqrt(a^2 + b^2), each pressed by m g / 4, slide against mu m g / 4:
  // the spin decelerates at mu m g r / I_zz (100 rad/s^2 here) and stops.
  Block block(0.0, 0.6);
  block.Run(0.2);
  const double w0 = 5.0;
  block.x[StateIndex::kBodyRate + 2] = w0;
  block.Run(0.02);
  const double r = std::hypot(Block::a, Block::b);
  const double alpha = 0.6 * block.params.weight_n() * r / block.params.inertia_kg_m2(2, 2);
  EXPECT_NEAR(StateView(block.x).w_B().z(), w0 - alpha * 0.02, 0.05 * alpha * 0.02);
  block.Run(0.5);
  EXPECT_LT(std::abs(StateView(block.x).w_B().z()), 1e-4);
}

TEST(GroundContactTest, RejectsBadInput) {
  EXPECT_THROW(GroundContact({}, 1.0, {}), std::invalid_argument);
  EXPECT_THROW(GroundContact({Vector3(0, 0, -0.05)}, 0.0, {}), std::invalid_argument);
  EXPECT_THROW(GroundContact({Vector3(0, 0, -0.05)}, 1.0, {}, {.normal_W = Vector3(0, 0, 2), .offset_m = 0}),
               std::invalid_argument);
  EXPECT_THROW(GroundContact({Vector3(0, 0, -0.05)}, 1.0, {.friction_coefficient = -1.0}), ValidationError);
}

}  // namespace
}  // namespace rotorguard::sim

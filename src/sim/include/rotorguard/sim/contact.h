#pragma once
/// The ground's contact on a vehicle's landing gear. Each contact point is a stiff spring-damper
/// along the ground's normal, pushing only, with Coulomb friction that sticks: a tangential
/// spring-damper ties the point to its anchor (where it touched down), its force limited to
/// mu * N; beyond that the point slides and the anchor follows it. A vehicle therefore rests on
/// its legs, tips about two of them when its weight falls outside them, pivots on one, and slides
/// on a slope steeper than atan(mu), as the closed forms say (tests/sim/contact_test.cc).
///
/// The springs are stiff (the vehicle bounces at `natural_frequency_hz` on them, sinking
/// m g / (n k), a fraction of a millimetre) yet slow enough for the simulator's RK4 at 1 kHz
/// (omega * dt ~ 0.16): the integrator evaluates the contact at each stage (vehicle::StateWrench).
#include <vector>

#include "rotorguard/core/config_schema.h"
#include "rotorguard/core/types.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::sim {

struct GroundContactOptions {
  /// The vehicle's vertical bounce on its gear [Hz]: each of n points gets k = m (2 pi f)^2 / n.
  double natural_frequency_hz = 25.0;
  /// Of that bounce; the tangential springs share k and the damping.
  double damping_ratio = 0.7;
  /// Coulomb's mu between the feet and the ground, static and kinetic (rubber feet on concrete or
  /// grass: 0.5-1).
  double friction_coefficient = 0.6;
  void Validate() const;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit("natural_frequency_hz", &natural_frequency_hz,
             {.meaning = "the vehicle's bounce on its landing gear [Hz]; sets the feet's stiffness", .min = 1.0, .max = 60.0});
    a->Visit("damping_ratio", &damping_ratio, {.meaning = "of that bounce", .min = 0.05, .max = 2.0});
    a->Visit("friction_coefficient", &friction_coefficient,
             {.meaning = "Coulomb's mu between the feet and the ground", .min = 0.0, .max = 2.0});
  }
};

/// The ground: the points p with normal . p = offset; the normal points out of the ground.
struct GroundPlane {
  Vector3 normal_W = Vector3::UnitZ();
  double offset_m = 0.0;
};

class GroundContact final : public vehicle::StateWrench {
 public:
  /// `points_B`: the landing gear's contact points relative to the centre of gravity, body frame
  /// (at least one); `mass_kg` sets the stiffness. Throws std::invalid_argument on bad input.
  GroundContact(std::vector<Vector3> points_B, double mass_kg, const GroundContactOptions& options,
                const GroundPlane& plane = {});

  /// The contact's force and torque at x (anchors as of the last Update).
  void AddTo(const vehicle::StateVector& x, vehicle::Disturbance* d) const override;
  /// After each accepted step: a point that touches gets its anchor, one that slides drags it,
  /// one that leaves the ground drops it.
  void Update(const vehicle::StateVector& x);

  /// Points touching the ground at the last Update.
  int points_in_contact() const;
  /// How far the deepest foot lies below the plane at x [m] (negative: all above it).
  double Depth(const vehicle::StateVector& x) const;
  /// How far the weight presses the feet into the ground when the vehicle stands level on all of
  /// them, m g / (n k) = g / (2 pi f)^2 [m].
  double standing_sink_m() const { return sink_m_; }
  /// The stiffness of one point [N/m].
  double point_stiffness_n_m() const { return k_; }
  const GroundPlane& plane() const { return plane_; }

 private:
  struct Foot {
    Vector3 c_B = Vector3::Zero();
    bool anchored = false;
    Vector3 anchor_W = Vector3::Zero();  // on the plane
  };
  struct FootState {
    Vector3 p_W, v_W;
    double depth = 0.0;  // below the plane, > 0 in contact
  };
  FootState StateOf(const Foot& f, const vehicle::StateView& s, const Matrix3& R) const;
  /// The normal force's magnitude on a foot in contact.
  double NormalForce(const FootState& fs) const;

  std::vector<Foot> feet_;
  GroundContactOptions options_;
  GroundPlane plane_;
  double k_ = 0.0, c_ = 0.0, sink_m_ = 0.0;
};

}  // namespace rotorguard::sim

#include "rotorguard/sim/contact.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/key_ranges.h"

namespace rotorguard::sim {

void GroundContactOptions::Validate() const { CheckDeclaredRanges("GroundContactOptions", *this); }

GroundContact::GroundContact(std::vector<Vector3> points_B, double mass_kg, const GroundContactOptions& options,
                             const GroundPlane& plane)
    : options_(options), plane_(plane) {
  options_.Validate();
  if (points_B.empty()) ThrowInvalidArgument("GroundContact", "points_B.size()", 0, "at least one contact point");
  for (std::size_t i = 0; i < points_B.size(); ++i) {
    if (!points_B[i].allFinite()) {
      ThrowInvalidArgument("GroundContact", fmt::format("points_B[{}]", i), "non-finite", "finite coordinates");
    }
    feet_.push_back({.c_B = points_B[i]});
  }
  if (!(mass_kg > 0.0) || !std::isfinite(mass_kg)) ThrowInvalidArgument("GroundContact", "mass_kg", mass_kg, "> 0");
  if (!plane.normal_W.allFinite() || std::abs(plane.normal_W.norm() - 1.0) > 1e-9 || !std::isfinite(plane.offset_m)) {
    ThrowInvalidArgument("GroundContact", "plane.normal_W.norm()", plane.normal_W.norm(), "a unit normal and a finite offset");
  }
  // Each foot carries m / n of the body: its spring and damper make the vehicle bounce at f with
  // damping ratio zeta when it stands on all of them.
  const double omega = 2.0 * std::numbers::pi * options_.natural_frequency_hz;
  const double m_foot = mass_kg / static_cast<double>(feet_.size());
  k_ = m_foot * omega * omega;
  c_ = 2.0 * options_.damping_ratio * m_foot * omega;
  sink_m_ = kGravity / (omega * omega);
}

GroundContact::FootState GroundContact::StateOf(const Foot& f, const vehicle::StateView& s, const Matrix3& R) const {
  FootState fs;
  const Vector3 r_W = R * f.c_B;
  fs.p_W = s.p_W() + r_W;
  fs.v_W = s.v_W() + R * s.w_B().cross(f.c_B);
  fs.depth = plane_.offset_m - plane_.normal_W.dot(fs.p_W);
  return fs;
}

double GroundContact::NormalForce(const FootState& fs) const {
  // The ground pushes, never pulls: a foot leaving faster than its spring relaxes lets go.
  return std::max(0.0, k_ * fs.depth - c_ * plane_.normal_W.dot(fs.v_W));
}

void GroundContact::AddTo(const vehicle::StateVector& x, vehicle::Disturbance* d) const {
  const vehicle::StateView s(x);
  const Matrix3 R = s.q_WB().toRotationMatrix();
  for (const Foot& f : feet_) {
    const FootState fs = StateOf(f, s, R);
    if (fs.depth <= 0.0) continue;
    const Vector3& n = plane_.normal_W;
    const double normal = NormalForce(fs);
    // The tangential spring to the anchor and its damper ...
    Vector3 tangential = -c_ * (fs.v_W - n.dot(fs.v_W) * n);
    if (f.anchored) {
      const Vector3 e = fs.p_W - f.anchor_W;
      tangential -= k_ * (e - n.dot(e) * n);
    }
    // ... within Coulomb's mu N (the foot slides at that force).
    const double limit = options_.friction_coefficient * normal;
    const double t = tangential.norm();
    if (t > limit) tangential *= limit / t;
    const Vector3 force_W = normal * n + tangential;
    d->force_W += force_W;
    d->torque_B += f.c_B.cross(R.transpose() * force_W);
  }
}

void GroundContact::Update(const vehicle::StateVector& x) {
  const vehicle::StateView s(x);
  const Matrix3 R = s.q_WB().toRotationMatrix();
  const Vector3& n = plane_.normal_W;
  for (Foot& f : feet_) {
    const FootState fs = StateOf(f, s, R);
    if (fs.depth <= 0.0) {
      f.anchored = false;
      continue;
    }
    const Vector3 on_plane = fs.p_W + fs.depth * n;
    if (!f.anchored) {
      f.anchored = true;
      f.anchor_W = on_plane;
      continue;
    }
    // Sliding: the spring's stretch beyond mu N / k is where the foot went, not the ground.
    const Vector3 e = on_plane - f.anchor_W;
    const double stretch = e.norm();
    const double max_stretch = options_.friction_coefficient * NormalForce(fs) / k_;
    if (stretch > max_stretch) f.anchor_W = on_plane - e * (max_stretch / stretch);
  }
}

int GroundContact::points_in_contact() const {
  return static_cast<int>(std::count_if(feet_.begin(), feet_.end(), [](const Foot& f) { return f.anchored; }));
}

double GroundContact::Depth(const vehicle::StateVector& x) const {
  const vehicle::StateView s(x);
  const Matrix3 R = s.q_WB().toRotationMatrix();
  double deepest = -std::numeric_limits<double>::infinity();
  for (const Foot& f : feet_) deepest = std::max(deepest, StateOf(f, s, R).depth);
  return deepest;
}

}  // namespace rotorguard::sim

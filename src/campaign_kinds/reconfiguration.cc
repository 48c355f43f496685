#include "rotorguard/campaign_kinds/reconfiguration.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>

#include <fmt/format.h>

#include "rotorguard/core/error.h"
#include "rotorguard/core/math.h"
#include "rotorguard/core/rng.h"
#include "rotorguard/core/stopwatch.h"
#include "rotorguard/harness/computation_delay.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/modular/assembly_controller.h"
#include "rotorguard/planning/references.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/sim/truth.h"
#include "rotorguard/stack/flight_stack.h"

namespace rotorguard::benchmarks {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

/// The truth of one body made of drawn units: its simulated vehicle (the units composed about
/// their common centre of gravity) and the draw it flies with, its first unit's (sensors, ESCs,
/// delays: that unit's computer flies the body) with the body's centre of gravity and every unit's
/// rotors.
struct BodyTruth {
  sim::TruthDraw draw;
  vehicle::VehicleParams vehicle;
};

/// The body whose file is `file`, made of the units `units` of `draws` (each drawn about
/// `unit_file`), unit k's file frame centred at `centre_B[k]` in the body's file frame.
BodyTruth ComposeTruth(const vehicle::VehicleParams& file, const vehicle::VehicleParams& unit_file,
                       const std::vector<sim::TruthDraw>& draws, const std::vector<int>& units,
                       const std::vector<Vector3>& centre_B) {
  std::vector<vehicle::VehicleParams> truths;
  truths.reserve(units.size());
  std::vector<modular::RigidPart> parts;
  BodyTruth t;
  t.draw = draws[static_cast<std::size_t>(units.front())];
  t.draw.thrust_coefficient_ratio.clear();
  t.draw.yaw_coefficient_ratio.clear();
  t.draw.esc_gain.clear();
  for (std::size_t k = 0; k < units.size(); ++k) {
    const sim::TruthDraw& d = draws[static_cast<std::size_t>(units[k])];
    truths.push_back(sim::TruthVehicle(unit_file, d));
    parts.push_back({&truths.back(), centre_B[k] + d.cog_offset_m});
    for (auto [to, from] : {std::pair{&t.draw.thrust_coefficient_ratio, &d.thrust_coefficient_ratio},
                            std::pair{&t.draw.yaw_coefficient_ratio, &d.yaw_coefficient_ratio},
                            std::pair{&t.draw.esc_gain, &d.esc_gain}}) {
      to->insert(to->end(), from->begin(), from->end());
    }
  }
  t.vehicle = modular::ComposeVehicle(parts, file.name, &t.draw.cog_offset_m);
  // The body stands on its file's feet (TruthVehicle's rule), about the true centre of gravity.
  t.vehicle.landing_gear_B.clear();
  for (const Vector3& f : file.LandingGear()) t.vehicle.landing_gear_B.push_back(f - t.draw.cog_offset_m);
  return t;
}

/// Where the file's body frame's origin is (what a stack estimates and tracks), in the world, for
/// the true state `x` of a body whose centre of gravity lies at `cog_B` in that frame.
Vector3 OriginOf(const vehicle::StateVector& x, const Vector3& cog_B) {
  const vehicle::StateView s(x);
  return s.p_W() - s.q_WB().normalized().toRotationMatrix() * cog_B;
}

/// One rigid body in flight: its truth (model, simulator) and its stack. `origin[k]` is the rotor
/// of the original assembly that rotor k of this body is, so faults follow their rotors.
struct Body {
  std::vector<int> origin;
  BodyTruth truth;
  std::unique_ptr<vehicle::MultirotorModel> model;
  std::unique_ptr<sim::Simulator> sim;
  std::unique_ptr<stack::FlightStack> stack;
  std::unique_ptr<harness::ComputationDelayModel> delay;
  modular::AssemblyController* controller = nullptr;  // owned by the stack, when an assembly
  TimeNs next_control = 0;

  /// A control cycle when one is due (its command reaches the ESCs after the cycle's computation
  /// delay, as in a flight of the runner), then one physics step. Until its estimate is valid (the
  /// odometry's first message, up to its latency after the split or the merge) a new body's stack
  /// commands nothing and the ESCs hold what its rotors were last commanded (the simulator starts
  /// from the motors' state): the hand-over of a vehicle in flight, not a start on the ground,
  /// whose idle command would drop it.
  void Step() {
    const TimeNs t = sim->time_ns();
    if (t >= next_control) {
      const Stopwatch clock;
      const RotorCommand command = stack->Update(t);
      if (stack->estimate().valid) sim->Send(command, t + delay->Next(clock.seconds()));
      next_control += stack->control_period_ns();
    }
    harness::DeliverToStack(sim->Step(), stack.get());
  }
  vehicle::StateView state() const { return vehicle::StateView(sim->state()); }
  Vector3 origin_W() const { return OriginOf(sim->state(), truth.draw.cog_offset_m); }
};

/// A body of `params` whose truth is `truth`, starting in `x` (its true centre of gravity's),
/// holding `reference`, flown by the assembly controller of `assembly` (or, when null, by the
/// nominal controller: a lone unit).
std::unique_ptr<Body> MakeBody(const harness::Scenario& base, const vehicle::VehicleParams& params, BodyTruth truth,
                               const modular::Assembly* assembly, std::vector<int> origin,
                               const vehicle::StateVector& x, std::shared_ptr<const ReferenceTrajectory> reference,
                               std::uint64_t seed) {
  auto b = std::make_unique<Body>();
  b->origin = std::move(origin);
  b->truth = std::move(truth);
  b->model = std::make_unique<vehicle::MultirotorModel>(b->truth.vehicle, sim::ThrustRatios(b->truth.draw));
  const auto index_of = [&](int original) {
    const auto it = std::find(b->origin.begin(), b->origin.end(), original);
    return it == b->origin.end() ? -1 : static_cast<int>(it - b->origin.begin());
  };
  std::vector<sim::FaultSpec> faults;
  for (sim::FaultSpec f : base.faults) {
    f.rotor = index_of(f.rotor);
    if (f.rotor < 0) continue;
    f.onset.kind = sim::FaultOnset::Kind::kAtTime;
    f.onset.value = 0.0;  // it has happened already
    faults.push_back(f);
  }
  stack::FlightStackOptions o = base.stack;
  o.known_faults.clear();
  std::unique_ptr<control::Controller> controller;
  if (assembly) {
    for (stack::KnownFault k : base.stack.known_faults) {
      k.rotor = index_of(k.rotor);
      k.at_time_s = 0.0;
      if (k.rotor >= 0) o.known_faults.push_back(k);
    }
    o.supervisor.max_failed_rotors = assembly->FailedRotorAllowance();
    auto c = std::make_unique<modular::AssemblyController>(*assembly, harness::AssemblyControllerOptionsOf(base));
    b->controller = c.get();
    controller = std::move(c);
  } else {
    o.controller = stack::ControllerKind::kNominal;
    o.supervisor.max_failed_rotors = 1;
  }
  b->sim = std::make_unique<sim::Simulator>(*b->model, base.world, faults,
                                            sim::TruthSimulatorOptions(base.sim, params, b->truth.draw), seed, x);
  b->stack = std::make_unique<stack::FlightStack>(params, std::move(reference), o, std::move(controller));
  b->delay = std::make_unique<harness::ComputationDelayModel>(base.computation_delay, b->truth.draw, seed);
  harness::DeliverToStack(b->sim->outputs(), b->stack.get());
  return b;
}

std::shared_ptr<const ReferenceTrajectory> Hold(const Vector3& p, double yaw) {
  planning::HoverOptions h;
  h.position_m = p;
  h.yaw_rad = yaw;
  return std::make_shared<planning::HoverReference>(h);
}

/// The state of a part of a rigid body whose centre of mass is `r_B` from the body's (body frame),
/// with the rotors `rotors` of the body.
vehicle::StateVector PartState(const vehicle::StateVector& x, const Vector3& r_B, const std::vector<int>& rotors) {
  const vehicle::StateView s(x);
  const Matrix3 R = s.q_WB().normalized().toRotationMatrix();
  vehicle::StateVector y(13 + static_cast<int>(rotors.size()));
  y.segment<3>(vehicle::StateIndex::kPosition) = s.p_W() + R * r_B;
  y.segment<4>(vehicle::StateIndex::kQuaternion) = x.segment<4>(vehicle::StateIndex::kQuaternion);
  y.segment<3>(vehicle::StateIndex::kVelocity) = s.v_W() + R * s.w_B().cross(r_B);
  y.segment<3>(vehicle::StateIndex::kBodyRate) = s.w_B();
  for (std::size_t k = 0; k < rotors.size(); ++k) y[vehicle::StateIndex::kMotor + static_cast<int>(k)] = s.motor(rotors[k]);
  return y;
}

/// A path moved by an offset that the docking guidance sets as the flight goes (a setpoint
/// correction sent to the unit's stack).
class GuidedReference final : public ReferenceTrajectory {
 public:
  explicit GuidedReference(std::shared_ptr<const ReferenceTrajectory> path) : path_(std::move(path)) {}
  [[nodiscard]] ReferencePoint Evaluate(double t) const override {
    ReferencePoint p = path_->Evaluate(t);
    p.p_W += offset_;
    return p;
  }
  [[nodiscard]] double duration() const override { return path_->duration(); }
  void set_offset(const Vector3& offset) { offset_ = offset; }

 private:
  std::shared_ptr<const ReferenceTrajectory> path_;
  Vector3 offset_ = Vector3::Zero();
};

/// Samples of the assembly (whichever body it is at the time) for the event windows.
struct Sample {
  double t;
  int body;
  Vector3 z_W, v_W;
};

/// The acceleration is the velocity's change over this long [s]: the mean acceleration an
/// accelerometer behind a 50 Hz low-pass reads, not the thrust's millisecond noise.
constexpr double kAccelWindowS = 0.02;

struct EventFigures {
  double max_attitude_deg = 0.0, max_accel = 0.0;
};

EventFigures Measure(const std::vector<Sample>& samples, double from, double to) {
  EventFigures f;
  const Sample* first = nullptr;
  std::size_t lag = 0;  // the sample kAccelWindowS before, once there is one in the window
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Sample& s = samples[i];
    if (s.t < from || s.t > to) continue;
    if (!first) first = &s;
    f.max_attitude_deg = std::max(f.max_attitude_deg, std::acos(std::clamp(s.z_W.dot(first->z_W), -1.0, 1.0)) / kDeg);
    while (lag < i && (samples[lag].t < from || samples[lag].t < s.t - kAccelWindowS - 1e-9)) ++lag;
    const Sample& earlier = samples[lag];
    if (earlier.body == s.body && s.t - earlier.t > kAccelWindowS - 1e-6) {
      f.max_accel = std::max(f.max_accel, ((s.v_W - earlier.v_W) / (s.t - earlier.t)).norm());
    }
  }
  return f;
}

}  // namespace

void ReconfigurationOptions::Validate() const {
  const auto fail = [](const char* field, double v, const char* rule) {
    ThrowInvalidArgument("ReconfigurationOptions", field, v, rule);
  };
  if (!base.assembly || base.stack.controller != stack::ControllerKind::kAssembly) {
    ThrowInvalidArgument("ReconfigurationOptions", "base", base.name, "an assembly scenario flown by controller assembly");
  }
  const modular::Assembly& a = *base.assembly;
  if (unit < 0 || unit >= a.num_units) fail("unit", unit, "a unit of the assembly");
  if (a.num_units < 2) fail("unit", unit, "an assembly of at least two units");
  for (const Eigen::Vector2i& s : a.slots) {
    if (s == target_slot) {
      ThrowInvalidArgument("ReconfigurationOptions", "target_slot", fmt::format("[{}, {}]", s.x(), s.y()), "a free grid cell");
    }
  }
  for (const sim::FaultSpec& f : base.faults) {
    if (a.UnitOfRotor(f.rotor) == unit) fail("unit", unit, "a healthy unit (it flies alone with the nominal controller)");
  }
  if (!(blend_s > 0.0 && separate_s > 2.0 * blend_s + window_s + 1.0)) {
    fail("separate_s", separate_s, "a time > 2 blend_s + window_s + 1 s (a steady window, then the separation)");
  }
  if (!(transfer_speed_m_s > 0.0)) fail("transfer_speed_m_s", transfer_speed_m_s, "> 0");
  if (!(climb_m > 0.0)) fail("climb_m", climb_m, "> 0");
  if (!(dock_tolerance_m > 0.0)) fail("dock_tolerance_m", dock_tolerance_m, "> 0");
  if (!(dock_speed_m_s > 0.0)) fail("dock_speed_m_s", dock_speed_m_s, "> 0");
  if (!(dock_camera_range_m > dock_tolerance_m)) fail("dock_camera_range_m", dock_camera_range_m, "> dock_tolerance_m");
  if (!(dock_camera_noise_m >= 0.0 && dock_camera_noise_m < dock_tolerance_m)) {
    fail("dock_camera_noise_m", dock_camera_noise_m, "in [0, dock_tolerance_m)");
  }
  if (!(dock_camera_rate_hz > 0.0)) fail("dock_camera_rate_hz", dock_camera_rate_hz, "> 0");
  if (!(dock_guidance_time_constant_s > 0.0)) {
    fail("dock_guidance_time_constant_s", dock_guidance_time_constant_s, "> 0");
  }
  if (!(hold_s > 0.0)) fail("hold_s", hold_s, "> 0");
  if (!(window_s > 0.0 && window_s <= hold_s)) fail("window_s", window_s, "in (0, hold_s]");
}

ReconfigurationResult RunReconfiguration(const ReconfigurationOptions& o) {
  o.Validate();
  ReconfigurationResult result;
  const harness::Scenario& base = o.base;
  const modular::Assembly& A = *base.assembly;
  const int per_unit = A.rotors_per_unit;
  const double yaw = base.initial_yaw_rad;
  std::vector<Sample> samples;
  const auto record = [&](double t, int id, const Body& b) {
    samples.push_back({t, id, b.state().q_WB().normalized().toRotationMatrix().col(2), b.state().v_W()});
  };
  const auto crashed = [&](const Body& b, const char* who) {
    if (!b.sim->crashed()) return false;
    result.failure = fmt::format("{} crashed: {}", who, b.sim->crash_reason().value_or("?"));
    return true;
  };

  // Each unit drawn about its file, once: the bodies it is part of are made of its draw.
  std::vector<sim::TruthDraw> draws;
  for (int u = 0; u < A.num_units; ++u) {
    draws.push_back(sim::DrawTruth(base.truth, A.unit, DeriveSeed(DeriveSeed(base.seed, "reconfiguration_unit"), u)));
  }
  const auto truth_of = [&](const vehicle::VehicleParams& file, const std::vector<int>& units,
                            const std::vector<Vector3>& centre_B) {
    return ComposeTruth(file, A.unit, draws, units, centre_B);
  };

  // Docked: the whole assembly holds the start (its file's origin there).
  std::vector<int> all(static_cast<std::size_t>(A.vehicle.num_rotors())), a_units;
  for (int k = 0; k < A.vehicle.num_rotors(); ++k) all[static_cast<std::size_t>(k)] = k;
  for (int u = 0; u < A.num_units; ++u) a_units.push_back(u);
  BodyTruth a_truth = truth_of(A.vehicle, a_units, A.unit_position_B);
  const Vector3 cog_a = a_truth.draw.cog_offset_m;
  const vehicle::MultirotorModel a_model(a_truth.vehicle, sim::ThrustRatios(a_truth.draw));
  const Matrix3 R_yaw = Eigen::AngleAxisd(yaw, Vector3::UnitZ()).toRotationMatrix();
  std::unique_ptr<Body> a =
      MakeBody(base, A.vehicle, std::move(a_truth), &A, all,
               a_model.MakeState(base.initial_position_m + R_yaw * cog_a, yaw, a_model.HoverThrusts()),
               Hold(base.initial_position_m, yaw), base.seed);
  const double blend_start = o.separate_s - o.blend_s;
  while (a->sim->time_s() < o.separate_s) {
    const double t = a->sim->time_s();
    if (!o.naive && t >= blend_start) a->controller->SetDetaching(o.unit, std::min(1.0, (t - blend_start) / o.blend_s));
    record(t, 0, *a);
    a->Step();
    if (crashed(*a, "the assembly")) return result;
  }
  result.separation_s = a->sim->time_s();

  // Separation: the remaining assembly B and the unit U, each from its part of A's state.
  modular::AssemblySpec b_spec;
  b_spec.name = A.name + "_without_unit";
  b_spec.unit = A.unit;
  b_spec.spacing_m = A.spacing_m;
  std::vector<int> b_rotors, u_rotors, b_units;
  Vector3 r_b = Vector3::Zero();  // B's file origin in A's file frame
  for (int u = 0; u < A.num_units; ++u) {
    for (int j = 0; j < per_unit; ++j) (u == o.unit ? u_rotors : b_rotors).push_back(A.FirstRotor(u) + j);
    if (u == o.unit) continue;
    b_units.push_back(u);
    b_spec.slots.push_back(A.slots[static_cast<std::size_t>(u)]);
    r_b += A.unit_position_B[static_cast<std::size_t>(u)] / (A.num_units - 1);
  }
  const modular::Assembly B = modular::BuildAssembly(b_spec);
  std::vector<Vector3> b_centres;
  for (int u : b_units) b_centres.push_back(A.unit_position_B[static_cast<std::size_t>(u)] - r_b);
  BodyTruth b_truth = truth_of(B.vehicle, b_units, b_centres), u_truth = truth_of(A.unit, {o.unit}, {Vector3::Zero()});
  // Each part's true centre of gravity from A's (both in A's file frame, then from A's CoG).
  const vehicle::StateVector x_a = a->sim->state();
  const vehicle::StateVector x_b = PartState(x_a, r_b + b_truth.draw.cog_offset_m - cog_a, b_rotors);
  const vehicle::StateVector x_u = PartState(
      x_a, A.unit_position_B[static_cast<std::size_t>(o.unit)] + u_truth.draw.cog_offset_m - cog_a, u_rotors);
  // The slot in B's frame, and in the world while B holds p_b0 at the yaw.
  Vector3 grid_com = Vector3::Zero();
  for (const Eigen::Vector2i& s : b_spec.slots) grid_com += Vector3(s.x(), s.y(), 0.0) * b_spec.spacing_m / b_spec.slots.size();
  const Vector3 slot_B = Vector3(o.target_slot.x(), o.target_slot.y(), 0.0) * b_spec.spacing_m - grid_com;
  const Vector3 p_b0 = OriginOf(x_b, b_truth.draw.cog_offset_m);
  const Vector3 p_u0 = OriginOf(x_u, u_truth.draw.cog_offset_m), target = p_b0 + R_yaw * slot_B;
  planning::WaypointOptions path;
  path.waypoints_m = {p_u0, p_u0 + Vector3(0, 0, o.climb_m), target + Vector3(0, 0, o.climb_m), target};
  path.max_speed_m_s = o.transfer_speed_m_s;
  path.max_accel_m_s2 = 0.5;
  path.yaw_rad = yaw;
  auto way = std::make_shared<GuidedReference>(std::make_shared<planning::WaypointReference>(path));
  const double transfer_s = way->duration();
  a.reset();
  std::unique_ptr<Body> b =
      MakeBody(base, B.vehicle, std::move(b_truth), &B, b_rotors, x_b, Hold(p_b0, yaw), base.seed + 1);
  std::unique_ptr<Body> u = MakeBody(base, A.unit, std::move(u_truth), nullptr, u_rotors, x_u, way, base.seed + 2);
  Rng camera(DeriveSeed(base.seed, "docking_camera"));
  const TimeNs camera_period = FromSeconds(1.0 / o.dock_camera_rate_hz);
  TimeNs next_frame = 0;
  Vector3 shift = Vector3::Zero(), unit_error = Vector3::Zero();
  // A first-order lag's gain per camera frame, for a time constant of `frames` frames. The
  // integral is four times slower than the lag: well inside the unit's position loop.
  const auto per_frame = [](double frames) { return 1.0 - std::exp(-1.0 / frames); };
  const double integral_gain = per_frame(4.0 * o.dock_camera_rate_hz * o.dock_guidance_time_constant_s);
  const double lag = per_frame(o.dock_camera_rate_hz * o.dock_guidance_time_constant_s);
  while (true) {
    const double t_local = b->sim->time_s(), t = o.separate_s + t_local;
    record(t, 1, *b);
    result.unit_max_tilt_deg = std::max(result.unit_max_tilt_deg, TiltOf(u->state().q_WB()) / kDeg);
    const Matrix3 R_b = b->state().q_WB().normalized().toRotationMatrix();
    const Vector3 slot_now = b->origin_W() + R_b * slot_B;
    // The docking camera's frame, and the guidance: the slot where the unit's estimate puts it.
    if (b->sim->time_ns() >= next_frame) {
      next_frame += camera_period;
      const Vector3 seen = slot_now - u->origin_W();
      if (seen.norm() < o.dock_camera_range_m && u->stack->estimate().valid) {
        // Seen in the unit's body axes, turned to the world's by the unit's estimated attitude.
        const Vector3 noise(camera.Normal(), camera.Normal(), camera.Normal());
        const Vector3 seen_B = u->state().q_WB().normalized().conjugate() * seen + o.dock_camera_noise_m * noise;
        const StateEstimate& e = u->stack->estimate();
        const Vector3 seen_W = e.q_WB.normalized() * seen_B;
        // The path ends where the estimate puts the slot; once it has ended, what the camera still
        // sees is the unit's own steady error, integrated out.
        shift += lag * (e.p_W + seen_W - target - shift);
        if (t_local >= transfer_s) unit_error -= integral_gain * seen_W;
        way->set_offset(shift - unit_error);
      }
    }
    if (t_local >= transfer_s) {
      if ((u->origin_W() - slot_now).norm() < o.dock_tolerance_m &&
          (u->state().v_W() - b->state().v_W()).norm() < o.dock_speed_m_s) {
        break;
      }
      if (t_local > transfer_s + 5.0) {
        result.failure = fmt::format("the unit did not reach its slot within 5 s of its path's end (off by {:.3f} m)",
                                     (u->origin_W() - slot_now).norm());
        return result;
      }
    }
    b->Step();
    u->Step();
    if (crashed(*b, "the assembly") || crashed(*u, "the unit")) return result;
  }
  result.docking_s = o.separate_s + b->sim->time_s();

  // Docking: one body again, its state from the two (momentum conserved; the latch aligns the
  // unit's attitude with the assembly's).
  modular::AssemblySpec c_spec = b_spec;
  c_spec.name = A.name + "_reconfigured";
  c_spec.slots.push_back(o.target_slot);
  const modular::Assembly C = modular::BuildAssembly(c_spec);
  std::vector<int> c_units = b_units;
  c_units.push_back(o.unit);  // C's units in c_spec's order: B's, then the unit in its new slot
  BodyTruth c_truth = truth_of(C.vehicle, c_units, C.unit_position_B);
  const double m_b = b->truth.vehicle.mass_kg, m_u = u->truth.vehicle.mass_kg, m = m_b + m_u;
  vehicle::StateVector x_c(13 + C.vehicle.num_rotors());
  x_c.segment<3>(vehicle::StateIndex::kPosition) = (m_b * b->state().p_W() + m_u * u->state().p_W()) / m;
  x_c.segment<4>(vehicle::StateIndex::kQuaternion) = b->sim->state().segment<4>(vehicle::StateIndex::kQuaternion);
  x_c.segment<3>(vehicle::StateIndex::kVelocity) = (m_b * b->state().v_W() + m_u * u->state().v_W()) / m;
  x_c.segment<3>(vehicle::StateIndex::kBodyRate) = b->state().w_B();
  std::vector<int> c_rotors = b_rotors;
  for (int k = 0; k < B.vehicle.num_rotors(); ++k) x_c[vehicle::StateIndex::kMotor + k] = b->state().motor(k);
  for (int j = 0; j < per_unit; ++j) {
    x_c[vehicle::StateIndex::kMotor + B.vehicle.num_rotors() + j] = u->state().motor(j);
    c_rotors.push_back(u_rotors[static_cast<std::size_t>(j)]);
  }
  const Vector3 p_c = OriginOf(x_c, c_truth.draw.cog_offset_m);
  b.reset();
  u.reset();
  std::unique_ptr<Body> c =
      MakeBody(base, C.vehicle, std::move(c_truth), &C, c_rotors, x_c, Hold(p_c, yaw), base.seed + 3);
  while (c->sim->time_s() < o.hold_s) {
    record(result.docking_s + c->sim->time_s(), 2, *c);
    c->Step();
    if (crashed(*c, "the docked assembly")) return result;
  }
  const EventFigures sep = Measure(samples, o.naive ? o.separate_s - 0.01 : blend_start - 0.01, o.separate_s + o.window_s);
  const EventFigures dock = Measure(samples, result.docking_s - 0.01, result.docking_s + o.window_s);
  const EventFigures steady =
      Measure(samples, blend_start - 0.5 - (o.separate_s + o.window_s - blend_start), blend_start - 0.5);
  result.steady_max_attitude_deg = steady.max_attitude_deg;
  result.steady_max_accel_m_s2 = steady.max_accel;
  result.separation_max_attitude_deg = sep.max_attitude_deg;
  result.separation_max_accel_m_s2 = sep.max_accel;
  result.docking_max_attitude_deg = dock.max_attitude_deg;
  result.docking_max_accel_m_s2 = dock.max_accel;
  const double held_m = (c->origin_W() - p_c).norm();
  result.success = held_m < 0.1;
  if (!result.success) {
    result.failure = fmt::format("the docked assembly did not hold its position within 0.1 m (off by {:.3f} m)", held_m);
  }
  return result;
}

}  // namespace rotorguard::benchmarks

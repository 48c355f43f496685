// rotorguard._core's flights: flying a scenario to its end (run) and a flight stepped from Python
// (Flight), whose simulator (the truth) and stack are separate views.
#include <pybind11/functional.h>
#include <pybind11/stl.h>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bindings.h"
#include "rotorguard/control/nmpc.h"
#include "rotorguard/fdd/composite_fdd.h"
#include "rotorguard/harness/flight.h"
#include "rotorguard/harness/runner.h"
#include "rotorguard/harness/scenario.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/sim/simulator.h"
#include "rotorguard/stack/flight_stack.h"
#include "rotorguard/vehicle/multirotor.h"

namespace rotorguard::python {
namespace {

/// The log's columns as {name: numpy array}, moved out of the table.
py::dict ColumnsOf(io::NumericTable&& table) {
  py::dict columns;
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    columns[py::str(table.columns[c])] = ArrayOf(std::move(table.values[c]));
  }
  return columns;
}

/// summary.json's object as a Python dict.
py::object DictOf(const harness::RunSummary& summary) { return FromJson(summary.ToJson()); }

/// The rotor command a Python sequence gives, one thrust per rotor [N].
RotorVector CommandOf(const py::array_t<double, py::array::c_style | py::array::forcecast>& thrust) {
  if (thrust.ndim() != 1) throw std::invalid_argument("command: expected a 1-D array of thrusts [N]");
  RotorVector u(static_cast<int>(thrust.shape(0)));
  auto in = thrust.unchecked<1>();
  for (py::ssize_t i = 0; i < thrust.shape(0); ++i) u[static_cast<int>(i)] = in(i);
  return u;
}

harness::RunOptions OptionsOf(const std::optional<std::string>& out, const std::string& log_format, bool report,
                              bool keep_log, bool stop_when_mission_complete) {
  harness::RunOptions o;
  o.out_dir = out.value_or("");
  const std::optional<harness::LogFormat> format = FromName<harness::LogFormat>(log_format);
  if (!format) throw std::invalid_argument("log_format: '" + log_format + "' is invalid; expected csv, mcap or both");
  o.log_format = *format;
  o.report = report;
  o.keep_log = keep_log;
  o.stop_when_mission_complete = stop_when_mission_complete;
  return o;
}

/// The truth's view of a flight: what the simulator flies. Only the Flight hands it out.
struct SimulatorView {
  const harness::Flight* flight;
  const sim::Simulator& sim() const { return flight->simulator(); }
};

/// The flight stack's view: what it received, estimated, diagnosed and commanded.
struct StackView {
  const harness::Flight* flight;
  const stack::FlightStack& stack() const { return flight->stack(); }
};

py::dict EstimateOf(const StateEstimate& e) {
  py::dict d;
  d["t_s"] = ToSeconds(e.t_ns);
  d["valid"] = e.valid;
  d["position"] = ArrayOf(e.p_W);
  d["attitude"] = ArrayOf(e.q_WB);
  d["velocity"] = ArrayOf(e.v_W);
  d["angular_velocity"] = ArrayOf(e.w_B);
  return d;
}

/// A LiDAR frame's returns as an (n, 3) float32 array in the sensor frame [m]. A copy: the
/// simulator replaces the frame at its next one.
py::array_t<float> PointsOf(const LidarFrame& frame) {
  const auto n = static_cast<py::ssize_t>(frame.points_S.size());
  py::array_t<float> a({n, py::ssize_t{3}});
  auto out = a.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    for (py::ssize_t k = 0; k < 3; ++k) out(i, k) = frame.points_S[static_cast<std::size_t>(i)](k);
  }
  return a;
}

/// Per return: its time after the frame's start [s].
py::array_t<double> OffsetsOf(const LidarFrame& frame) {
  std::vector<double> offsets(frame.offset_ns.size());
  for (std::size_t i = 0; i < offsets.size(); ++i) offsets[i] = ToSeconds(frame.offset_ns[i]);
  return ArrayOf(std::move(offsets));
}

/// The sensor messages of the latest step, by kind (those the step produced).
py::dict MessagesOf(const sim::SensorOutputs& o) {
  py::dict d;
  if (o.imu) {
    d["imu"] =
        py::dict(py::arg("t_s") = ToSeconds(o.imu->t_ns), py::arg("specific_force") = ArrayOf(o.imu->specific_force_B),
                 py::arg("angular_velocity") = ArrayOf(o.imu->w_B));
  }
  if (o.esc) {
    d["esc"] = py::dict(py::arg("t_s") = ToSeconds(o.esc->t_ns),
                        py::arg("motor_speed_rad_s") = ArrayOf(o.esc->motor_speed_rad_s));
  }
  if (o.odometry) {
    d["odometry"] =
        py::dict(py::arg("t_s") = ToSeconds(o.odometry->t_ns), py::arg("position") = ArrayOf(o.odometry->p_W),
                 py::arg("attitude") = ArrayOf(o.odometry->q_WB), py::arg("velocity") = ArrayOf(o.odometry->v_W));
  }
  if (o.lidar) {
    d["lidar"] = py::dict(py::arg("t_start_s") = ToSeconds(o.lidar->t_start_ns),
                          py::arg("t_end_s") = ToSeconds(o.lidar->t_end_ns), py::arg("points") = PointsOf(*o.lidar),
                          py::arg("offsets_s") = OffsetsOf(*o.lidar), py::arg("dropped") = o.lidar->dropped);
  }
  return d;
}

}  // namespace

void BindFlight(py::module_& m) {
  m.def(
      "run",
      [](const harness::Scenario& scenario, const std::optional<std::string>& out, const std::string& log_format,
         bool report, bool keep_log, bool stop_when_mission_complete) {
        harness::RunOptions options = OptionsOf(out, log_format, report, keep_log, stop_when_mission_complete);
        std::optional<harness::RunSummary> summary;
        io::NumericTable log;
        {
          // The flight holds no Python object: other threads run meanwhile (flights in parallel).
          py::gil_scoped_release release;
          harness::Flight flight(scenario, options);
          flight.Fly();
          summary = flight.Finish();
          log = flight.TakeLog();
        }
        return py::make_tuple(DictOf(*summary), ColumnsOf(std::move(log)), summary->success,
                              summary->infeasible_request);
      },
      py::arg("scenario"), py::arg("out"), py::arg("log_format"), py::arg("report"), py::arg("keep_log"),
      py::arg("stop_when_mission_complete"));

  py::class_<SimulatorView>(m, "SimulatorView", "The truth: the simulated vehicle, its rotors and faults")
      .def_property_readonly("time_s", [](const SimulatorView& v) { return v.sim().time_s(); })
      .def_property_readonly("state", [](const SimulatorView& v) { return ArrayOf(v.sim().state()); })
      .def_property_readonly("position",
                             [](const SimulatorView& v) { return ArrayOf(vehicle::StateView(v.sim().state()).p_W()); })
      .def_property_readonly("attitude",
                             [](const SimulatorView& v) { return ArrayOf(vehicle::StateView(v.sim().state()).q_WB()); })
      .def_property_readonly("velocity",
                             [](const SimulatorView& v) { return ArrayOf(vehicle::StateView(v.sim().state()).v_W()); })
      .def_property_readonly("angular_velocity",
                             [](const SimulatorView& v) { return ArrayOf(vehicle::StateView(v.sim().state()).w_B()); })
      .def_property_readonly("rotor_thrusts", [](const SimulatorView& v) { return ArrayOf(v.sim().rotor_thrusts()); })
      .def_property_readonly("motor_speeds", [](const SimulatorView& v) { return ArrayOf(v.sim().motor_speeds()); })
      .def_property_readonly("applied_command",
                             [](const SimulatorView& v) { return ArrayOf(v.sim().applied_command()); })
      .def_property_readonly("wind", [](const SimulatorView& v) { return ArrayOf(v.sim().wind()); })
      .def_property_readonly("landed", [](const SimulatorView& v) { return v.sim().landed(); })
      .def_property_readonly("crashed", [](const SimulatorView& v) { return v.sim().crashed(); })
      .def_property_readonly("crash_reason", [](const SimulatorView& v) { return v.sim().crash_reason(); })
      .def_property_readonly("faults",
                             [](const SimulatorView& v) {
                               std::vector<std::string> kinds;
                               for (const vehicle::RotorFaultState& f : v.sim().faults()) {
                                 kinds.emplace_back(vehicle::ToString(f.kind));
                               }
                               return kinds;
                             })
      .def_property_readonly("fault_events", [](const SimulatorView& v) {
        py::list events;
        for (const sim::FaultEvent& e : v.sim().fault_events()) {
          events.append(py::dict(py::arg("rotor") = e.rotor, py::arg("kind") = std::string(vehicle::ToString(e.kind)),
                                 py::arg("onset_s") = e.onset_s));
        }
        return events;
      });

  py::class_<StackView>(m, "StackView", "The flight stack: its estimate, reference, modes, fault detection, command")
      .def_property_readonly("estimate", [](const StackView& v) { return EstimateOf(v.stack().estimate()); })
      .def_property_readonly("reference",
                             [](const StackView& v) {
                               const ReferencePoint& r = v.stack().reference_point();
                               return py::dict(
                                   py::arg("position") = ArrayOf(r.p_W), py::arg("velocity") = ArrayOf(r.v_W),
                                   py::arg("acceleration") = ArrayOf(r.a_W), py::arg("jerk") = ArrayOf(r.j_W),
                                   py::arg("snap") = ArrayOf(r.s_W), py::arg("yaw") = r.yaw,
                                   py::arg("yaw_rate") = r.yaw_rate);
                             })
      .def_property_readonly("command", [](const StackView& v) { return ArrayOf(v.stack().command().thrust_n); })
      .def_property_readonly("mode",
                             [](const StackView& v) { return std::string(ToString(v.stack().supervisor().mode())); })
      .def_property_readonly("control_period_s",
                             [](const StackView& v) { return ToSeconds(v.stack().control_period_ns()); })
      .def_property_readonly("isolated_rotors", [](const StackView& v) { return v.stack().isolated_rotors(); })
      .def_property_readonly("waypoints_reached", [](const StackView& v) { return v.stack().waypoints_reached(); })
      .def_property_readonly(
          "fdd",
          [](const StackView& v) -> py::object {
            const fdd::FaultDetector* detector = v.stack().fault_detector();
            if (detector == nullptr) return py::none();
            py::list rotors;
            for (const fdd::RotorStatus& r : detector->rotors()) {
              rotors.append(py::dict(py::arg("health") = std::string(fdd::ToString(r.health)),
                                     py::arg("motor_index") = r.motor_index,
                                     py::arg("propeller_index") = r.propeller_index, py::arg("eta") = r.eta,
                                     py::arg("detected_s") = r.detected_s, py::arg("detector") = r.detector));
            }
            return rotors;
          })
      .def_property_readonly(
          "nmpc",
          [](const StackView& v) -> py::object {
            const control::NmpcController* nmpc = v.stack().nmpc();
            if (nmpc == nullptr) return py::none();
            const control::NmpcSummary& s = nmpc->summary();
            return py::dict(py::arg("status") = std::string(control::ToString(s.status)),
                            py::arg("sqp_iterations") = s.sqp_iterations, py::arg("qp_iterations") = s.qp_iterations,
                            py::arg("kkt_residual") = s.kkt_residual, py::arg("objective") = s.objective,
                            py::arg("solve_time_s") = s.solve_time_s, py::arg("fallbacks") = s.fallbacks);
          })
      .def_property_readonly("model", [](const StackView& v) {
        // The vehicle as the stack knows it (its file), which the truth departs from.
        const vehicle::MultirotorModel& model = v.stack().model();
        const vehicle::VehicleParams& p = model.params();
        return py::dict(py::arg("mass_kg") = p.mass_kg, py::arg("inertia_kg_m2") = MatrixOf(p.inertia_kg_m2),
                        py::arg("effectiveness") = MatrixOf(model.effectiveness()),
                        py::arg("max_thrust_n") = ArrayOf(model.max_thrust()),
                        py::arg("hover_thrusts_n") = ArrayOf(model.HoverThrusts()),
                        py::arg("rotor_drag_kg_s") = ArrayOf(p.rotor_drag_kg_s),
                        py::arg("yaw_damping_n_m_s") = p.yaw_damping_n_m_s,
                        py::arg("motor_time_constant_s") = p.motor_time_constant_s, py::arg("gravity_m_s2") = kGravity);
      });

  py::class_<harness::Flight>(m, "Flight")
      .def(py::init([](const harness::Scenario& scenario, const std::optional<std::string>& out,
                       const std::string& log_format, bool report, bool keep_log, bool stop_when_mission_complete) {
             return std::make_unique<harness::Flight>(
                 scenario, OptionsOf(out, log_format, report, keep_log, stop_when_mission_complete));
           }),
           py::arg("scenario"), py::arg("out"), py::arg("log_format"), py::arg("report"), py::arg("keep_log"),
           py::arg("stop_when_mission_complete"))
      .def_property_readonly("done", &harness::Flight::done)
      .def_property_readonly("time_s", [](const harness::Flight& f) { return f.simulator().time_s(); })
      .def_property_readonly("steps_total", &harness::Flight::steps_total)
      .def_property_readonly("steps_taken", &harness::Flight::steps_taken)
      .def("step", &harness::Flight::Step, "One physics step (the stack's control cycle first when due)")
      .def(
          "step_control",
          [](harness::Flight& f,
             const std::optional<py::array_t<double, py::array::c_style | py::array::forcecast>>& command) {
            if (!command) return f.StepControlPeriod(nullptr);
            const RotorVector u = CommandOf(*command);
            return f.StepControlPeriod(&u);
          },
          py::arg("command") = py::none())
      .def("fly", &harness::Flight::Fly, py::call_guard<py::gil_scoped_release>())
      .def("finish",
           [](harness::Flight& f) {
             std::optional<harness::RunSummary> summary;
             {
               py::gil_scoped_release release;
               summary = f.Finish();
             }
             return py::make_tuple(DictOf(*summary), summary->success, summary->infeasible_request);
           })
      .def("take_log", [](harness::Flight& f) { return ColumnsOf(f.TakeLog()); })
      .def_property_readonly("messages", [](const harness::Flight& f) { return MessagesOf(f.simulator().outputs()); })
      .def_property_readonly(
          "simulator", [](const harness::Flight& f) { return SimulatorView{&f}; }, py::keep_alive<0, 1>())
      .def_property_readonly(
          "stack", [](const harness::Flight& f) { return StackView{&f}; }, py::keep_alive<0, 1>());
}

}  // namespace rotorguard::python

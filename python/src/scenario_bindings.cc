// rotorguard._core's scenario: loading one, its read-only facts, and its options as the keys the
// options structs declare (Serialize), read and written through the scenario loader.
#include <pybind11/stl.h>

#include <string>

#include "bindings.h"
#include "rotorguard/harness/scenario.h"

namespace rotorguard::python {

void BindScenario(py::module_& m) {
  py::class_<harness::Scenario>(m, "Scenario", "A loaded, validated scenario (rotorguard.load_scenario)")
      .def_readonly("name", &harness::Scenario::name)
      .def_readonly("file", &harness::Scenario::file)
      .def_readwrite("seed", &harness::Scenario::seed)
      .def_readonly("duration_s", &harness::Scenario::duration_s)
      .def_property_readonly("num_rotors", [](const harness::Scenario& s) { return s.vehicle.num_rotors(); })
      .def_property_readonly("control_rate_hz", [](const harness::Scenario& s) { return s.stack.control_rate_hz; })
      .def_property_readonly("controller",
                             [](const harness::Scenario& s) { return std::string(ToName(s.stack.controller)); })
      .def_property_readonly(
          "options", [](const harness::Scenario& s) { return FromJson(harness::ScenarioOptions(s)); },
          "How the scenario is flown: its sim, sensors, wind, stack and metrics sections as a dict, in the "
          "scenario file's keys and units (each key's declaration, docs/scenarios.md)")
      .def(
          "set_options",
          [](harness::Scenario& s, const py::object& options) {
            // A dict (numpy values as lists) as indented JSON, so that an error's line finds the key.
            const py::function tolist = py::cpp_function([](const py::object& o) { return o.attr("tolist")(); });
            const std::string text =
                py::isinstance<py::str>(options)
                    ? options.cast<std::string>()
                    : py::module_::import("json").attr("dumps")(options, py::arg("indent") = 1, py::arg("default") = tolist)
                          .cast<std::string>();
            harness::SetScenarioOptions(&s, text, "<options>");
          },
          py::arg("options"),
          "Sets keys of those sections from a dict of the same shape (or its YAML or JSON text), through the "
          "loader's readers and rules; keys left out keep their values, and nothing changes when it raises")
      .def("__repr__", [](const harness::Scenario& s) {
        return "<rotorguard.Scenario '" + s.name + "' from '" + s.file + "', seed " + std::to_string(s.seed) + ">";
      });

  m.def("load_scenario", &harness::LoadScenario, py::arg("path"), py::arg("overrides"),
        "Loads and validates a scenario file with key.path=value overrides");

}

}  // namespace rotorguard::python

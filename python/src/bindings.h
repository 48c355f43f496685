#pragma once
// rotorguard._core, the C++ side of the Python package (python/rotorguard/, docs/python.md), in
// parts by topic, joined by module.cc: the scenario and its options (scenario_bindings.cc), flights
// and their views (flight_bindings.cc), campaigns and their statistics (campaign_bindings.cc).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <vector>

#include "rotorguard/core/types.h"

namespace rotorguard::python {

namespace py = pybind11;

/// A numpy array that owns `values` (moved, not copied).
py::array_t<double> ArrayOf(std::vector<double>&& values);

/// A copy of a fixed or dynamic Eigen vector as a 1-D numpy array.
template <typename Derived>
py::array_t<double> ArrayOf(const Eigen::MatrixBase<Derived>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  auto out = a.mutable_unchecked<1>();
  for (Eigen::Index i = 0; i < v.size(); ++i) out(i) = v(i);
  return a;
}

py::array_t<double> ArrayOf(const Quaternion& q);
py::array_t<double> MatrixOf(const Eigen::MatrixXd& m);
/// A JSON value as the Python object json.loads makes of it.
py::object FromJson(const nlohmann::json& value);

void BindScenario(py::module_& m);
void BindFlight(py::module_& m);
void BindCampaigns(py::module_& m);

}  // namespace rotorguard::python

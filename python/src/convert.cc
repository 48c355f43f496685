#include "bindings.h"

#include <utility>

namespace rotorguard::python {

py::array_t<double> ArrayOf(std::vector<double>&& values) {
  auto* owned = new std::vector<double>(std::move(values));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>({static_cast<py::ssize_t>(owned->size())}, {sizeof(double)}, owned->data(),
                             free_when_done);
}

py::array_t<double> ArrayOf(const Quaternion& q) { return ArrayOf(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z())); }

py::array_t<double> MatrixOf(const Eigen::MatrixXd& m) {
  py::array_t<double> a({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  auto out = a.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) out(r, c) = m(r, c);
  }
  return a;
}

py::object FromJson(const nlohmann::json& value) { return py::module_::import("json").attr("loads")(value.dump()); }

}  // namespace rotorguard::python

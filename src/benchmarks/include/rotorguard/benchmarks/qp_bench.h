#pragma once
/// `rotorguard bench qp`: the NMPC's QP solver on a reference OCP QP instance (JSON: N, nx, nu,
/// A, B, Q_diag, R_diag, input and state bounds, and cases of x0 with the optimal u_0 found by an
/// interior-point solver). Every case is solved cold; times and the error in u_0 are reported.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorguard/control/ocp_qp.h"

namespace rotorguard::benchmarks {

struct QpBenchOptions {
  int repetitions = 3;  ///< each case is solved this many times; its median time counts, >= 1
  control::OcpQpMethod solver = control::OcpQpMethod::kRiccati;
};

/// One case of an instance: the initial state and the instance's optimal first input.
struct QpInstanceCase {
  Eigen::VectorXd x0, u0;
};

/// A reference instance as this library's OCP QP (the instance's cost, sum x'Qx + u'Ru, is written
/// with the factor 1/2 of OcpQp: Q and R doubled), and its two groups of cases.
struct QpInstance {
  control::OcpQp qp;
  std::vector<QpInstanceCase> stress;  ///< about 20 active bounds each
  std::vector<QpInstanceCase> track;   ///< about one
};

/// Reads the instance at `path`. Throws io::InputFileError when the file cannot be read or is not a
/// valid instance (it names the missing or malformed field).
QpInstance LoadQpInstance(const std::string& path);

/// Runs the benchmark on the instance at `path`. Throws io::InputFileError when the file cannot be
/// read or is not a valid instance (it names the missing or malformed field).
nlohmann::json RunQpBenchmark(const std::string& path, const QpBenchOptions& options);

}  // namespace rotorguard::benchmarks

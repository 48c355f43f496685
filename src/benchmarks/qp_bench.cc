#include "rotorguard/benchmarks/qp_bench.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/control/ocp_qp.h"
#include "rotorguard/core/error.h"
#include "rotorguard/core/statistics.h"
#include "rotorguard/io/config_node.h"
#include "rotorguard/io/files.h"

namespace rotorguard::benchmarks {

namespace {
using nlohmann::json;
constexpr double kInf = std::numeric_limits<double>::infinity();

Eigen::VectorXd Vector(const json& j, const std::string& what, int size) {
  if (!j.is_array() || static_cast<int>(j.size()) != size) {
    throw std::runtime_error(fmt::format("'{}' must be an array of {} numbers", what, size));
  }
  Eigen::VectorXd v(size);
  for (int i = 0; i < size; ++i) v[i] = j[i].get<double>();
  if (!v.allFinite()) throw std::runtime_error(fmt::format("'{}' holds non-finite numbers", what));
  return v;
}

Eigen::MatrixXd Matrix(const json& j, const std::string& what, int rows, int cols) {
  if (!j.is_array() || static_cast<int>(j.size()) != rows) {
    throw std::runtime_error(fmt::format("'{}' must have {} rows", what, rows));
  }
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) m.row(r) = Vector(j[r], fmt::format("{}[{}]", what, r), cols).transpose();
  return m;
}

struct GroupResult {
  std::vector<double> times_us;
  std::vector<double> prepare_us, feedback_us;  ///< per case, each phase's fastest repetition
  std::vector<double> u0_errors;
  double iterations_sum = 0.0;
  std::vector<double> iterations, active;  ///< per case
  int failures = 0;
  /// Cases whose reference u_0 is provably not optimal for the stated problem: fixing u_0 to it
  /// makes the best achievable objective higher than ours (and ours is feasible).
  int reference_suboptimal = 0;
  double worst_reference_gap = 0.0;  ///< largest such relative objective gap
};
}  // namespace

QpInstance LoadQpInstance(const std::string& path) {
  std::string text;
  try {
    text = io::ReadFile(path);
  } catch (const std::runtime_error& e) {
    throw io::InputFileError(path, e.what());
  }
  control::OcpQpDims dims;
  std::unique_ptr<control::OcpQp> qp;
  std::vector<QpInstanceCase> stress, track;
  try {
    const json doc = json::parse(text);
    dims.horizon = doc.at("N").get<int>();
    dims.nx = doc.at("nx").get<int>();
    dims.nu = doc.at("nu").get<int>();
    for (const auto& i : doc.at("rate_index")) dims.state_bound_index.push_back(i.get<int>());
    dims.Validate();
    const int nx = dims.nx, nu = dims.nu, nbx = static_cast<int>(dims.state_bound_index.size());
    qp = std::make_unique<control::OcpQp>(dims);
    const Eigen::MatrixXd A = Matrix(doc.at("A"), "A", nx, nx);
    const Eigen::MatrixXd B = Matrix(doc.at("B"), "B", nx, nu);
    // The instance's cost has no factor 1/2: sum x'Qx + u'Ru. Ours is 1/2 x'Qx: double it.
    const Eigen::MatrixXd Q = 2.0 * Vector(doc.at("Q_diag"), "Q_diag", nx).asDiagonal().toDenseMatrix();
    const Eigen::MatrixXd R = 2.0 * Vector(doc.at("R_diag"), "R_diag", nu).asDiagonal().toDenseMatrix();
    const Eigen::VectorXd ul = Vector(doc.at("u_lower"), "u_lower", nu), uu = Vector(doc.at("u_upper"), "u_upper", nu);
    const Eigen::VectorXd xl = Vector(doc.at("rate_lower"), "rate_lower", nbx);
    const Eigen::VectorXd xu = Vector(doc.at("rate_upper"), "rate_upper", nbx);
    for (int k = 0; k < dims.horizon; ++k) {
      qp->A[k] = A;
      qp->B[k] = B;
      qp->R[k] = R;
      qp->u_lower[k] = ul;
      qp->u_upper[k] = uu;
    }
    for (int k = 0; k <= dims.horizon; ++k) {
      qp->Q[k] = Q;
      qp->x_lower[k] = xl;
      qp->x_upper[k] = xu;
    }
    for (const auto& [name, cases] : {std::pair{"stress", &stress}, std::pair{"track", &track}}) {
      int i = 0;
      for (const auto& c : doc.at(name)) {
        cases->push_back({Vector(c.at("x0"), fmt::format("{}[{}].x0", name, i), nx),
                          Vector(c.at("u0"), fmt::format("{}[{}].u0", name, i), nu)});
        ++i;
      }
    }
  } catch (const json::exception& e) {
    throw io::InputFileError(path, fmt::format("not a valid QP instance: {}", e.what()));
  } catch (const std::exception& e) {
    throw io::InputFileError(path, fmt::format("not a valid QP instance: {}", e.what()));
  }
  return QpInstance{std::move(*qp), std::move(stress), std::move(track)};
}

json RunQpBenchmark(const std::string& path, const QpBenchOptions& options) {
  if (options.repetitions < 1) ThrowInvalidArgument("RunQpBenchmark", "repetitions", options.repetitions, ">= 1");
  QpInstance instance = LoadQpInstance(path);
  control::OcpQp* qp = &instance.qp;
  const control::OcpQpDims& dims = qp->dims;
  const std::vector<QpInstanceCase>& stress = instance.stress;
  const std::vector<QpInstanceCase>& track = instance.track;

  // Every case, and every repetition of one, is solved cold, as the reference solver's figures
  // are: a start from the previous solve's active set would make the repetitions free.
  control::ActiveSetOptions cold;
  cold.warm_start = false;
  const std::unique_ptr<control::OcpQpSolver> solver = control::MakeOcpQpSolver(options.solver, dims, cold);
  // Each case where u_0 differs from the reference by more than this is cross-examined.
  constexpr double kExamineError = 1e-4;
  const auto run = [&](const std::vector<QpInstanceCase>& cases) {
    GroupResult g;
    std::vector<double> reps(static_cast<std::size_t>(options.repetitions));
    for (const QpInstanceCase& c : cases) {
      qp->x0 = c.x0;
      double prepare_min = kInf, feedback_min = kInf;
      for (int r = 0; r < options.repetitions; ++r) {
        const control::OcpQpSummary& s = solver->Solve(*qp);
        reps[r] = s.total_time_s * 1e6;
        prepare_min = std::min(prepare_min, s.prepare_time_s * 1e6);
        feedback_min = std::min(feedback_min, s.feedback_time_s * 1e6);
      }
      g.times_us.push_back(Percentile(reps, 0.5));
      g.prepare_us.push_back(prepare_min);
      g.feedback_us.push_back(feedback_min);
      const control::OcpQpSummary& s = solver->summary();
      if (!s.IsSolutionUsable()) ++g.failures;
      g.iterations_sum += s.iterations;
      g.iterations.push_back(s.iterations);
      g.active.push_back(s.active_constraints);
      const double error = (solver->u()[0] - c.u0).cwiseAbs().maxCoeff();
      g.u0_errors.push_back(error);
      if (error > kExamineError && s.IsSolutionUsable()) {
        // The best objective with u_0 pinned to the reference's value, against ours.
        const double ours = s.objective;
        const Eigen::VectorXd lower = qp->u_lower[0], upper = qp->u_upper[0];
        qp->u_lower[0] = c.u0;
        qp->u_upper[0] = c.u0;
        const control::OcpQpSummary& pinned = solver->Solve(*qp);
        if (pinned.IsSolutionUsable() && pinned.objective > ours * (1.0 + 1e-12)) {
          ++g.reference_suboptimal;
          g.worst_reference_gap = std::max(g.worst_reference_gap, (pinned.objective - ours) / std::abs(ours));
        }
        qp->u_lower[0] = lower;
        qp->u_upper[0] = upper;
      }
    }
    return g;
  };
  const GroupResult st = run(stress), tr = run(track);
  // What the slowest 1 % of the stress cases do, beside the median case: a case's time is about a
  // preparation plus a constant per active-set change, so the tail is the cases with most changes.
  const auto slowest = [](const GroupResult& g, const std::vector<double>& per_case) {
    std::vector<std::size_t> order(g.times_us.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return g.times_us[a] > g.times_us[b]; });
    const std::size_t n = std::max<std::size_t>(1, order.size() / 100);
    double sum = 0.0;
    for (std::size_t i = 0; i < n && i < order.size(); ++i) sum += per_case[order[i]];
    return order.empty() ? 0.0 : sum / static_cast<double>(std::min(n, order.size()));
  };
  const double cases = static_cast<double>(stress.size() + track.size());
  std::vector<double> all_errors = st.u0_errors;
  all_errors.insert(all_errors.end(), tr.u0_errors.begin(), tr.u0_errors.end());
  return {{"benchmark", "qp"},
          {"instance", path},
          {"solver", options.solver == control::OcpQpMethod::kRiccati
                         ? "riccati: Riccati factorisation + range-space Goldfarb-Idnani dual active set"
                         : "condensing: condensing + Goldfarb-Idnani dual active set"},
          {"cases_stress", stress.size()},
          {"cases_track", track.size()},
          {"repetitions", options.repetitions},
          {"stress_us_median", Percentile(st.times_us, 0.5)},
          {"stress_us_p99", Percentile(st.times_us, 0.99)},
          {"track_us_median", Percentile(tr.times_us, 0.5)},
          {"track_us_p99", Percentile(tr.times_us, 0.99)},
          {"stress_prepare_us_median", Percentile(st.prepare_us, 0.5)},
          {"stress_feedback_us_median", Percentile(st.feedback_us, 0.5)},
          {"track_prepare_us_median", Percentile(tr.prepare_us, 0.5)},
          {"track_feedback_us_median", Percentile(tr.feedback_us, 0.5)},
          {"iterations_mean", cases > 0 ? (st.iterations_sum + tr.iterations_sum) / cases : 0.0},
          {"stress_iterations_median", Percentile(st.iterations, 0.5)},
          {"stress_active_median", Percentile(st.active, 0.5)},
          {"stress_slowest_1pct_iterations_mean", slowest(st, st.iterations)},
          {"stress_slowest_1pct_active_mean", slowest(st, st.active)},
          {"max_u0_error", std::max(Percentile(st.u0_errors, 1.0), Percentile(tr.u0_errors, 1.0))},
          {"u0_error_median", Percentile(all_errors, 0.5)},
          {"u0_error_p99", Percentile(all_errors, 0.99)},
          {"cases_u0_error_above_1e-4",
           std::count_if(all_errors.begin(), all_errors.end(), [](double e) { return e > 1e-4; })},
          {"cases_reference_u0_suboptimal", st.reference_suboptimal + tr.reference_suboptimal},
          {"worst_reference_relative_gap", std::max(st.worst_reference_gap, tr.worst_reference_gap)},
          {"failures", st.failures + tr.failures},
          {"host", buildinfo::HostInfo()}};
}

}  // namespace rotorguard::benchmarks

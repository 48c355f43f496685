// peer_qp: the NMPC's QP solver beside HPIPM on the same reference instance, in one process, case by
// case, the solvers' turns rotated so that neither always runs first (docs/performance.md).
//
//   peer_qp INSTANCE.json [--repetitions 3] [--cases N]
//
// Every solve is cold: rotorguard's active set from empty, HPIPM's interior point without a warm
// start. HPIPM sees the problem as its users give it: x0 eliminated (stage 0 has no state, its
// dynamics' constant A x0), the same Q, R, bounds. Its settings are frozen here, as published:
//   fast_pc4:  partial condensing to 4 stages of 5 (d_part_cond_qp), SPEED_ABS defaults (mu0 10,
//              at most 15 iterations, the residual test 1e-8);
//   fast:      no condensing, SPEED_ABS defaults;
//   balance:   no condensing, BALANCE, every tolerance 1e-10, at most 100 iterations;
//   robust:    no condensing, ROBUST, every tolerance 1e-10, at most 100 iterations.
// A case's time is the fastest of its repetitions. Each side's timed solve takes the problem's data
// as an NMPC step would hand them over: rotorguard's Prepare and Feedback from its OcpQp, HPIPM's
// d_ocp_qp_set_* of every stage, the condensing and the expansion of its solution. u0's error is
// against the instance's certified optimum; HPIPM's status other than converged is counted apart
// (not_converged). Prints one JSON object.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

extern "C" {
#include <blasfeo.h>
#include <hpipm_d_ocp_qp.h>
#include <hpipm_d_ocp_qp_dim.h>
#include <hpipm_d_ocp_qp_ipm.h>
#include <hpipm_d_ocp_qp_sol.h>
#include <hpipm_d_part_cond.h>
}

#include "rotorguard/benchmarks/qp_bench.h"
#include "rotorguard/buildinfo/build_info.h"
#include "rotorguard/control/ocp_qp.h"
#include "rotorguard/core/statistics.h"

namespace {

using rotorguard::benchmarks::QpInstance;
using rotorguard::benchmarks::QpInstanceCase;
using Clock = std::chrono::steady_clock;

double Micros(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::micro>(b - a).count();
}

/// Memory HPIPM's create functions carve their structures from; freed with the solver.
struct Arena {
  std::vector<std::unique_ptr<char[]>> blocks;
  void* Get(hpipm_size_t size) {
    blocks.emplace_back(new char[size + 64]);
    return blocks.back().get();
  }
};

/// One HPIPM configuration on the instance. The problem is written once; a case changes b_0 = A x0.
class HpipmSolver {
 public:
  HpipmSolver(const rotorguard::control::OcpQp& qp, hpipm_mode mode, int condensed_stages, double tolerance)
      : n_(qp.dims.horizon), nx_(qp.dims.nx), nu_(qp.dims.nu), condensed_(condensed_stages), a0_(qp.A[0]) {
    const int nbx = static_cast<int>(qp.dims.state_bound_index.size());
    std::vector<int> nx(n_ + 1, nx_), nu(n_ + 1, nu_), nbx_v(n_ + 1, nbx), nbu(n_ + 1, nu_), ng(n_ + 1, 0),
        ns(n_ + 1, 0);
    nx[0] = 0;  // x0 eliminated
    nbx_v[0] = 0;
    nu[n_] = 0;
    nbu[n_] = 0;
    d_ocp_qp_dim_create(n_, &dim_, arena_.Get(d_ocp_qp_dim_memsize(n_)));
    d_ocp_qp_dim_set_all(nx.data(), nu.data(), nbx_v.data(), nbu.data(), ng.data(), ns.data(), &dim_);
    d_ocp_qp_create(&dim_, &qp_, arena_.Get(d_ocp_qp_memsize(&dim_)));
    d_ocp_qp_sol_create(&dim_, &sol_, arena_.Get(d_ocp_qp_sol_memsize(&dim_)));

    qp_data_ = &qp;
    idxbx_ = qp.dims.state_bound_index;
    idxbu_.resize(nu_);
    for (int i = 0; i < nu_; ++i) idxbu_[i] = i;
    b0_ = Eigen::VectorXd::Zero(nx_);
    zero_x_ = Eigen::VectorXd::Zero(nx_);
    zero_u_ = Eigen::VectorXd::Zero(nu_);
    Load();

    const bool condense = condensed_ < n_;
    struct d_ocp_qp_dim* ipm_dim = &dim_;
    if (condense) {
      block_size_.assign(condensed_ + 1, 0);
      d_ocp_qp_dim_create(condensed_, &dim2_, arena_.Get(d_ocp_qp_dim_memsize(condensed_)));
      d_part_cond_qp_compute_block_size(n_, condensed_, block_size_.data());
      d_part_cond_qp_compute_dim(&dim_, block_size_.data(), &dim2_);
      d_ocp_qp_create(&dim2_, &qp2_, arena_.Get(d_ocp_qp_memsize(&dim2_)));
      d_ocp_qp_sol_create(&dim2_, &sol2_, arena_.Get(d_ocp_qp_sol_memsize(&dim2_)));
      d_part_cond_qp_arg_create(condensed_, &cond_arg_, arena_.Get(d_part_cond_qp_arg_memsize(condensed_)));
      d_part_cond_qp_arg_set_default(&cond_arg_);
      d_part_cond_qp_ws_create(&dim_, block_size_.data(), &dim2_, &cond_arg_, &cond_ws_,
                               arena_.Get(d_part_cond_qp_ws_memsize(&dim_, block_size_.data(), &dim2_, &cond_arg_)));
      ipm_dim = &dim2_;
    }
    d_ocp_qp_ipm_arg_create(ipm_dim, &arg_, arena_.Get(d_ocp_qp_ipm_arg_memsize(ipm_dim)));
    d_ocp_qp_ipm_arg_set_default(mode, &arg_);
    if (tolerance > 0.0) {
      int iter_max = 100;
      d_ocp_qp_ipm_arg_set_iter_max(&iter_max, &arg_);
      d_ocp_qp_ipm_arg_set_tol_stat(&tolerance, &arg_);
      d_ocp_qp_ipm_arg_set_tol_eq(&tolerance, &arg_);
      d_ocp_qp_ipm_arg_set_tol_ineq(&tolerance, &arg_);
      d_ocp_qp_ipm_arg_set_tol_comp(&tolerance, &arg_);
    }
    int cold = 0;
    d_ocp_qp_ipm_arg_set_warm_start(&cold, &arg_);
    d_ocp_qp_ipm_ws_create(ipm_dim, &arg_, &ws_, arena_.Get(d_ocp_qp_ipm_ws_memsize(ipm_dim, &arg_)));
    u0_.resize(nu_);
  }

  /// Solves from x0, the problem's data set again first; returns HPIPM's status (0: converged) and
  /// leaves u0.
  int Solve(const Eigen::VectorXd& x0) {
    b0_ = a0_ * x0;
    Load();
    int status = 0;
    if (condensed_ < n_) {
      d_part_cond_qp_cond(&qp_, &qp2_, &cond_arg_, &cond_ws_);
      d_ocp_qp_ipm_solve(&qp2_, &sol2_, &arg_, &ws_);
      d_part_cond_qp_expand_sol(&qp_, &sol2_, &sol_, &cond_arg_, &cond_ws_);
    } else {
      d_ocp_qp_ipm_solve(&qp_, &sol_, &arg_, &ws_);
    }
    d_ocp_qp_ipm_get_status(&ws_, &status);
    d_ocp_qp_sol_get_u(0, &sol_, u0_.data());
    d_ocp_qp_ipm_get_iter(&ws_, &iterations_);
    return status;
  }
  const Eigen::VectorXd& u0() const { return u0_; }

  /// Every stage's data into HPIPM's problem (column-major, Eigen's default storage, as HPIPM reads
  /// them; stage 0 has no state: its dynamics' constant is b0_ = A x0).
  void Load() {
    const rotorguard::control::OcpQp& qp = *qp_data_;
    for (int k = 0; k <= n_; ++k) {
      if (k < n_) {
        if (k > 0) d_ocp_qp_set_A(k, const_cast<double*>(qp.A[k].data()), &qp_);
        d_ocp_qp_set_B(k, const_cast<double*>(qp.B[k].data()), &qp_);
        d_ocp_qp_set_b(k, k == 0 ? b0_.data() : zero_x_.data(), &qp_);
        d_ocp_qp_set_R(k, const_cast<double*>(qp.R[k].data()), &qp_);
        d_ocp_qp_set_r(k, zero_u_.data(), &qp_);
        d_ocp_qp_set_idxbu(k, idxbu_.data(), &qp_);
        d_ocp_qp_set_lbu(k, const_cast<double*>(qp.u_lower[k].data()), &qp_);
        d_ocp_qp_set_ubu(k, const_cast<double*>(qp.u_upper[k].data()), &qp_);
      }
      if (k > 0) {
        d_ocp_qp_set_Q(k, const_cast<double*>(qp.Q[k].data()), &qp_);
        d_ocp_qp_set_q(k, zero_x_.data(), &qp_);
        d_ocp_qp_set_idxbx(k, idxbx_.data(), &qp_);
        d_ocp_qp_set_lbx(k, const_cast<double*>(qp.x_lower[k].data()), &qp_);
        d_ocp_qp_set_ubx(k, const_cast<double*>(qp.x_upper[k].data()), &qp_);
      }
    }
  }
  int iterations() const { return iterations_; }

 private:
  int n_, nx_, nu_, condensed_;
  Eigen::MatrixXd a0_;
  const rotorguard::control::OcpQp* qp_data_ = nullptr;
  std::vector<int> idxbx_, idxbu_;
  Eigen::VectorXd b0_, u0_, zero_x_, zero_u_;
  Arena arena_;
  std::vector<int> block_size_;
  struct d_ocp_qp_dim dim_ {}, dim2_{};
  struct d_ocp_qp qp_ {}, qp2_{};
  struct d_ocp_qp_sol sol_ {}, sol2_{};
  struct d_part_cond_qp_arg cond_arg_ {};
  struct d_part_cond_qp_ws cond_ws_ {};
  struct d_ocp_qp_ipm_arg arg_ {};
  struct d_ocp_qp_ipm_ws ws_ {};
  int iterations_ = 0;
};

struct Side {
  std::string name;
  std::string settings;
  std::vector<double> stress_us, track_us, errors;
  int wrong = 0;  // u0 off the certified optimum by more than 1e-4
  int failed = 0;
  double iterations = 0.0;
};

constexpr const char* kUsage = "peer_qp INSTANCE.json [--repetitions R >= 1] [--cases N >= 1]";

int Usage(const char* why) {
  std::fprintf(stderr, "peer_qp: %s\nusage: %s\n", why, kUsage);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return Usage("no instance given");
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") {
      std::printf("usage: %s\n", kUsage);
      return 0;
    }
  }
  std::string path = argv[1];
  int repetitions = 3, max_cases = 1 << 30;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if ((a == "--repetitions" || a == "--cases") && i + 1 < argc) {
      char* end = nullptr;
      const long v = std::strtol(argv[++i], &end, 10);
      if (*end != '\0' || v < 1) return Usage((a + ": expected an integer >= 1, got '" + argv[i] + "'").c_str());
      (a == "--repetitions" ? repetitions : max_cases) = static_cast<int>(v);
    } else {
      return Usage(("unknown argument '" + a + "'").c_str());
    }
  }
  std::optional<QpInstance> loaded;
  try {
    loaded.emplace(rotorguard::benchmarks::LoadQpInstance(path));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "peer_qp: %s\n", e.what());
    return 3;
  }
  QpInstance& instance = *loaded;
  rotorguard::control::OcpQp& qp = instance.qp;
  const int n = qp.dims.horizon;
  rotorguard::control::ActiveSetOptions cold;
  cold.warm_start = false;
  auto riccati = rotorguard::control::MakeOcpQpSolver(rotorguard::control::OcpQpMethod::kRiccati, qp.dims, cold);
  HpipmSolver fast_pc4(qp, SPEED_ABS, 4, 0.0), fast(qp, SPEED_ABS, n, 0.0), balance(qp, BALANCE, n, 1e-10),
      robust(qp, ROBUST, n, 1e-10);

  std::vector<Side> sides = {
      {"rotorguard", "Riccati recursion + dual active set (the default)", {}, {}, {}},
      {"hpipm_fast_pc4", "SPEED_ABS defaults (at most 15 iterations), partial condensing to 4 stages", {}, {}, {}},
      {"hpipm_fast", "SPEED_ABS defaults, no condensing", {}, {}, {}},
      {"hpipm_balance", "BALANCE, tolerances 1e-10, at most 100 iterations, no condensing", {}, {}, {}},
      {"hpipm_robust", "ROBUST, tolerances 1e-10, at most 100 iterations, no condensing", {}, {}, {}}};
  HpipmSolver* hpipm[] = {nullptr, &fast_pc4, &fast, &balance, &robust};
  constexpr int kSides = 5;
  std::vector<double> reps(static_cast<std::size_t>(repetitions));
  int index = 0;
  for (const auto& [group, cases] : {std::pair{0, &instance.stress}, std::pair{1, &instance.track}}) {
    const int count = std::min<int>(static_cast<int>(cases->size()), max_cases);
    for (int c = 0; c < count; ++c, ++index) {
      const QpInstanceCase& ic = (*cases)[c];
      qp.x0 = ic.x0;
      for (int turn = 0; turn < kSides; ++turn) {
        const int s = (turn + index) % kSides;  // each solver first in a fifth of the cases
        Side& side = sides[s];
        int status = 0;
        for (int r = 0; r < repetitions; ++r) {
          const auto t0 = Clock::now();
          if (s == 0) {
            status = riccati->Solve(qp).IsSolutionUsable() ? 0 : 1;
          } else {
            status = hpipm[s]->Solve(ic.x0);
          }
          reps[r] = Micros(t0, Clock::now());
        }
        (group == 0 ? side.stress_us : side.track_us).push_back(*std::min_element(reps.begin(), reps.end()));
        const Eigen::VectorXd u0 = s == 0 ? riccati->u()[0] : hpipm[s]->u0();
        const double error = (u0 - ic.u0).cwiseAbs().maxCoeff();
        side.errors.push_back(std::isfinite(error) ? error : 1e300);
        if (!(error <= 1e-4)) ++side.wrong;
        if (status != 0) ++side.failed;
        side.iterations += s == 0 ? riccati->summary().iterations : hpipm[s]->iterations();
      }
    }
  }
  using rotorguard::Percentile;
  nlohmann::json out = {{"benchmark", "peer_qp"},
                        {"instance", path},
                        {"repetitions", repetitions},
                        {"host", rotorguard::buildinfo::HostInfo()},
                        {"sides", nlohmann::json::array()}};
  for (const Side& s : sides) {
    out["sides"].push_back({{"name", s.name},
                            {"settings", s.settings},
                            {"cases_stress", s.stress_us.size()},
                            {"cases_track", s.track_us.size()},
                            {"stress_us_median", Percentile(s.stress_us, 0.5)},
                            {"stress_us_p99", Percentile(s.stress_us, 0.99)},
                            {"track_us_median", Percentile(s.track_us, 0.5)},
                            {"track_us_p99", Percentile(s.track_us, 0.99)},
                            {"max_u0_error", Percentile(s.errors, 1.0)},
                            {"u0_error_median", Percentile(s.errors, 0.5)},
                            {"cases_u0_error_above_1e-4", s.wrong},
                            {"not_converged", s.failed},
                            {"iterations_mean", s.iterations / static_cast<double>(s.errors.size())}});
  }
  std::printf("%s\n", out.dump(2).c_str());
  return 0;
}

// Cross-check of a reference OCP QP instance (e.g. qp_hover_n20.json): every case where our u0 differs
// from the instance's by more than 1e-4 is solved again by Ipopt (exact Hessian, tol 1e-12), an
// independent interior-point solver, to tell which of the two is right. Usage: qp_instance_ipopt_check FILE
#include <IpIpoptApplication.hpp>
#include <IpTNLP.hpp>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>

#include "rotorguard/control/ocp_qp.h"
using namespace Ipopt;
struct Inst {
  int N, nx, nu;
  Eigen::MatrixXd A, B;
  Eigen::VectorXd Q, R, ul, uu, rl, ru;
  std::vector<int> ri;
};
class QpNlp : public TNLP {
 public:
  QpNlp(const Inst& inst, Eigen::VectorXd initial) : I(inst), x0(std::move(initial)) {}
  const Inst& I;
  Eigen::VectorXd x0, sol;
  double obj = 0;
  int nv() const { return I.N * (I.nu + I.nx); }
  int U(int k) const { return k * I.nu; }
  int X(int k) const { return I.N * I.nu + (k - 1) * I.nx; }  // k = 1..N
  bool get_nlp_info(Index& n, Index& m, Index& nj, Index& nh, IndexStyleEnum& st) override {
    n = nv();
    m = I.N * I.nx;
    nj = I.N * (I.nx + I.nx * I.nu) + (I.N - 1) * I.nx * I.nx;
    nh = n;
    st = C_STYLE;
    return true;
  }
  bool get_bounds_info(Index n, Number* xl, Number* xu, Index m, Number* gl, Number* gu) override {
    for (int i = 0; i < n; ++i) {
      xl[i] = -1e20;
      xu[i] = 1e20;
    }
    for (int k = 0; k < I.N; ++k)
      for (int i = 0; i < I.nu; ++i) {
        xl[U(k) + i] = I.ul[i];
        xu[U(k) + i] = I.uu[i];
      }
    for (int k = 1; k <= I.N; ++k)
      for (size_t b = 0; b < I.ri.size(); ++b) {
        xl[X(k) + I.ri[b]] = I.rl[b];
        xu[X(k) + I.ri[b]] = I.ru[b];
      }
    for (int i = 0; i < m; ++i) gl[i] = gu[i] = 0;
    return true;
  }
  bool get_starting_point(Index n, bool, Number* x, bool, Number*, Number*, Index, bool, Number*) override {
    for (int i = 0; i < n; ++i) x[i] = 0;
    return true;
  }
  bool eval_f(Index, const Number* z, bool, Number& f) override {
    f = 0;
    for (int k = 0; k < I.N; ++k)
      for (int i = 0; i < I.nu; ++i) f += I.R[i] * z[U(k) + i] * z[U(k) + i];
    for (int k = 1; k <= I.N; ++k)
      for (int i = 0; i < I.nx; ++i) f += I.Q[i] * z[X(k) + i] * z[X(k) + i];
    return true;
  }
  bool eval_grad_f(Index, const Number* z, bool, Number* g) override {
    for (int k = 0; k < I.N; ++k)
      for (int i = 0; i < I.nu; ++i) g[U(k) + i] = 2 * I.R[i] * z[U(k) + i];
    for (int k = 1; k <= I.N; ++k)
      for (int i = 0; i < I.nx; ++i) g[X(k) + i] = 2 * I.Q[i] * z[X(k) + i];
    return true;
  }
  bool eval_g(Index, const Number* z, bool, Index, Number* g) override {
    for (int k = 1; k <= I.N; ++k) {
      Eigen::VectorXd prev = k == 1 ? x0 : Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(z + X(k - 1), I.nx));
      Eigen::VectorXd r = Eigen::Map<const Eigen::VectorXd>(z + X(k), I.nx) - I.A * prev -
                          I.B * Eigen::Map<const Eigen::VectorXd>(z + U(k - 1), I.nu);
      for (int i = 0; i < I.nx; ++i) g[(k - 1) * I.nx + i] = r[i];
    }
    return true;
  }
  bool eval_jac_g(Index, const Number*, bool, Index, Index, Index* r, Index* c, Number* v) override {
    int e = 0;
    for (int k = 1; k <= I.N; ++k)
      for (int i = 0; i < I.nx; ++i) {
        int row = (k - 1) * I.nx + i;
        if (v)
          v[e] = 1.0;
        else {
          r[e] = row;
          c[e] = X(k) + i;
        }
        ++e;
        for (int j = 0; j < I.nu; ++j) {
          if (v)
            v[e] = -I.B(i, j);
          else {
            r[e] = row;
            c[e] = U(k - 1) + j;
          }
          ++e;
        }
        if (k >= 2)
          for (int j = 0; j < I.nx; ++j) {
            if (v)
              v[e] = -I.A(i, j);
            else {
              r[e] = row;
              c[e] = X(k - 1) + j;
            }
            ++e;
          }
      }
    return true;
  }
  bool eval_h(Index n, const Number*, bool, Number of, Index, const Number*, bool, Index, Index* r, Index* c,
              Number* v) override {
    for (int i = 0; i < n; ++i) {
      if (v) {
        double w = i < I.N * I.nu ? I.R[i % I.nu] : I.Q[(i - I.N * I.nu) % I.nx];
        v[i] = 2 * of * w;
      } else {
        r[i] = i;
        c[i] = i;
      }
    }
    return true;
  }
  void finalize_solution(SolverReturn, Index n, const Number* z, const Number*, const Number*, Index, const Number*,
                         const Number*, Number o, const IpoptData*, IpoptCalculatedQuantities*) override {
    sol = Eigen::Map<const Eigen::VectorXd>(z, n);
    obj = o;
  }
};
int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: qp_instance_ipopt_check INSTANCE.json\n";
    return 2;
  }
  std::ifstream in(argv[1]);
  if (!in) {
    std::cerr << argv[1] << ": cannot read input file\n";
    return 3;
  }
  nlohmann::json d;
  in >> d;
  Inst I;
  I.N = d["N"];
  I.nx = d["nx"];
  I.nu = d["nu"];
  I.A.resize(I.nx, I.nx);
  I.B.resize(I.nx, I.nu);
  for (int i = 0; i < I.nx; ++i) {
    for (int j = 0; j < I.nx; ++j) I.A(i, j) = d["A"][i][j];
    for (int j = 0; j < I.nu; ++j) I.B(i, j) = d["B"][i][j];
  }
  auto vec = [&](const char* k) {
    Eigen::VectorXd v(d[k].size());
    for (size_t i = 0; i < d[k].size(); ++i) v[i] = d[k][i];
    return v;
  };
  I.Q = vec("Q_diag");
  I.R = vec("R_diag");
  I.ul = vec("u_lower");
  I.uu = vec("u_upper");
  I.rl = vec("rate_lower");
  I.ru = vec("rate_upper");
  I.ri = d["rate_index"].get<std::vector<int>>();
  rotorguard::control::OcpQpDims dims{I.N, I.nx, I.nu, I.ri};
  rotorguard::control::OcpQp qp(dims);
  for (int k = 0; k < I.N; ++k) {
    qp.A[k] = I.A;
    qp.B[k] = I.B;
    qp.R[k] = 2 * I.R.asDiagonal().toDenseMatrix();
    qp.u_lower[k] = I.ul;
    qp.u_upper[k] = I.uu;
  }
  for (int k = 0; k <= I.N; ++k) {
    qp.Q[k] = 2 * I.Q.asDiagonal().toDenseMatrix();
    qp.x_lower[k] = I.rl;
    qp.x_upper[k] = I.ru;
  }
  rotorguard::control::CondensingQpSolver s(dims);
  int checked = 0, ipopt_agrees_ours = 0, ipopt_agrees_ref = 0;
  double worst_ours = 0, worst_ref_min = 1e9;
  for (const char* g : {"stress", "track"})
    for (auto& c : d[g]) {
      Eigen::VectorXd x0(I.nx), u0(I.nu);
      for (int i = 0; i < I.nx; ++i) x0[i] = c["x0"][i];
      for (int i = 0; i < I.nu; ++i) u0[i] = c["u0"][i];
      qp.x0 = x0;
      s.Solve(qp);
      double e = (s.u()[0] - u0).cwiseAbs().maxCoeff();
      if (e < 1e-4) continue;
      SmartPtr<QpNlp> nlp = new QpNlp(I, x0);
      SmartPtr<IpoptApplication> app = IpoptApplicationFactory();
      app->Options()->SetNumericValue("tol", 1e-12);
      app->Options()->SetIntegerValue("print_level", 0);
      app->Options()->SetStringValue("sb", "yes");
      app->Options()->SetStringValue("mehrotra_algorithm", "yes");
      app->Initialize();
      app->OptimizeTNLP(nlp);
      Eigen::VectorXd ui = nlp->sol.segment(0, I.nu);
      double d_ours = (ui - s.u()[0]).cwiseAbs().maxCoeff(), d_ref = (ui - u0).cwiseAbs().maxCoeff();
      ++checked;
      if (d_ours < 1e-4) ++ipopt_agrees_ours;
      if (d_ref < 1e-4) ++ipopt_agrees_ref;
      worst_ours = std::max(worst_ours, d_ours);
      worst_ref_min = std::min(worst_ref_min, d_ref);
    }
  std::cout << "cases with |u0 - ref| > 1e-4: " << checked
            << "; Ipopt (tol 1e-12) within 1e-4 of ours: " << ipopt_agrees_ours << " (worst " << worst_ours
            << "), of the reference: " << ipopt_agrees_ref << " (closest " << worst_ref_min << ")\n";
}

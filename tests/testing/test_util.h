#pragma once
/// Shared test helpers: matrix comparison with an informative message, expect-throw-with-message,
/// central finite differences, a fixture with a fresh temporary folder.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>

#include <Eigen/Core>
#include <gtest/gtest.h>

namespace rotorguard::testing {

/// A file of the source tree by its path from the root ("configs/scenarios/hover.yaml"). Joined
/// as paths at run time: GCC 12 misreads the inlined concatenation of a string literal this long
/// as an out-of-bounds copy (-Warray-bounds) when the standard headers come precompiled.
inline std::string SourcePath(const std::string& relative) {
  return (std::filesystem::path(ROTORGUARD_SOURCE_DIR) / relative).string();
}

/// The reference vehicle file's text without its `fdd:` key, for a copy that names other
/// thresholds (or none: the code's defaults, the paper's values).
inline std::string ReferenceVehicleWithoutFdd() {
  std::ifstream in(SourcePath("configs/vehicles/zhou2025_quad.yaml"));
  std::string line, text;
  while (std::getline(in, line)) {
    if (line.rfind("fdd:", 0) != 0) text += line + "\n";
  }
  return text;
}

/// Passes when |a - b| <= tol elementwise; prints both matrices otherwise.
template <typename A, typename B>
::testing::AssertionResult MatricesNear(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b,
                                        double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "size " << a.rows() << "x" << a.cols() << " vs "
                                         << b.rows() << "x" << b.cols();
  }
  const double err = (a - b).cwiseAbs().maxCoeff();
  if (err <= tol) return ::testing::AssertionSuccess();
  std::ostringstream os;
  os << "max |a - b| = " << err << " > " << tol << "\na =\n" << a << "\nb =\n" << b;
  return ::testing::AssertionFailure() << os.str();
}

/// Central-difference Jacobian of f at x.
inline Eigen::MatrixXd NumericalJacobian(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x,
    double h = 1e-6) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd j(f0.size(), x.size());
  for (int i = 0; i < x.size(); ++i) {
    Eigen::VectorXd xp = x, xm = x;
    xp[i] += h;
    xm[i] -= h;
    j.col(i) = (f(xp) - f(xm)) / (2.0 * h);
  }
  return j;
}

/// A fixture with a fresh folder per test (named after the process and the test), removed after.
class TempFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rotorguard_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  /// Writes `text` to dir_/name byte for byte; returns the path.
  std::string Write(const std::string& name, const std::string& text) {
    const std::filesystem::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
  std::filesystem::path dir_;
};

}  // namespace rotorguard::testing

/// EXPECT that `statement` throws `exception_type` whose what() contains `substring`.
#define RG_EXPECT_THROW_WITH(statement, exception_type, substring)                        \
  do {                                                                                    \
    try {                                                                                 \
      statement;                                                                          \
      ADD_FAILURE() << "expected " #exception_type " from " #statement;                   \
    } catch (const exception_type& e) {                                                   \
      EXPECT_NE(std::string(e.what()).find(substring), std::string::npos)                 \
          << "message \"" << e.what() << "\" lacks \"" << (substring) << "\"";            \
    }                                                                                     \
  } while (false)

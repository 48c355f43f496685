#include "rotorguard/benchmarks/qp_bench.h"

#include <gtest/gtest.h>

#include <string>

#include "rotorguard/io/config_node.h"
#include "test_util.h"

namespace rotorguard::benchmarks {
namespace {

using QpInstanceTest = testing::TempFolderTest;

// A hand-made instance of two stages: 2 states, 1 input, the second state bounded. Its cost,
// x'Qx + u'Ru, has no factor 1/2; OcpQp's has (1/2 x'Qx), so the loader must double Q and R.
constexpr const char* kInstance = R"({
  "N": 2, "nx": 2, "nu": 1,
  "A": [[1.0, 0.1], [0.0, 1.0]], "B": [[0.005], [0.1]],
  "Q_diag": [3.0, 0.5], "R_diag": [0.25],
  "u_lower": [-2.0], "u_upper": [1.5],
  "rate_index": [1], "rate_lower": [-0.7], "rate_upper": [0.8],
  "stress": [{"x0": [1.0, -0.5], "u0": [-2.0]}],
  "track": [{"x0": [0.1, 0.0], "u0": [-0.3]}, {"x0": [0.0, 0.2], "u0": [0.1]}]
})";

TEST_F(QpInstanceTest, ReadsEveryStageWithTheFactorOneHalfOfTheSolversCost) {
  const QpInstance in = LoadQpInstance(Write("instance.json", kInstance));
  const control::OcpQp& qp = in.qp;
  ASSERT_EQ(qp.dims.horizon, 2);
  ASSERT_EQ(qp.dims.nx, 2);
  ASSERT_EQ(qp.dims.nu, 1);
  ASSERT_EQ(qp.dims.state_bound_index, std::vector<int>{1});
  for (int k = 0; k < 2; ++k) {
    EXPECT_DOUBLE_EQ(qp.A[k](0, 1), 0.1);
    EXPECT_DOUBLE_EQ(qp.B[k](0, 0), 0.005);
    EXPECT_DOUBLE_EQ(qp.R[k](0, 0), 0.5) << "R doubled";
    EXPECT_DOUBLE_EQ(qp.u_lower[k][0], -2.0);
    EXPECT_DOUBLE_EQ(qp.u_upper[k][0], 1.5);
  }
  for (int k = 0; k <= 2; ++k) {
    EXPECT_DOUBLE_EQ(qp.Q[k](0, 0), 6.0) << "Q doubled";
    EXPECT_DOUBLE_EQ(qp.Q[k](1, 1), 1.0);
    EXPECT_DOUBLE_EQ(qp.Q[k](0, 1), 0.0);
    EXPECT_DOUBLE_EQ(qp.x_lower[k][0], -0.7);
    EXPECT_DOUBLE_EQ(qp.x_upper[k][0], 0.8);
  }
  ASSERT_EQ(in.stress.size(), 1u);
  ASSERT_EQ(in.track.size(), 2u);
  EXPECT_DOUBLE_EQ(in.stress[0].x0[1], -0.5);
  EXPECT_DOUBLE_EQ(in.track[1].u0[0], 0.1);
}

TEST_F(QpInstanceTest, AMissingOrMalformedFieldIsNamed) {
  std::string text = kInstance;
  text.replace(text.find("\"R_diag\""), 8, "\"R_dig\"");
  RG_EXPECT_THROW_WITH(LoadQpInstance(Write("no_r.json", text)), io::InputFileError, "R_diag");
  std::string short_b = kInstance;
  short_b.replace(short_b.find("[[0.005], [0.1]]"), 16, "[[0.005]]");
  RG_EXPECT_THROW_WITH(LoadQpInstance(Write("short_b.json", short_b)), io::InputFileError, "'B' must have 2 rows");
  RG_EXPECT_THROW_WITH(LoadQpInstance((dir_ / "none.json").string()), io::InputFileError, "none.json");
}

}  // namespace
}  // namespace rotorguard::benchmarks

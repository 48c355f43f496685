#include "rotorguard/planning/banded.h"

#include <algorithm>
#include <cmath>

namespace rotorguard::planning {

BandedMatrix::BandedMatrix(int n, int lower, int upper)
    : n_(n), lower_(lower), upper_(upper), width_(lower + upper + 1),
      data_(static_cast<std::size_t>(n) * static_cast<std::size_t>(lower + upper + 1), 0.0) {}

void BandedMatrix::Reset(int n, int lower, int upper) {
  n_ = n;
  lower_ = lower;
  upper_ = upper;
  width_ = lower + upper + 1;
  data_.assign(static_cast<std::size_t>(n) * static_cast<std::size_t>(width_), 0.0);
}

bool BandedMatrix::Factorize() {
  // Doolittle elimination restricted to the band: without row exchanges L keeps the lower and U
  // the upper bandwidth, and L's multipliers overwrite the eliminated entries.
  for (int k = 0; k < n_; ++k) {
    const double pivot = (*this)(k, k);
    if (pivot == 0.0 || !std::isfinite(pivot)) return false;
    const int last_row = std::min(n_ - 1, k + lower_), last_col = std::min(n_ - 1, k + upper_);
    for (int i = k + 1; i <= last_row; ++i) {
      double& l = (*this)(i, k);
      if (l == 0.0) continue;
      l /= pivot;
      for (int j = k + 1; j <= last_col; ++j) (*this)(i, j) -= l * (*this)(k, j);
    }
  }
  return true;
}

void BandedMatrix::Solve(Eigen::Ref<Eigen::MatrixXd> b) const {
  for (int i = 0; i < n_; ++i) {  // L y = b (unit diagonal)
    for (int k = std::max(0, i - lower_); k < i; ++k) b.row(i) -= (*this)(i, k) * b.row(k);
  }
  for (int i = n_ - 1; i >= 0; --i) {  // U x = y
    for (int j = i + 1; j <= std::min(n_ - 1, i + upper_); ++j) b.row(i) -= (*this)(i, j) * b.row(j);
    b.row(i) /= (*this)(i, i);
  }
}

void BandedMatrix::SolveTransposed(Eigen::Ref<Eigen::MatrixXd> b) const {
  // A^T = U^T L^T: U^T y = b forward, then L^T x = y backward.
  for (int j = 0; j < n_; ++j) {
    b.row(j) /= (*this)(j, j);
    for (int i = j + 1; i <= std::min(n_ - 1, j + upper_); ++i) b.row(i) -= (*this)(j, i) * b.row(j);
  }
  for (int j = n_ - 1; j >= 0; --j) {
    for (int i = std::max(0, j - lower_); i < j; ++i) b.row(i) -= (*this)(j, i) * b.row(j);
  }
}

Eigen::MatrixXd BandedMatrix::ToDense() const {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n_, n_);
  for (int i = 0; i < n_; ++i) {
    for (int j = std::max(0, i - lower_); j <= std::min(n_ - 1, i + upper_); ++j) a(i, j) = (*this)(i, j);
  }
  return a;
}

}  // namespace rotorguard::planning

#pragma once
/// A square banded matrix and its LU factorisation without pivoting, O(n l (l + u)) to factor and
/// O(n (l + u)) per solve: the linear-complexity solve of MINCO's map c = M(q, T) (Wang et al.,
/// "Geometrically constrained trajectory optimization for multicopters", T-RO 2022, Sec. IV),
/// whose system needs no pivoting when its rows are ordered as `MinimumJerkTrajectory` orders them
/// (tested against a dense pivoting solve over durations from 0.02 to 50 s).
#include <vector>

#include <Eigen/Dense>

namespace rotorguard::planning {

class BandedMatrix {
 public:
  /// An n x n zero matrix with `lower` sub- and `upper` super-diagonals.
  BandedMatrix(int n, int lower, int upper);
  /// The same, in this matrix's storage (no allocation when it held as many entries before).
  void Reset(int n, int lower, int upper);

  int size() const { return n_; }
  /// Element (i, j); |i - j| must lie within the band.
  double& operator()(int i, int j) { return data_[Index(i, j)]; }
  double operator()(int i, int j) const { return data_[Index(i, j)]; }

  /// Factors in place (L unit lower, U upper). Returns false on a zero or non-finite pivot; the
  /// matrix is then unusable.
  bool Factorize();
  /// Solves A X = B in place (after Factorize).
  void Solve(Eigen::Ref<Eigen::MatrixXd> b) const;
  /// Solves A^T X = B in place (after Factorize): the adjoint of the map, for gradients.
  void SolveTransposed(Eigen::Ref<Eigen::MatrixXd> b) const;

  /// The dense matrix (for tests).
  Eigen::MatrixXd ToDense() const;

 private:
  int Index(int i, int j) const { return i * width_ + (j - i + lower_); }
  int n_, lower_, upper_, width_;
  std::vector<double> data_;  // row-major, each row's band from column i - lower to i + upper
};

}  // namespace rotorguard::planning

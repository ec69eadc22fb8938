// Covariance of theta in the batch problem by a Schur complement on theta.
//
// The normal matrix H = J^T J of the batch problem is block-tridiagonal in the
// trajectory states x_e (each process residual couples x_e and x_{e+1}) with a
// dense border for theta:
//
//   H = [ H_xx  H_xt ]        cov(theta) = (H_tt - H_tx H_xx^-1 H_xt)^-1
//       [ H_tx  H_tt ]
//
// Eliminating x_0, x_1, ... in turn (block forward elimination, an information
// filter in disguise) costs O(E (6^3 + 6^2 n + 6 n^2)) instead of a sparse QR of
// the whole Jacobian. Exact for the same Jacobian; a test compares it with
// Ceres's Covariance.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace triadcal {

// Whitened Jacobian blocks of one residual kind.
struct ProcessBlock {      // residual couples x_e, x_{e+1} and theta
  Eigen::Matrix<double, 6, 6> A, B;  // d r / d x_e, d r / d x_{e+1}
  Eigen::MatrixXd C;                 // d r / d theta (6 x n)
};
struct MeasurementBlock {  // residual couples x_e and theta
  Eigen::Matrix<double, 6, 6> M;
  Eigen::MatrixXd N;                 // 6 x n
};

// process[e] links epoch e and e+1 (E - 1 of them); measurement[e] is at epoch
// e (E of them); theta_rows are the rows on theta alone (priors, constraints).
Eigen::MatrixXd ThetaCovarianceBySchur(const std::vector<ProcessBlock>& process,
                                       const std::vector<MeasurementBlock>& measurement,
                                       const Eigen::MatrixXd& theta_rows);

// The information of theta with the states eliminated, H_tt - H_tx H_xx^-1 H_xt
// (its inverse is the covariance above; effect_discovery's score tests and
// reliability analysis use the information itself).
Eigen::MatrixXd ThetaInformationBySchur(const std::vector<ProcessBlock>& process,
                                        const std::vector<MeasurementBlock>& measurement,
                                        const Eigen::MatrixXd& theta_rows);

}  // namespace triadcal

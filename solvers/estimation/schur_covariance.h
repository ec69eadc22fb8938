// The information of theta in the batch problem by a Schur complement on theta.
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
// the dense normal equations (schur_covariance_test.cpp).
#pragma once

#include <vector>

#include <Eigen/Core>

namespace triadcal {

// Whitened Jacobian blocks of one residual kind.
struct ProcessBlock {      // residual couples x_e, x_{e+1} and theta
  Eigen::Matrix<double, 6, 6> A, B;  // d r / d x_e, d r / d x_{e+1}
  Eigen::MatrixXd C;                 // d r / d theta (6 x n)
  // The residual at x = 0 (ReduceOverStates only): r = r0 + A x_e + B x_{e+1}.
  Eigen::Matrix<double, 6, 1> r0 = Eigen::Matrix<double, 6, 1>::Zero();
};
struct MeasurementBlock {  // residual couples x_e and theta
  Eigen::Matrix<double, 6, 6> M;
  Eigen::MatrixXd N;                 // 6 x n
  Eigen::Matrix<double, 6, 1> r0 = Eigen::Matrix<double, 6, 1>::Zero();  // r = r0 + M x_e
};

// The information of theta with the states eliminated, H_tt - H_tx H_xx^-1 H_xt
// (its inverse is the covariance above). process[e] links epoch e and e+1
// (E - 1 of them); measurement[e] is at epoch e (E of them); theta_rows are
// the rows on theta alone (priors, constraints). *scale, when given, gets
// the diagonal before the elimination (H_tt's): what the elimination
// subtracts from, so that a parameter's information resolves to about
// 1e-16 of it (InformationResolution, batch_solver.h). With threads > 1 the
// data's sum and the eliminated one are formed at once.
// probe, when given: k more columns P on the process rows alone (zero on the
// measurements), eliminated with theta's without entering its information:
// probe->cross = J_theta^T (I - P_x) P (n x k) and probe->self =
// P^T (I - P_x) P (k x k), P_x the projection on the states' columns.
struct SchurProbe {
  std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>> columns;  // per process block
  Eigen::MatrixXd cross, self;
};
Eigen::MatrixXd ThetaInformationBySchur(const std::vector<ProcessBlock>& process,
                                        const std::vector<MeasurementBlock>& measurement,
                                        const Eigen::MatrixXd& theta_rows,
                                        Eigen::VectorXd* scale = nullptr, int threads = 1,
                                        SchurProbe* probe = nullptr);

// The problem at one theta with the states solved for (variable projection).
// The residuals are affine in the states for a given theta (r = r0 + J_x x),
// so min over x of 0.5 |r|^2 is one linear solve; at that minimum the
// gradient of the reduced cost by theta is J_theta^T r (J_x^T r = 0 there)
// and its Gauss-Newton Hessian is the information above. The same block
// forward elimination carries the right-hand side:
//
//   cost      = 0.5 |r0|^2 - 0.5 b_x^T H_xx^-1 b_x,       b = J^T r0
//   gradient  = b_t - H_tx H_xx^-1 b_x
//   x_optimal = -H_xx^-1 b_x            (when asked: back substitution)
struct ReducedOverStates {
  double cost = 0.0;             // 0.5 |r|^2 at the optimal states
  Eigen::VectorXd gradient;      // d cost / d theta at the optimal states (n)
  Eigen::MatrixXd information;   // H_tt - H_tx H_xx^-1 H_xt (n x n)
  std::vector<Eigen::Matrix<double, 6, 1>> states;  // optimal x_e, when asked
};
ReducedOverStates ReduceOverStates(const std::vector<ProcessBlock>& process,
                                   const std::vector<MeasurementBlock>& measurement,
                                   bool with_states = false);

// The reduced gradient split by epoch (the prediction-error decomposition of
// a state-space model's likelihood). T_e is the problem truncated after epoch e
// (measurements 0..e, intervals 0..e-1) and F_e the gradient by theta of its
// cost with its states solved for; score e is F_e - F_{e-1} (F_{-1} = 0), the
// gradient of what epoch e adds to the cost given the epochs before it. The
// blocks' r0 are the residuals at the point (states and theta) where the
// scores are wanted, e.g. the solution. Under the model, at the true theta,
// the scores are martingale differences: uncorrelated between epochs, each of
// covariance the information epoch e adds, so the sum of their outer
// products estimates the information of theta from the data, and correlation
// between epochs shows residuals correlated in time (hac_covariance.h). The
// scores sum to ReduceOverStates's gradient. Cost O(E (6^3 + 6^2 n)).
std::vector<Eigen::VectorXd> EpochScores(const std::vector<ProcessBlock>& process,
                                         const std::vector<MeasurementBlock>& measurement);

}  // namespace triadcal

// The residual blocks of the batch problem (batch_solver.h) as Ceres cost
// functions with analytic Jacobians. theta is one parameter block of size n;
// each epoch's state x = (V, S) is a block of 6.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>

#include "solvers/estimation/run_problem.h"

namespace triadcal {

using Mat6 = Eigen::Matrix<double, 6, 6>;
using Vec6 = Eigen::Matrix<double, 6, 1>;

// Whitening L with L^T L = cov^-1 (L = chol(cov)^-1, lower-triangular inverse).
Mat6 WhiteningOf(const Mat6& cov);

// Process residual of the interval a -> b, first order in theta about theta_lin:
//   r = L [ V_b - V_a - dv - Jv (theta - theta_lin) ;
//           S_b - S_a - V_a T - ds - Js (theta - theta_lin) ]
// In exact mode dv, ds, Jv, Js are recomputed at theta in every evaluation.
class ProcessCost : public ceres::CostFunction {
 public:
  ProcessCost(const IntervalIncrement* inc, const Eigen::VectorXd* theta_lin, const Mat6& L,
              const RunProblem* exact_problem, std::size_t k0, std::size_t k1);
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override;

  // Raw (unwhitened) residual at the given states.
  Vec6 Raw(const double* xa, const double* xb, const double* theta) const;

 private:
  const IntervalIncrement* inc_;
  const Eigen::VectorXd* theta_lin_;
  Mat6 L_;
  const RunProblem* exact_;  // non-null: exact mode
  std::size_t k0_, k1_;
  int n_;
};

// Measurement residual at an epoch (block B2):
//   r = L [ V - V_DU(theta) ; S - S_DU(theta) ]
class MeasurementCost : public ceres::CostFunction {
 public:
  MeasurementCost(const RunProblem* problem, std::size_t k, const Mat6& L);
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override;
  Vec6 Raw(const double* x, const double* theta) const;

 private:
  const RunProblem* problem_;
  std::size_t k_;
  Mat6 L_;
  int n_;
};

// Linear rows over theta: r = A theta - b (priors and constraints, whitened).
class LinearThetaCost : public ceres::CostFunction {
 public:
  LinearThetaCost(Eigen::MatrixXd A, Eigen::VectorXd b);
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override;

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd b_;
};

}  // namespace triadcal

// The residual blocks of the batch problem (batch_solver.h) as Ceres cost
// functions with analytic Jacobians: thin wrappers over the state-space model
// (state_space_model.h), whitened by L (L^T L = covariance^-1). theta_free is
// one parameter block of the free parameters; each epoch's state x = (V, S) is
// a block of 6.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>

#include "solvers/estimation/state_space_model.h"

namespace triadcal {

// Process residual of the interval e -> e+1, r = L(theta) r_p
// (state_space_model.h), r_p first order about the step's theta_lin, L the
// whitening at the current theta (StateSpaceModel::ProcessWhitening) with its
// derivative by the scale factors. In exact mode the step is recomputed at
// theta in every evaluation.
class ProcessCost : public ceres::CostFunction {
 public:
  ProcessCost(const ProcessStep* step, const Eigen::VectorXd* theta_lin_free,
              const StateSpaceModel* model, bool exact, std::size_t e);
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override;

  // Raw (unwhitened) residual at the given states.
  Vec6 Raw(const double* xa, const double* xb, const double* theta_free) const;

 private:
  const ProcessStep* step_;
  const Eigen::VectorXd* theta_lin_;
  const StateSpaceModel* model_;
  bool exact_;
  std::size_t e_;
  int n_;
};

// Measurement residual at epoch e, r = L r_m = L (x - h_e(theta)).
class MeasurementCost : public ceres::CostFunction {
 public:
  MeasurementCost(const StateSpaceModel* model, std::size_t e, const Mat6& L);
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override;
  Vec6 Raw(const double* x, const double* theta_free) const;

 private:
  const StateSpaceModel* model_;
  std::size_t e_;
  Mat6 L_;
  int n_;
};

// Linear rows over theta_free: r = A theta_free - b (priors and constraints,
// whitened; StateSpaceModel::ThetaRows).
class LinearThetaCost : public ceres::CostFunction {
 public:
  LinearThetaCost(Eigen::MatrixXd A, Eigen::VectorXd b);
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override;

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd b_;
};

}  // namespace triadcal

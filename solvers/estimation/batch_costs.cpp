#include "solvers/estimation/batch_costs.h"

namespace triadcal {

using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

namespace {
// Ceres wants Jacobians row-major: write an Eigen expression into one.
template <typename M>
void Store(const M& m, double* out) {
  Eigen::Map<RowMat> dst(out, m.rows(), m.cols());
  dst = m;
}
}  // namespace

ProcessCost::ProcessCost(const ProcessStep* step, const Eigen::VectorXd* theta_lin_free,
                         const StateSpaceModel* model, bool exact, std::size_t e)
    : step_(step), theta_lin_(theta_lin_free), model_(model), exact_(exact), e_(e) {
  n_ = static_cast<int>(theta_lin_free->size());
  set_num_residuals(6);
  mutable_parameter_block_sizes()->push_back(6);
  mutable_parameter_block_sizes()->push_back(6);
  mutable_parameter_block_sizes()->push_back(n_);
}

Vec6 ProcessCost::Raw(const double* xa, const double* xb, const double* theta_free) const {
  Eigen::Map<const Vec6> a(xa), b(xb);
  Eigen::Map<const Eigen::VectorXd> th(theta_free, n_);
  if (exact_) {
    const ProcessStep s = model_->Process(e_, model_->Expand(th), false);
    return StateSpaceModel::ProcessResidual(s, a, b, Eigen::VectorXd());
  }
  return StateSpaceModel::ProcessResidual(*step_, a, b, th - *theta_lin_);
}

bool ProcessCost::Evaluate(double const* const* p, double* residuals, double** jacobians) const {
  Eigen::Map<const Vec6> a(p[0]), b(p[1]);
  Eigen::Map<const Eigen::VectorXd> th(p[2], n_);
  const bool want_theta = jacobians && jacobians[2];
  const Eigen::VectorXd theta = model_->Expand(th);
  ProcessStep exact_step;
  const ProcessStep* s = step_;
  Eigen::VectorXd d = th - *theta_lin_;
  if (exact_) {
    exact_step = model_->Process(e_, theta, want_theta);
    s = &exact_step;
    d.setZero();
  }
  std::vector<Mat6> dL;
  // The noise model's make-up (channel directions) stays at theta_lin; its
  // variances follow theta's scale factors.
  const Mat6 L = model_->ProcessWhitening(*step_, theta, want_theta ? &dL : nullptr);
  if (!L.allFinite()) return false;  // a scale factor at 0: Ceres steps back
  const Vec6 r = StateSpaceModel::ProcessResidual(*s, a, b, d);
  Eigen::Map<Vec6> res(residuals);
  res = L * r;
  if (!jacobians) return true;
  if (jacobians[0]) Store(L * StateSpaceModel::ProcessJacobianXa(*s), jacobians[0]);
  if (jacobians[1]) Store(L, jacobians[1]);
  if (want_theta) {
    Eigen::MatrixXd J = -L * StateSpaceModel::PredictThetaJacobian(*s, d);
    for (int j = 0; j < n_; ++j) {
      J.col(j) += dL[j] * r;  // zero unless theta_j is a scale factor
    }
    Store(J, jacobians[2]);
  }
  return true;
}

MeasurementCost::MeasurementCost(const StateSpaceModel* model, std::size_t e, const Mat6& L)
    : model_(model), e_(e), L_(L), n_(model->num_free()) {
  set_num_residuals(6);
  mutable_parameter_block_sizes()->push_back(6);
  mutable_parameter_block_sizes()->push_back(n_);
}

Vec6 MeasurementCost::Raw(const double* x, const double* theta_free) const {
  Eigen::Map<const Vec6> s(x);
  Eigen::Map<const Eigen::VectorXd> th(theta_free, n_);
  const MeasurementStep m = model_->Measurement(e_, model_->Expand(th), false, false);
  return StateSpaceModel::MeasurementResidual(m, s);
}

bool MeasurementCost::Evaluate(double const* const* p, double* residuals,
                               double** jacobians) const {
  Eigen::Map<const Vec6> s(p[0]);
  Eigen::Map<const Eigen::VectorXd> th(p[1], n_);
  const bool want_theta = jacobians && jacobians[1];
  const MeasurementStep m = model_->Measurement(e_, model_->Expand(th), want_theta, false);
  Eigen::Map<Vec6> out(residuals);
  out = L_ * StateSpaceModel::MeasurementResidual(m, s);
  if (!jacobians) return true;
  if (jacobians[0]) Store(L_, jacobians[0]);
  if (want_theta) Store(-L_ * m.H, jacobians[1]);
  return true;
}

LinearThetaCost::LinearThetaCost(Eigen::MatrixXd A, Eigen::VectorXd b)
    : A_(std::move(A)), b_(std::move(b)) {
  set_num_residuals(static_cast<int>(A_.rows()));
  mutable_parameter_block_sizes()->push_back(static_cast<int>(A_.cols()));
}

bool LinearThetaCost::Evaluate(double const* const* p, double* residuals,
                               double** jacobians) const {
  Eigen::Map<const Eigen::VectorXd> th(p[0], A_.cols());
  Eigen::Map<Eigen::VectorXd> out(residuals, A_.rows());
  out = A_ * th - b_;
  if (jacobians && jacobians[0]) Store(A_, jacobians[0]);
  return true;
}

}  // namespace triadcal

#include "solvers/estimation/batch_costs.h"

#include <Eigen/Cholesky>

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

Mat6 WhiteningOf(const Mat6& cov) {
  const Eigen::LLT<Mat6> llt(cov);
  const Mat6 Lc = llt.matrixL();
  return Lc.triangularView<Eigen::Lower>().solve(Mat6::Identity());
}

ProcessCost::ProcessCost(const IntervalIncrement* inc, const Eigen::VectorXd* theta_lin,
                         const Mat6& L, const RunProblem* exact_problem, std::size_t k0,
                         std::size_t k1)
    : inc_(inc), theta_lin_(theta_lin), L_(L), exact_(exact_problem), k0_(k0), k1_(k1) {
  n_ = static_cast<int>(theta_lin->size());
  set_num_residuals(6);
  mutable_parameter_block_sizes()->push_back(6);
  mutable_parameter_block_sizes()->push_back(6);
  mutable_parameter_block_sizes()->push_back(n_);
}

Vec6 ProcessCost::Raw(const double* xa, const double* xb, const double* theta) const {
  Eigen::Map<const Vec6> a(xa), b(xb);
  Eigen::Map<const Eigen::VectorXd> th(theta, n_);
  Vec6 r;
  if (exact_) {
    const IntervalIncrement e = IntegrateInterval(exact_->cfg, th, exact_->series, k0_, k1_, false);
    r.head<3>() = b.head<3>() - a.head<3>() - e.dv_mps;
    r.tail<3>() = b.tail<3>() - a.tail<3>() - a.head<3>() * e.T_s - e.ds_m;
    return r;
  }
  const Eigen::VectorXd d = th - *theta_lin_;
  r.head<3>() = b.head<3>() - a.head<3>() - inc_->dv_mps - inc_->ddv_dtheta * d;
  r.tail<3>() = b.tail<3>() - a.tail<3>() - a.head<3>() * inc_->T_s - inc_->ds_m -
                inc_->dds_dtheta * d;
  return r;
}

bool ProcessCost::Evaluate(double const* const* p, double* residuals, double** jacobians) const {
  Eigen::Map<Vec6> res(residuals);
  res = L_ * Raw(p[0], p[1], p[2]);
  if (!jacobians) return true;
  if (jacobians[0]) {
    Mat6 D = -Mat6::Identity();
    D.block<3, 3>(3, 0) = -inc_->T_s * Eigen::Matrix3d::Identity();
    Store(L_ * D, jacobians[0]);
  }
  if (jacobians[1]) Store(L_, jacobians[1]);
  if (jacobians[2]) {
    Eigen::MatrixXd J(6, n_);
    if (exact_) {
      Eigen::Map<const Eigen::VectorXd> th(p[2], n_);
      const IntervalIncrement e = IntegrateInterval(exact_->cfg, th, exact_->series, k0_, k1_, true);
      J.topRows(3) = -e.ddv_dtheta;
      J.bottomRows(3) = -e.dds_dtheta;
    } else {
      J.topRows(3) = -inc_->ddv_dtheta;
      J.bottomRows(3) = -inc_->dds_dtheta;
    }
    Store(L_ * J, jacobians[2]);
  }
  return true;
}

MeasurementCost::MeasurementCost(const RunProblem* problem, std::size_t k, const Mat6& L)
    : problem_(problem), k_(k), L_(L), n_(problem->n) {
  set_num_residuals(6);
  mutable_parameter_block_sizes()->push_back(6);
  mutable_parameter_block_sizes()->push_back(n_);
}

Vec6 MeasurementCost::Raw(const double* x, const double* theta) const {
  Eigen::Map<const Vec6> s(x);
  Eigen::Map<const Eigen::VectorXd> th(theta, n_);
  const ReferenceSample ref =
      EvaluateReference(problem_->cfg, th, problem_->series.recorded[k_], false);
  Vec6 r;
  r << s.head<3>() - ref.v_mps, s.tail<3>() - ref.p_m;
  return r;
}

bool MeasurementCost::Evaluate(double const* const* p, double* residuals,
                               double** jacobians) const {
  Eigen::Map<const Vec6> s(p[0]);
  Eigen::Map<const Eigen::VectorXd> th(p[1], n_);
  const bool want_theta = jacobians && jacobians[1];
  const ReferenceSample ref =
      EvaluateReference(problem_->cfg, th, problem_->series.recorded[k_], want_theta);
  Vec6 r;
  r << s.head<3>() - ref.v_mps, s.tail<3>() - ref.p_m;
  Eigen::Map<Vec6> out(residuals);
  out = L_ * r;
  if (!jacobians) return true;
  if (jacobians[0]) Store(L_, jacobians[0]);
  if (want_theta) Store(-L_ * ref.dref_dtheta, jacobians[1]);
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

#include "solvers/estimation/batch_objective.h"

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace triadcal {

namespace {

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

bool BatchObjective::HasGyroPart(const Point& pt, int r) const {
  return has_gyro_[r] && r < static_cast<int>(pt.gyro.size()) && pt.gyro[r].degrees_of_freedom > 0;
}

bool BatchObjective::Point::finite() const {
  return std::isfinite(cost) && (gradient.size() == 0 || gradient.allFinite());
}

BatchObjective::BatchObjective(std::vector<LinkedRun> runs, Eigen::MatrixXd A, Eigen::VectorXd b,
                               const Eigen::VectorXd& weights_phi, int threads,
                               std::vector<std::shared_ptr<const RunPass>> weights)
    : runs_(std::move(runs)), weights_(std::move(weights)), A_(std::move(A)), b_(std::move(b)),
      threads_(threads) {
  m_ = static_cast<int>(A_.cols());
  for (const LinkedRun& r : runs_) {
    if (!r.problem) throw std::logic_error("BatchObjective: a run without its problem");
    const int n = r.problem->n;
    if (r.map.size() == 0 ? n != m_ : (r.map.rows() != n || r.map.cols() != m_)) {
      throw std::logic_error("BatchObjective: a run's map does not fit its layout");
    }
  }
  for (int r = 0; r < this->runs(); ++r) {
    if (static_cast<int>(weights_.size()) <= r) {
      weights_.push_back(std::make_shared<const RunPass>(
          WeightsPass(*runs_[r].problem, ThetaOf(r, weights_phi), threads_)));
    }
    has_gyro_.push_back(RunHasGyro(*runs_[r].problem));
    gyro_noise_hint_.push_back(runs_[r].problem->gyro_noise_rad_s);
  }
}

Eigen::VectorXd BatchObjective::ThetaOf(int r, const Eigen::VectorXd& phi) const {
  const LinkedRun& lr = runs_[r];
  Eigen::VectorXd theta = lr.map.size() == 0 ? phi : Eigen::VectorXd(lr.map * phi);
  if (lr.offset.size() > 0) theta += lr.offset;
  return theta;
}

Eigen::MatrixXd BatchObjective::MapOf(int r) const {
  const LinkedRun& lr = runs_[r];
  return lr.map.size() == 0 ? Eigen::MatrixXd::Identity(m_, m_) : lr.map;
}

BatchObjective::Point BatchObjective::Evaluate(const Eigen::VectorXd& phi,
                                               const std::vector<Eigen::Vector3d>& noise,
                                               bool with_jacobian, ThetaPart theta_part,
                                               const std::vector<int>* free) const {
  Point pt;
  pt.phi = phi;
  pt.passes.reserve(runs_.size());
  const auto t_pass = std::chrono::steady_clock::now();
  for (int r = 0; r < runs(); ++r) {
    pt.passes.push_back(std::make_shared<const RunPass>(
        EvaluatePass(*runs_[r].problem, ThetaOf(r, phi), with_jacobian, threads_)));
  }
  pt.gyro_passes.resize(runs_.size());
  for (int r = 0; r < runs(); ++r) {
    if (!has_gyro_[r]) continue;
    pt.gyro_passes[r] = std::make_shared<const GyroPass>(
        EvaluateGyroPass(*runs_[r].problem, ThetaOf(r, phi), with_jacobian, threads_));
  }
  work_.passes += 1;
  work_.pass_seconds += SecondsSince(t_pass);
  const auto t_gyro = std::chrono::steady_clock::now();
  pt.gyro.resize(runs_.size());
  for (int r = 0; r < runs(); ++r) {
    if (!has_gyro_[r]) continue;
    const RunProblem& p = *runs_[r].problem;
    const int fitted = p.cfg.layout.has_gyro() ? kNumGyroParams : 0;
    if (gyro_noise_held_) {
      pt.gyro[r] = ReduceGyroAtNoise(*pt.gyro_passes[r], p.gyro_noise_rad_s,
                                     GyroNoiseDofShare(*pt.gyro_passes[r], fitted));
      continue;
    }
    pt.gyro[r] =
        ReduceGyroAtBestNoise(*pt.gyro_passes[r], gyro_noise_hint_[r], fitted, true, threads_);
    if (pt.gyro[r].noise_rad_s.allFinite()) gyro_noise_hint_[r] = pt.gyro[r].noise_rad_s;
  }
  work_.reduction_seconds += SecondsSince(t_gyro);
  Reweight(&pt, noise, theta_part, free);
  return pt;
}

std::vector<int> BatchObjective::ColumnsOf(int r, const std::vector<int>& free) const {
  const LinkedRun& lr = runs_[r];
  if (lr.map.size() == 0) return free;
  std::vector<int> cols;
  for (int i = 0; i < lr.map.rows(); ++i) {
    for (int j : free) {
      if (lr.map(i, j) != 0.0) {
        cols.push_back(i);
        break;
      }
    }
  }
  return cols;
}

void BatchObjective::Reweight(Point* pt, const std::vector<Eigen::Vector3d>& noise,
                              ThetaPart theta_part, const std::vector<int>* free) const {
  const auto t0 = std::chrono::steady_clock::now();
  pt->reductions.clear();
  for (int r = 0; r < runs(); ++r) {
    std::vector<int> cols;
    if (free) cols = ColumnsOf(r, *free);
    pt->reductions.push_back(Reduce(*runs_[r].problem, *pt->passes[r], *weights_[r], noise[r],
                                    threads_, theta_part, free ? &cols : nullptr));
  }
  Assemble(pt);
  work_.reductions += 1;
  work_.reduction_seconds += SecondsSince(t0);
}

BatchObjective::Point BatchObjective::AtNoise(const Point& pt,
                                              const std::vector<Eigen::Vector3d>& noise,
                                              ThetaPart theta_part,
                                              const std::vector<int>* free) const {
  Point at;
  at.phi = pt.phi;
  at.passes = pt.passes;
  at.gyro_passes = pt.gyro_passes;
  at.gyro = pt.gyro;
  Reweight(&at, noise, theta_part, free);
  return at;
}

void BatchObjective::ReweightGyro(Point* pt, const Point& other) const {
  const auto t0 = std::chrono::steady_clock::now();
  for (int r = 0; r < runs(); ++r) {
    if (!HasGyroPart(*pt, r) || !HasGyroPart(other, r)) continue;
    pt->gyro[r] = ReduceGyroAtNoise(*pt->gyro_passes[r], other.gyro[r].noise_rad_s,
                                    pt->gyro[r].rho);
  }
  Assemble(pt);
  work_.reduction_seconds += SecondsSince(t0);
}

void BatchObjective::Assemble(Point* pt) const {
  const Eigen::VectorXd res = A_ * pt->phi - b_;
  pt->data_cost = 0.0;
  for (const RunReduction& red : pt->reductions) pt->data_cost += red.cost;
  pt->gyro_cost = 0.0;
  for (int r = 0; r < runs(); ++r) {
    if (HasGyroPart(*pt, r)) pt->gyro_cost += pt->gyro[r].neg_log_l;
  }
  pt->cost = pt->data_cost + pt->gyro_cost + 0.5 * res.squaredNorm();
  const bool with_jacobian = !pt->reductions.empty() && pt->reductions[0].gradient.size() > 0;
  if (!with_jacobian) {
    pt->gradient.resize(0);
    pt->information.resize(0, 0);
    pt->data_information.resize(0, 0);
    pt->data_information_scale.resize(0);
    return;
  }
  const bool with_information = pt->reductions[0].information.size() > 0;
  pt->gradient = A_.transpose() * res;
  pt->data_information = Eigen::MatrixXd::Zero(with_information ? m_ : 0, with_information ? m_ : 0);
  pt->data_information_scale = Eigen::VectorXd::Zero(with_information ? m_ : 0);
  for (int r = 0; r < runs(); ++r) {
    const RunReduction& red = pt->reductions[r];
    Eigen::VectorXd g = red.gradient;
    Eigen::MatrixXd I = red.information;
    Eigen::VectorXd scale = red.information_scale.size() == red.information.rows()
                                ? red.information_scale
                                : Eigen::VectorXd(red.information.diagonal().cwiseAbs());
    if (HasGyroPart(*pt, r) && pt->gyro[r].gradient.size() > 0) {
      g += pt->gyro[r].gradient;
      if (with_information) {
        I += pt->gyro[r].information;
        scale += pt->gyro[r].information.diagonal().cwiseAbs();
      }
    }
    if (runs_[r].map.size() == 0) {
      pt->gradient += g;
      if (with_information) {
        pt->data_information += I;
        pt->data_information_scale += scale;
      }
    } else {
      const Eigen::MatrixXd& T = runs_[r].map;
      pt->gradient.noalias() += T.transpose() * g;
      if (with_information) {
        pt->data_information.noalias() += T.transpose() * I * T;
        pt->data_information_scale.noalias() += T.cwiseAbs2().transpose() * scale;
      }
    }
  }
  pt->information = with_information ? Eigen::MatrixXd(pt->data_information + A_.transpose() * A_)
                                     : Eigen::MatrixXd();
}

void PriorAndConstraintRows(const RunProblem& p, Eigen::MatrixXd* A, Eigen::VectorXd* b) {
  const int n = p.n;
  const int k = static_cast<int>(p.constraints.size());
  A->setZero(n + k, n);
  b->resize(n + k);
  for (int i = 0; i < n; ++i) {
    (*A)(i, i) = 1.0 / p.prior.sigma[i];
    (*b)[i] = p.prior.mean[i] / p.prior.sigma[i];
  }
  for (int j = 0; j < k; ++j) {
    const ConstraintRow& c = p.constraints[j];
    A->row(n + j) = c.c.transpose() / c.sigma;
    (*b)[n + j] = c.value / c.sigma;
  }
}

}  // namespace triadcal

#include "solvers/estimation/hac_covariance.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

namespace triadcal {

double Lag1(const Eigen::VectorXd& series) {
  const Eigen::Index N = series.size();
  if (N < 3) return 0.0;
  const Eigen::VectorXd x = series.array() - series.mean();
  const double x0 = x.head(N - 1).squaredNorm();
  return x0 > 0.0 ? x.tail(N - 1).dot(x.head(N - 1)) / x0 : 0.0;
}

double BartlettAr1Ratio(double rho, double bandwidth, Eigen::Index max_lag) {
  rho = std::clamp(rho, -0.97, 0.97);
  double g = 1.0, p = 1.0;
  for (Eigen::Index l = 1; static_cast<double>(l) < bandwidth && l <= max_lag; ++l) {
    p *= rho;
    g += 2.0 * (1.0 - static_cast<double>(l) / bandwidth) * p;
  }
  // g > 0 for the Bartlett weights (a non-negative spectral window); kept
  // as a guard against a degenerate series.
  return g > 0.0 ? (1.0 + rho) / (1.0 - rho) / g : 1.0;
}

double BartlettBandwidth(const Eigen::MatrixXd& series, const Eigen::VectorXd& weight,
                         double* largest_lag1) {
  const Eigen::Index N = series.rows();
  if (largest_lag1) *largest_lag1 = 0.0;
  if (N < 4) return 0.0;
  double num = 0.0, den = 0.0;
  for (Eigen::Index a = 0; a < series.cols(); ++a) {
    if (weight[a] <= 0.0) continue;
    const Eigen::VectorXd x = series.col(a).array() - series.col(a).mean();
    const double c0 = x.squaredNorm();
    if (!(c0 > 0.0)) continue;
    // AR(1) by least squares: rho and the innovation variance, in units of
    // the series' variance (each parameter counts alike, whatever its unit).
    const double c1 = x.tail(N - 1).dot(x.head(N - 1));
    const double x0 = x.head(N - 1).squaredNorm();
    double rho = x0 > 0.0 ? c1 / x0 : 0.0;
    if (largest_lag1) *largest_lag1 = std::max(*largest_lag1, std::abs(rho));
    rho = std::clamp(rho, -0.97, 0.97);
    const double s2 = std::max(1e-12, (c0 - c1 * rho) / c0);  // innovation var / var
    const double s4 = s2 * s2;
    num += weight[a] * 4.0 * rho * rho * s4 /
           (std::pow(1.0 - rho, 6) * (1.0 + rho) * (1.0 + rho));
    den += weight[a] * s4 / std::pow(1.0 - rho, 4);
  }
  if (!(den > 0.0)) return 0.0;
  const double S = 1.1447 * std::cbrt(num / den * static_cast<double>(N));
  return std::min(S, 0.5 * static_cast<double>(N));
}

HacDataPart HacDataCovariance(const std::vector<Eigen::VectorXd>& scores,
                              const Eigen::MatrixXd& Iinv, const Eigen::VectorXd& weight,
                              double bandwidth, bool prewhiten, bool correct_kernel_bias) {
  const Eigen::Index n = Iinv.rows();
  const std::size_t E = scores.size();
  HacDataPart out;
  out.kernel_bias_factor = Eigen::VectorXd::Ones(n);
  out.cov = Eigen::MatrixXd::Zero(n, n);
  if (E < 2) return out;
  Eigen::MatrixXd s(E, n);
  for (std::size_t e = 0; e < E; ++e) s.row(static_cast<Eigen::Index>(e)) = scores[e].transpose();
  // Prewhitening when asked (hac_covariance.h: why not by default): u_e =
  // s_e - rho s_{e-1}, the kernel estimate on u, recoloured by 1 / (1 - rho).
  Eigen::VectorXd rho = Eigen::VectorXd::Zero(n);
  if (prewhiten) {
    for (Eigen::Index a = 0; a < n; ++a) {
      const double x0 = s.col(a).head(E - 1).squaredNorm();
      if (x0 > 0.0) {
        rho[a] = std::clamp(s.col(a).tail(E - 1).dot(s.col(a).head(E - 1)) / x0, -0.97, 0.97);
      }
    }
  }
  out.score_lag1 = rho.cwiseAbs().maxCoeff();
  const Eigen::Index m0 = static_cast<Eigen::Index>(prewhiten ? E - 1 : E);
  Eigen::MatrixXd u(m0, n);
  if (prewhiten) {
    u = s.bottomRows(m0) - s.topRows(m0) * rho.asDiagonal();
  } else {
    u = s;
  }
  double lag1_of_u = 0.0;
  out.bandwidth = bandwidth >= 0.0 ? bandwidth : BartlettBandwidth(u, weight, &lag1_of_u);
  if (!prewhiten) out.score_lag1 = lag1_of_u;

  Eigen::MatrixXd B = u.transpose() * u;
  for (Eigen::Index l = 1; static_cast<double>(l) < out.bandwidth && l < m0; ++l) {
    const double w = 1.0 - static_cast<double>(l) / out.bandwidth;
    const Eigen::Index m = m0 - l;
    const Eigen::MatrixXd G = u.bottomRows(m).transpose() * u.topRows(m);
    B.noalias() += w * (G + G.transpose());
  }
  if (prewhiten) {
    const Eigen::VectorXd d = (Eigen::VectorXd::Ones(n) - rho).cwiseInverse();
    B = d.asDiagonal() * B * d.asDiagonal();
    B *= static_cast<double>(E) / static_cast<double>(m0);  // the one epoch the filter drops
  }
  const double N = 6.0 * static_cast<double>(E - 1);
  const double k = weight.sum();
  out.cov = Iinv * B * Iinv * (N / std::max(1.0, N - k));
  // The kernel's bias (hac_covariance.h), parameter by parameter: the
  // long-run variance of an AR(1) series with the lag-1 of the parameter's
  // influence series (I^-1 u_e, what each epoch adds to its error) over what
  // the Bartlett weights at this bandwidth take of it.
  if (correct_kernel_bias) {
    const Eigen::MatrixXd influence = u * Iinv;
    const Eigen::Index max_lag = m0 - 1;
    for (Eigen::Index a = 0; a < n; ++a) {
      if (!(out.cov(a, a) > 0.0)) continue;
      out.kernel_bias_factor[a] =
          std::sqrt(BartlettAr1Ratio(Lag1(influence.col(a)), out.bandwidth, max_lag));
    }
    const Eigen::VectorXd& d = out.kernel_bias_factor;
    out.cov = d.asDiagonal() * out.cov * d.asDiagonal();
  }
  return out;
}

HacCovariance HacThetaCovariance(const std::vector<Eigen::VectorXd>& scores,
                                 const Eigen::MatrixXd& information,
                                 const Eigen::MatrixXd& theta_rows_information,
                                 double bandwidth, bool prewhiten,
                                 bool correct_kernel_bias) {
  const Eigen::Index n = information.rows();
  HacCovariance out;
  out.kernel_bias_factor = Eigen::VectorXd::Ones(n);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(information);
  const Eigen::MatrixXd Iinv = ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  if (scores.size() < 2) {
    out.cov = Iinv;
    return out;
  }
  // The parameters the data determine (at least half of their information
  // from the data) choose the bandwidth and count in the small-sample factor.
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(n);
  for (Eigen::Index a = 0; a < n; ++a) {
    const double total = information(a, a);
    const double data = total - theta_rows_information(a, a);
    if (total > 0.0 && data >= 0.5 * total) weight[a] = 1.0;
  }
  const HacDataPart part =
      HacDataCovariance(scores, Iinv, weight, bandwidth, prewhiten, correct_kernel_bias);
  out.bandwidth = part.bandwidth;
  out.score_lag1 = part.score_lag1;
  out.kernel_bias_factor = part.kernel_bias_factor;
  out.cov = part.cov + Iinv * theta_rows_information * Iinv;
  out.cov = 0.5 * (out.cov + out.cov.transpose());
  return out;
}

Eigen::MatrixXd FloorVariances(const Eigen::MatrixXd& cov, const Eigen::MatrixXd& floor) {
  Eigen::VectorXd d = Eigen::VectorXd::Ones(cov.rows());
  for (Eigen::Index i = 0; i < cov.rows(); ++i) {
    if (cov(i, i) > 0.0 && floor(i, i) > cov(i, i)) d[i] = std::sqrt(floor(i, i) / cov(i, i));
  }
  Eigen::MatrixXd out = d.asDiagonal() * cov * d.asDiagonal();
  // A variance the sandwich leaves at zero (a held parameter) keeps the floor's.
  for (Eigen::Index i = 0; i < cov.rows(); ++i) {
    if (!(cov(i, i) > 0.0)) out(i, i) = floor(i, i);
  }
  return out;
}

}  // namespace triadcal

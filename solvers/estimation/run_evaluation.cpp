#include "solvers/estimation/run_evaluation.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "solvers/estimation/parallel.h"

namespace triadcal {
namespace {

// s_i^2 = (g sigma_i / K_i)^2 [m^2/s^4], the acceleration noise of channel i.
Eigen::Vector3d ChannelVariance(const RunProblem& p, const Eigen::VectorXd& theta,
                                const Eigen::Vector3d& noise) {
  Eigen::Vector3d var;
  for (int i = 0; i < 3; ++i) {
    const double s = p.cfg.g_mps2 * noise[i] / std::abs(theta[kKx + i]);
    var[i] = s * s;
  }
  return var;
}

}  // namespace

Mat6 ProcessCovariance(const RunProblem& p, const ProcessStep& s, const Eigen::VectorXd& theta,
                       const Eigen::Vector3d& noise_mV) {
  const Eigen::Vector3d var = ChannelVariance(p, theta, noise_mV);
  const ProcessNoise& q = *s.noise;
  Mat6 Q = q.Q_iso;
  for (int i = 0; i < 3; ++i) Q += var[i] * q.channel_weight[i];
  return Q;
}

namespace {

RunPass Pass(const RunProblem& p, const Eigen::VectorXd& theta, bool with_jacobian,
             bool with_noise, int threads) {
  if (!p.held.empty()) throw std::logic_error("EvaluatePass: the problem holds parameters");
  const StateSpaceModel model(p);
  const std::size_t E = p.epochs.size();
  RunPass pass;
  pass.theta = theta;
  pass.with_jacobian = with_jacobian;
  pass.with_noise = with_noise;
  pass.process.resize(E - 1);
  pass.measurement.resize(E);
  if (with_noise) pass.LR.resize(E);
  ParallelFor(E, threads, [&](std::size_t e) {
    // The weights' pass (with the noise) needs no increments.
    if (e + 1 < E) {
      pass.process[e] = model.Process(e, theta, with_jacobian, with_noise, !with_noise);
    }
    pass.measurement[e] = model.Measurement(e, theta, with_jacobian, with_noise);
    if (with_noise) pass.LR[e] = WhiteningOf(pass.measurement[e].R);
  });
  return pass;
}

}  // namespace

RunPass EvaluatePass(const RunProblem& p, const Eigen::VectorXd& theta, bool with_jacobian,
                     int threads) {
  return Pass(p, theta, with_jacobian, false, threads);
}

RunPass WeightsPass(const RunProblem& p, const Eigen::VectorXd& theta_ref, int threads) {
  return Pass(p, theta_ref, false, true, threads);
}

std::shared_ptr<const RunPass> SharedRunWork::Weights(const RunProblem& p, int threads) {
  const Eigen::VectorXd nominal = p.prior.mean.head(kNumBaseParams);
  WeightsEntry& w = weights_;
  if (!w.pass || w.data != p.series.run || w.epochs != p.epochs || w.nominal != nominal ||
      w.sigma_angle != p.sigma_angle || w.sigma_rate != p.sigma_rate ||
      w.isotropic_var != p.isotropic_var) {
    w = WeightsEntry{p.series.run, p.epochs, nominal, p.sigma_angle, p.sigma_rate,
                     p.isotropic_var,
                     std::make_shared<const RunPass>(WeightsPass(p, p.prior.mean, threads))};
  }
  return w.pass;
}

RunReduction Reduce(const RunProblem& p, const RunPass& pass, const RunPass& weights,
                    const Eigen::Vector3d& noise_mV, int threads, ThetaPart theta_part,
                    const std::vector<int>* columns) {
  if (!weights.with_noise) throw std::logic_error("Reduce: the weights' pass has no noise weights");
  if (pass.with_noise) throw std::logic_error("Reduce: the weights' pass has no increments");
  const RunPass& wp = weights;
  const std::size_t E = pass.measurement.size();
  const int n = pass.with_jacobian ? static_cast<int>(pass.theta.size()) : 0;
  const Eigen::VectorXd& theta = pass.theta;
  const Eigen::Vector3d var = ChannelVariance(p, theta, noise_mV);
  RunReduction out;
  out.noise_mV = noise_mV;
  out.degrees_of_freedom = static_cast<int>(6 * (E - 1));

  // 1. The trajectory for this theta: the residuals are affine in the states,
  // formed about the B2 reference motion (small numbers: about x = 0 the
  // cost would be the difference of two numbers ~1e10 times larger).
  std::vector<Mat6> LQ(E - 1);
  std::vector<Vec6> raw0(E - 1);  // raw process residual at the reference motion
  std::vector<ProcessBlock> pb(E - 1);
  std::vector<MeasurementBlock> mb(E);
  ParallelFor(E, threads, [&](std::size_t e) {
    const Vec6& h = pass.measurement[e].h;
    mb[e].M = wp.LR[e];
    mb[e].N.resize(6, 0);
    mb[e].r0.setZero();  // x = h: the measurement residual is zero there
    if (e + 1 < E) {
      const ProcessStep& s = pass.process[e];
      const ProcessNoise& w = *wp.process[e].noise;
      Mat6 Q = w.Q_iso;
      for (int i = 0; i < 3; ++i) Q += var[i] * w.channel_weight[i];
      LQ[e] = WhiteningOf(Q);
      raw0[e] = pass.measurement[e + 1].h - s.F() * h - s.u;
      pb[e].A = -LQ[e] * s.F();
      pb[e].B = LQ[e];
      pb[e].C.resize(6, 0);
      pb[e].r0 = LQ[e] * raw0[e];
    }
  });
  const ReducedOverStates at_states = ReduceOverStates(pb, mb, true);
  out.cost = at_states.cost;
  out.states.resize(E);
  out.process_residual.assign(E, Vec6::Zero());
  out.measurement_residual.resize(E);
  for (std::size_t e = 0; e < E; ++e) {
    const Vec6& dx = at_states.states[e];
    out.states[e] = pass.measurement[e].h + dx;
    out.measurement_residual[e] = dx;
    if (e > 0) {
      const ProcessStep& s = pass.process[e - 1];
      out.process_residual[e] = raw0[e - 1] + dx - s.F() * at_states.states[e - 1];
    }
  }

  // 2. The reading noise's part of the likelihood at the optimal states. With
  // s_i = log sigma_i, d cost / d s_i = -q_i, q_i = r^T Q^-1 Q_i Q^-1 r; the
  // log-determinant 0.5 sum_e log det Q_e(s) is taken with the scale factors
  // of the weights' reference (the readings' own noise does not depend on
  // theta), so that d/ds_i of it is N_i = sum_e tr(Q_e^-1 Q_i,e) there.
  const Eigen::Vector3d var_ref = ChannelVariance(p, wp.theta, noise_mV);
  // Per interval: q_i, N_i, log det, and the 3 x 3 q_ij = (Q_i w)^T Q^-1 (Q_j w)
  // and tr(A_i A_j) (A_i = Q^-1 Q_i) of the noise's second derivatives.
  struct Parts {
    Eigen::Vector3d q, N;
    double log_det = 0.0;
    Eigen::Matrix3d qq, tt;
  };
  std::vector<Parts> comp(E - 1);
  // The noise's pseudo-residuals p_i (RunReduction::gradient_by_log_noise),
  // with the noise's coupling only.
  const bool information =
      pass.with_jacobian && (theta_part == ThetaPart::kGradientAndInformation ||
                             theta_part == ThetaPart::kGradientAndInformationAtFixedNoise);
  const bool coupling = information && theta_part == ThetaPart::kGradientAndInformation;
  std::vector<std::array<Vec6, 3>> pseudo(coupling ? E - 1 : 0);
  ParallelFor(E - 1, threads, [&](std::size_t e) {
    const ProcessNoise& qn = *wp.process[e].noise;
    // Q's whitening from step 1: Q^-1 v = LQ^T LQ v (products of the whole
    // 6 x 6, its upper triangle zero: cheaper than Eigen's triangular kernels
    // at this size).
    const Mat6& L = LQ[e];
    auto solve_q = [&L](const Vec6& v) -> Vec6 {
      const Vec6 Lv = L * v;
      return L.transpose() * Lv;
    };
    Mat6 Q_ref = qn.Q_iso;
    for (int i = 0; i < 3; ++i) Q_ref += var_ref[i] * qn.channel_weight[i];
    Parts& c = comp[e];
    // With Q_ref = R R^T and L_ref = R^-1: A_i = Q_ref^-1 Q_i is similar to
    // the symmetric B_i = L_ref Q_i L_ref^T, so tr A_i = tr B_i and
    // tr(A_i A_j) = tr(B_i B_j) = sum B_i o B_j.
    const Mat6 L_ref = WhiteningOf(Q_ref, &c.log_det);  // 0.5 log det
    const Vec6 w = solve_q(out.process_residual[e + 1]);
    std::array<Mat6, 3> B;
    std::array<Vec6, 3> QiQinv_r, QinvQiw;
    for (int i = 0; i < 3; ++i) {
      B[i].noalias() = L_ref * (var_ref[i] * qn.channel_weight[i]) * L_ref.transpose();
      QiQinv_r[i] = var[i] * (qn.channel_weight[i] * w);
      QinvQiw[i] = solve_q(QiQinv_r[i]);
      c.q[i] = w.dot(QiQinv_r[i]);
      c.N[i] = B[i].trace();
      if (coupling) pseudo[e][i] = -2.0 * (L * QiQinv_r[i]);
    }
    // Both symmetric: q_ij = (Q_i w)^T Q^-1 (Q_j w), tr(B_i B_j) = sum B_i o B_j.
    for (int i = 0; i < 3; ++i) {
      for (int j = i; j < 3; ++j) {
        c.qq(i, j) = c.qq(j, i) = QiQinv_r[i].dot(QinvQiw[j]);
        c.tt(i, j) = c.tt(j, i) = B[i].cwiseProduct(B[j]).sum();
      }
    }
  });
  for (const Parts& c : comp) {
    out.channel_quadratic += c.q;
    out.channel_trace += c.N;
    out.channel_trace2 += c.tt.diagonal();
    out.channel_cross_quadratic += c.qq;
    out.channel_cross_trace += c.tt;
    out.log_det += c.log_det;
  }
  if (!pass.with_jacobian || theta_part == ThetaPart::kNone) return out;

  // 3. The theta part at the optimal states: the whitened Jacobians (the
  // process whitening's derivative by K_i acts on the residual there), the
  // gradient J_theta^T r (J_x^T r = 0 at the optimal states) and the
  // information with the states eliminated. The gradient alone keeps no
  // Jacobian: each epoch's share is summed in order.
  // The columns formed (all n, or the caller's): col[c] is theta's index of
  // column c, and k_col[i] the column of K_i (-1 when not formed).
  std::vector<int> col;
  if (columns) {
    col = *columns;
  } else {
    col.resize(n);
    for (int i = 0; i < n; ++i) col[i] = i;
  }
  const int nc = static_cast<int>(col.size());
  bool all_columns = nc == n;  // every column, in theta's order
  for (int c = 0; c < nc && all_columns; ++c) all_columns = col[c] == c;
  std::array<int, 3> k_col = {-1, -1, -1};
  for (int c = 0; c < nc; ++c) {
    if (col[c] >= kKx && col[c] <= kKz) k_col[col[c] - kKx] = c;
  }
  auto columns_of = [&](const Eigen::MatrixXd& M) -> Eigen::MatrixXd {
    if (all_columns) return M;
    Eigen::MatrixXd out(M.rows(), nc);
    for (int c = 0; c < nc; ++c) out.col(c) = M.col(col[c]);
    return out;
  };
  std::vector<Eigen::VectorXd> share_m, share_p;  // without the information: N^T r0, C^T r0
  // With the information: each K_i column's part from the weights' derivative.
  std::vector<std::array<Vec6, 3>> k_weight(coupling ? E - 1 : 0);
  if (!information) {
    share_m.resize(E);
    share_p.resize(E);
  }
  ParallelFor(E, threads, [&](std::size_t e) {
    const MeasurementStep& m = pass.measurement[e];
    mb[e].N = -wp.LR[e] * columns_of(m.H);
    mb[e].r0 = wp.LR[e] * out.measurement_residual[e];
    if (!information) {
      share_m[e].noalias() = mb[e].N.transpose() * mb[e].r0;
      mb[e].N.resize(6, 0);
    }
    if (e + 1 == E) return;
    const ProcessStep& s = pass.process[e];
    const Vec6& r = out.process_residual[e + 1];
    const ProcessNoise& w = *wp.process[e].noise;
    pb[e].C = -LQ[e] * columns_of(s.U);
    pb[e].r0 = LQ[e] * r;
    for (int i = 0; i < 3; ++i) {
      if (k_col[i] < 0) continue;
      // d var_i / d K_i = -2 var_i / K_i. The whitening L = R^-1 of Q = R R^T
      // moves as dL = -Phi(L dQ L^T) L, Phi the lower triangle with half the
      // diagonal (the Cholesky factor's derivative), and L r = r0.
      Mat6 X = LQ[e] * w.channel_weight[i] * LQ[e].transpose();
      X.diagonal() *= 0.5;
      const Mat6 X_lower = X.triangularView<Eigen::Lower>();
      const Vec6 dLr = -(X_lower * pb[e].r0);
      pb[e].C.col(k_col[i]) += dLr * (-2.0 * var[i] / theta[kKx + i]);
      if (coupling) k_weight[e][i] = dLr * (-2.0 * var[i] / theta[kKx + i]);
    }
    if (!information) {
      share_p[e].noalias() = pb[e].C.transpose() * pb[e].r0;
      pb[e].C.resize(6, 0);
    }
  });
  Eigen::VectorXd gradient = Eigen::VectorXd::Zero(nc);
  for (std::size_t e = 0; e < E; ++e) {
    if (information) {
      gradient.noalias() += mb[e].N.transpose() * mb[e].r0;
      if (e + 1 < E) gradient.noalias() += pb[e].C.transpose() * pb[e].r0;
    } else {
      gradient += share_m[e];
      if (e + 1 < E) gradient += share_p[e];
    }
  }
  if (all_columns) {
    out.gradient = std::move(gradient);
  } else {
    out.gradient = Eigen::VectorXd::Zero(n);
    for (int c = 0; c < nc; ++c) out.gradient[col[c]] = gradient[c];
  }
  if (!information) return out;
  // The noise's coupling, eliminated with the information: the probe's
  // columns are the pseudo-residuals p_i and the K_i columns' weights' part
  // (whose derivative by the noise is added exactly below).
  SchurProbe probe;
  probe.columns.resize(coupling ? E - 1 : 0);
  Eigen::Matrix3d pp = Eigen::Matrix3d::Zero();
  for (std::size_t e = 0; coupling && e + 1 < E; ++e) {
    Eigen::Matrix<double, 6, Eigen::Dynamic>& c = probe.columns[e];
    c.setZero(6, 6);
    for (int i = 0; i < 3; ++i) {
      c.col(i) = pseudo[e][i];
      if (k_col[i] >= 0) c.col(3 + i) = k_weight[e][i];
    }
    pp.noalias() += c.leftCols<3>().transpose() * c.leftCols<3>();
  }
  Eigen::VectorXd scale;
  Eigen::MatrixXd info = ThetaInformationBySchur(pb, mb, Eigen::MatrixXd::Zero(0, nc), &scale,
                                                 threads, coupling ? &probe : nullptr);
  // Without an interval or a column the elimination formed nothing.
  const bool probed = probe.self.rows() == 6 && probe.cross.rows() == nc && nc > 0;
  if (coupling) {
    Eigen::MatrixXd by_noise = Eigen::MatrixXd::Zero(nc, 3);
    if (probed) {
      out.channel_state_coupling = pp - probe.self.topLeftCorner<3, 3>();
      by_noise = probe.cross.leftCols<3>();
      for (int i = 0; i < 3; ++i) {
        if (k_col[i] >= 0) by_noise.row(k_col[i]) -= probe.self.block<1, 3>(3 + i, 0);
      }
    }
    // The weights' part of d cost / d K_i is q_i / K_i (d var_i / d K_i =
    // -2 var_i / K_i); by log sigma_j, the states solved for again, it moves
    // by (2 q_i d_ij - 4 qq_ij + p_i^T P_x p_j) / K_i (the noise's Hessian's
    // terms, NoiseHessian).
    for (int i = 0; i < 3; ++i) {
      if (k_col[i] < 0) continue;
      for (int j = 0; j < 3; ++j) {
        by_noise(k_col[i], j) += ((i == j ? 2.0 * out.channel_quadratic[i] : 0.0) -
                                  4.0 * out.channel_cross_quadratic(i, j) +
                                  out.channel_state_coupling(i, j)) /
                                 theta[kKx + i];
      }
    }
    out.gradient_by_log_noise = Eigen::MatrixXd::Zero(n, 3);
    for (int c = 0; c < nc; ++c) out.gradient_by_log_noise.row(col[c]) = by_noise.row(c);
  }
  if (all_columns) {
    out.information = std::move(info);
    out.information_scale = std::move(scale);
    out.process_blocks = std::move(pb);
    out.measurement_blocks = std::move(mb);
    return out;
  }
  // Over the columns formed; zero elsewhere, the blocks by those columns.
  out.process_blocks = std::move(pb);
  out.measurement_blocks = std::move(mb);
  out.block_columns = col;
  out.information = Eigen::MatrixXd::Zero(n, n);
  out.information_scale = Eigen::VectorXd::Zero(n);
  for (int a = 0; a < nc; ++a) {
    out.information_scale[col[a]] = scale[a];
    for (int b = 0; b < nc; ++b) out.information(col[a], col[b]) = info(a, b);
  }
  return out;
}

Eigen::Matrix3d NoiseHessian(const RunReduction& r, double rho) {
  Eigen::Matrix3d H = 4.0 * r.channel_cross_quadratic - 2.0 * rho * r.channel_cross_trace -
                      r.channel_state_coupling;
  for (int i = 0; i < 3; ++i) H(i, i) += -2.0 * r.channel_quadratic[i] + 2.0 * rho * r.channel_trace[i];
  return 0.5 * (H + H.transpose());
}

double NoiseDofShare(const RunReduction& r, int fitted_parameters) {
  return std::clamp(1.0 - fitted_parameters / std::max(1.0, double(r.degrees_of_freedom)), 0.1,
                    1.0);
}

Eigen::Vector3d NoiseFromReduction(const RunReduction& r, int fitted_parameters) {
  const double rho = NoiseDofShare(r, fitted_parameters);
  Eigen::Vector3d out = r.noise_mV;
  for (int i = 0; i < 3; ++i) {
    if (r.channel_trace[i] > 0.0) {
      out[i] *= std::sqrt(std::max(r.channel_quadratic[i], 0.0) / (rho * r.channel_trace[i]));
    }
  }
  return out;
}

Eigen::Vector3d NoiseDegreesOfFreedom(const RunReduction& r, int fitted_parameters) {
  const double rho = NoiseDofShare(r, fitted_parameters);
  Eigen::Vector3d dof = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    if (r.channel_trace2[i] > 0.0) {
      dof[i] = rho * r.channel_trace[i] * r.channel_trace[i] / r.channel_trace2[i];
    }
  }
  return dof;
}

}  // namespace triadcal

#include "solvers/estimation/schur_covariance.h"

#include <Eigen/Cholesky>

#include "solvers/estimation/parallel.h"
#include "solvers/estimation/state_space_model.h"

namespace triadcal {

Eigen::MatrixXd ThetaInformationBySchur(const std::vector<ProcessBlock>& process,
                                        const std::vector<MeasurementBlock>& measurement,
                                        const Eigen::MatrixXd& theta_rows,
                                        Eigen::VectorXd* scale, int threads,
                                        SchurProbe* probe) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  const std::size_t E = measurement.size();
  const Eigen::Index n = measurement[0].N.cols();
  Eigen::MatrixXd Htt = Eigen::MatrixXd::Zero(n, n);
  if (scale) *scale = Eigen::VectorXd::Zero(n);
  if (n == 0) return Htt;
  // H_tt - H_tx H_xx^-1 H_xt = rows^T rows + sum_e (N_e^T N_e + C_e^T C_e)
  // - sum_e W_e^T W_e, with W_e = L_e^-1 G_e (S_e = L_e L_e^T) the theta
  // coupling of state e once the states before it are eliminated. The
  // recursion is O(E n); the sums are rank updates of the lower triangle,
  // chunks of epochs at a time (one product of many rows instead of three
  // 6-row products an epoch: the score analysis's 84 columns took 0.1 s).
  // The first sum needs no elimination: the two are formed apart, on two
  // threads when there are.
  constexpr std::size_t kChunk = 64;
  Eigen::MatrixXd data_sum = Eigen::MatrixXd::Zero(n, n);
  Eigen::MatrixXd eliminated_sum = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd data_scale = Eigen::VectorXd::Zero(n);
  const Eigen::Index k = probe && !process.empty() ? probe->columns[0].cols() : 0;
  Eigen::MatrixXd cross_data = Eigen::MatrixXd::Zero(n, k), self_data = Eigen::MatrixXd::Zero(k, k);
  Eigen::MatrixXd cross_eliminated = Eigen::MatrixXd::Zero(n, k);
  Eigen::MatrixXd self_eliminated = Eigen::MatrixXd::Zero(k, k);
  auto data_part = [&]() {
    for (std::size_t e = 0; k > 0 && e + 1 < E; ++e) {
      cross_data.noalias() += process[e].C.transpose() * probe->columns[e];
      self_data.noalias() += probe->columns[e].transpose() * probe->columns[e];
    }
    Eigen::MatrixXd pos(12 * kChunk, n);
    std::size_t rows = 0;  // epochs in the chunk
    for (std::size_t e = 0; e < E; ++e) {
      pos.middleRows(12 * rows, 6) = measurement[e].N;
      if (e + 1 < E) {
        pos.middleRows(12 * rows + 6, 6) = process[e].C;
      } else {
        pos.middleRows(12 * rows + 6, 6).setZero();
      }
      if (++rows < kChunk && e + 1 < E) continue;
      data_scale += pos.topRows(12 * rows).colwise().squaredNorm().transpose();
      data_sum.selfadjointView<Eigen::Lower>().rankUpdate(pos.topRows(12 * rows).transpose());
      rows = 0;
    }
  };
  auto eliminated_part = [&]() {
    Eigen::MatrixXd neg(6 * kChunk, n);
    std::size_t rows = 0;
    // Running state of the elimination: S (6x6) and G (6xn) of the next x_e,
    // after eliminating the states before it.
    Mat6 S = measurement[0].M.transpose() * measurement[0].M;
    Eigen::MatrixXd G = measurement[0].M.transpose() * measurement[0].N;
    if (!process.empty()) {
      S += process[0].A.transpose() * process[0].A;
      G.noalias() += process[0].A.transpose() * process[0].C;
    }
    // The probe's columns ride along: their G and W.
    Eigen::MatrixXd G_p = Eigen::MatrixXd::Zero(6, k), W_p(6, k), Gn_p(6, k);
    if (k > 0) G_p.noalias() = process[0].A.transpose() * probe->columns[0];
    Eigen::MatrixXd W(6, n), Gn(6, n);
    for (std::size_t e = 0; e < E; ++e) {
      const Mat6 Li = LowerInverse(Eigen::LLT<Mat6>(S).matrixLLT());  // chol(S)^-1
      W.noalias() = Li * G;
      if (k > 0) {
        W_p.noalias() = Li * G_p;
        cross_eliminated.noalias() += W.transpose() * W_p;
        self_eliminated.noalias() += W_p.transpose() * W_p;
      }
      neg.middleRows(6 * rows, 6) = W;
      if (++rows == kChunk || e + 1 == E) {
        eliminated_sum.selfadjointView<Eigen::Lower>().rankUpdate(neg.topRows(6 * rows).transpose());
        rows = 0;
      }
      if (e + 1 == E) break;
      const ProcessBlock& p = process[e];
      // The fill-in of eliminating x_e: U^T S^-1 U and U^T S^-1 G, with
      // U = A^T B the (e, e+1) block, as (L^-1 U)^T (L^-1 U) and (L^-1 U)^T W.
      const Mat6 LiU = Li * (p.A.transpose() * p.B);
      Mat6 Sn = p.B.transpose() * p.B + measurement[e + 1].M.transpose() * measurement[e + 1].M;
      Gn.noalias() = p.B.transpose() * p.C;
      Gn.noalias() += measurement[e + 1].M.transpose() * measurement[e + 1].N;
      if (e + 1 < process.size()) {
        Sn += process[e + 1].A.transpose() * process[e + 1].A;
        Gn.noalias() += process[e + 1].A.transpose() * process[e + 1].C;
      }
      S = Sn - LiU.transpose() * LiU;
      G = Gn;
      G.noalias() -= LiU.transpose() * W;
      if (k > 0) {
        Gn_p.noalias() = p.B.transpose() * probe->columns[e];
        if (e + 1 < process.size()) {
          Gn_p.noalias() += process[e + 1].A.transpose() * probe->columns[e + 1];
        }
        G_p = Gn_p;
        G_p.noalias() -= LiU.transpose() * W_p;
      }
    }
  };
  ParallelFor(2, threads, [&](std::size_t part) {
    if (part == 0) {
      eliminated_part();
    } else {
      data_part();
    }
  });
  if (theta_rows.rows() > 0) {
    Htt.selfadjointView<Eigen::Lower>().rankUpdate(theta_rows.transpose());
    if (scale) *scale += theta_rows.colwise().squaredNorm().transpose();
  }
  if (scale) *scale += data_scale;
  Htt.triangularView<Eigen::Lower>() += data_sum;
  Htt.triangularView<Eigen::Lower>() -= eliminated_sum;
  for (Eigen::Index j = 1; j < n; ++j) {
    for (Eigen::Index i = 0; i < j; ++i) Htt(i, j) = Htt(j, i);
  }
  if (probe) {
    probe->cross = cross_data - cross_eliminated;
    probe->self = self_data - self_eliminated;
  }
  return Htt;
}

ReducedOverStates ReduceOverStates(const std::vector<ProcessBlock>& process,
                                   const std::vector<MeasurementBlock>& measurement,
                                   bool with_states) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  const std::size_t E = measurement.size();
  const int n = static_cast<int>(measurement[0].N.cols());
  ReducedOverStates out;
  out.information = Eigen::MatrixXd::Zero(n, n);
  out.gradient = Eigen::VectorXd::Zero(n);
  double rr = 0.0;
  // Without theta columns (the states alone solved for) the products by
  // them are skipped: each would cost a dynamic product's set-up.
  const bool with_theta = n > 0;
  for (const MeasurementBlock& m : measurement) {
    if (with_theta) {
      out.information.noalias() += m.N.transpose() * m.N;
      out.gradient.noalias() += m.N.transpose() * m.r0;
    }
    rr += m.r0.squaredNorm();
  }
  for (const ProcessBlock& p : process) {
    if (with_theta) {
      out.information.noalias() += p.C.transpose() * p.C;
      out.gradient.noalias() += p.C.transpose() * p.r0;
    }
    rr += p.r0.squaredNorm();
  }
  // The diagonal block, theta coupling and right-hand side of state e before
  // the elimination of the states before it.
  auto block = [&](std::size_t e, Mat6* S, Eigen::MatrixXd* G, Vec6* h) {
    const MeasurementBlock& m = measurement[e];
    *S = m.M.transpose() * m.M;
    if (with_theta) *G = m.M.transpose() * m.N;
    *h = m.M.transpose() * m.r0;
    if (e > 0) {
      const ProcessBlock& p = process[e - 1];
      *S += p.B.transpose() * p.B;
      if (with_theta) *G += p.B.transpose() * p.C;
      *h += p.B.transpose() * p.r0;
    }
    if (e < process.size()) {
      const ProcessBlock& p = process[e];
      *S += p.A.transpose() * p.A;
      if (with_theta) *G += p.A.transpose() * p.C;
      *h += p.A.transpose() * p.r0;
    }
  };
  Mat6 S;
  Eigen::MatrixXd G;
  Vec6 h;
  block(0, &S, &G, &h);
  double hSh = 0.0;
  // For the back substitution: x_e = S_e^-1 (-h_e - U_e x_{e+1}).
  std::vector<Mat6> Sinv_U(with_states ? E : 0);
  std::vector<Vec6> Sinv_h(with_states ? E : 0);
  Mat6 Sn;
  Eigen::MatrixXd Gn;
  Vec6 hn;
  for (std::size_t e = 0; e < E; ++e) {
    // S^-1 = Li^T Li with Li = chol(S)^-1 (LowerInverse: faster than
    // Eigen's triangular solves at 6 x 6).
    const Mat6 Li = LowerInverse(Eigen::LLT<Mat6>(S).matrixLLT());
    const Vec6 Sih = Li.transpose() * (Li * h);
    Eigen::MatrixXd SiG;
    if (with_theta) {
      SiG = Li.transpose() * (Li * G);
      out.information.noalias() -= G.transpose() * SiG;
      out.gradient.noalias() -= G.transpose() * Sih;
    }
    hSh += h.dot(Sih);
    if (with_states) Sinv_h[e] = Sih;
    if (e + 1 == E) break;
    const ProcessBlock& p = process[e];
    const Mat6 U = p.A.transpose() * p.B;
    const Mat6 SiU = Li.transpose() * (Li * U);
    if (with_states) Sinv_U[e] = SiU;
    block(e + 1, &Sn, &Gn, &hn);
    S = Sn - U.transpose() * SiU;
    if (with_theta) G = Gn - U.transpose() * SiG;
    h = hn - U.transpose() * Sih;
  }
  out.cost = 0.5 * (rr - hSh);
  out.information = 0.5 * (out.information + out.information.transpose());
  if (with_states) {
    // theta is held (the states are optimal for this theta): x_e = -S_e^-1 (h_e + U_e x_{e+1}).
    out.states.assign(E, Vec6::Zero());
    for (std::size_t k = E; k-- > 0;) {
      out.states[k] = -Sinv_h[k];
      if (k + 1 < E) out.states[k] -= Sinv_U[k] * out.states[k + 1];
    }
  }
  return out;
}

std::vector<Eigen::VectorXd> EpochScores(const std::vector<ProcessBlock>& process,
                                         const std::vector<MeasurementBlock>& measurement) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Rows6 = Eigen::Matrix<double, 6, Eigen::Dynamic>;
  const std::size_t E = measurement.size();
  std::vector<Eigen::VectorXd> scores(E);
  if (E == 0) return scores;
  // State x_e in T_e with x_0..x_{e-1} eliminated: its diagonal block S,
  // theta coupling G and right-hand side h; `done` is b_theta of T_e less what
  // the eliminated states took. S^-1 as (L^-1)^T L^-1 (S = L L^T, as
  // ThetaInformationBySchur): G^T S^-1 h = (L^-1 G)^T (L^-1 h). Six-row
  // blocks formed in place: the recursion is serial, every epoch counts.
  const MeasurementBlock& m0 = measurement[0];
  const Eigen::Index n = m0.N.cols();
  if (n == 0) {  // no theta columns: nothing to score
    for (Eigen::VectorXd& v : scores) v.resize(0);
    return scores;
  }
  Mat6 S = m0.M.transpose() * m0.M;
  Rows6 G(6, n), Gf(6, n), W(6, n);
  G.noalias() = m0.M.transpose() * m0.N;
  Vec6 h = m0.M.transpose() * m0.r0;
  Eigen::VectorXd done(n), F(n), F_prev = Eigen::VectorXd::Zero(n);
  done.noalias() = m0.N.transpose() * m0.r0;
  for (std::size_t e = 0; e < E; ++e) {
    // F_e: x_e solved for within T_e.
    {
      const Mat6 Li = LowerInverse(Eigen::LLT<Mat6>(S).matrixLLT());
      W.noalias() = Li * G;
      const Vec6 z = Li * h;
      F = done;
      F.noalias() -= W.transpose() * z;
    }
    scores[e] = F - F_prev;
    F_prev = F;
    if (e + 1 == E) break;
    // Interval e joins (T_{e+1}); x_e is eliminated with it, then epoch e+1's
    // measurement joins.
    const ProcessBlock& p = process[e];
    done.noalias() += p.C.transpose() * p.r0;
    const Mat6 Sf = S + p.A.transpose() * p.A;
    Gf = G;
    Gf.noalias() += p.A.transpose() * p.C;
    const Vec6 hf = h + p.A.transpose() * p.r0;
    const Mat6 Li = LowerInverse(Eigen::LLT<Mat6>(Sf).matrixLLT());
    W.noalias() = Li * Gf;
    const Vec6 z = Li * hf;
    done.noalias() -= W.transpose() * z;
    const Mat6 LiU = Li * (p.A.transpose() * p.B);
    const MeasurementBlock& m = measurement[e + 1];
    S = p.B.transpose() * p.B + m.M.transpose() * m.M - LiU.transpose() * LiU;
    G.noalias() = p.B.transpose() * p.C;
    G.noalias() += m.M.transpose() * m.N;
    G.noalias() -= LiU.transpose() * W;
    h = p.B.transpose() * p.r0 + m.M.transpose() * m.r0 - LiU.transpose() * z;
    done.noalias() += m.N.transpose() * m.r0;
  }
  return scores;
}

}  // namespace triadcal

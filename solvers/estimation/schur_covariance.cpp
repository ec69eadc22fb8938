#include "solvers/estimation/schur_covariance.h"

#include <Eigen/Cholesky>

namespace triadcal {

Eigen::MatrixXd ThetaInformationBySchur(const std::vector<ProcessBlock>& process,
                                        const std::vector<MeasurementBlock>& measurement,
                                        const Eigen::MatrixXd& theta_rows) {
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  const std::size_t E = measurement.size();
  Eigen::MatrixXd Htt = theta_rows.transpose() * theta_rows;
  for (const MeasurementBlock& m : measurement) Htt.noalias() += m.N.transpose() * m.N;
  for (const ProcessBlock& p : process) Htt.noalias() += p.C.transpose() * p.C;

  // Running state of the elimination: S (6x6) and G (6xn) of the next x_e,
  // after eliminating the states before it.
  Mat6 S = measurement[0].M.transpose() * measurement[0].M;
  Eigen::MatrixXd G = measurement[0].M.transpose() * measurement[0].N;
  if (!process.empty()) {
    S += process[0].A.transpose() * process[0].A;
    G += process[0].A.transpose() * process[0].C;
  }
  for (std::size_t e = 0; e < E; ++e) {
    const Eigen::LDLT<Mat6> ldlt(S);
    const Eigen::MatrixXd SiG = ldlt.solve(G);
    Htt.noalias() -= G.transpose() * SiG;
    if (e + 1 == E) break;
    const ProcessBlock& p = process[e];
    const Mat6 U = p.A.transpose() * p.B;  // H block (e, e+1)
    const Mat6 SiU = ldlt.solve(U);
    // Next diagonal block and theta coupling, before elimination ...
    Mat6 Sn = p.B.transpose() * p.B + measurement[e + 1].M.transpose() * measurement[e + 1].M;
    Eigen::MatrixXd Gn =
        p.B.transpose() * p.C + measurement[e + 1].M.transpose() * measurement[e + 1].N;
    if (e + 1 < process.size()) {
      Sn += process[e + 1].A.transpose() * process[e + 1].A;
      Gn += process[e + 1].A.transpose() * process[e + 1].C;
    }
    // ... and the fill-in from eliminating x_e.
    S = Sn - U.transpose() * SiU;
    G = Gn - U.transpose() * SiG;
  }
  return 0.5 * (Htt + Htt.transpose());
}

Eigen::MatrixXd ThetaCovarianceBySchur(const std::vector<ProcessBlock>& process,
                                       const std::vector<MeasurementBlock>& measurement,
                                       const Eigen::MatrixXd& theta_rows) {
  const int n = static_cast<int>(theta_rows.cols());
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(ThetaInformationBySchur(process, measurement, theta_rows));
  return ldlt.solve(Eigen::MatrixXd::Identity(n, n));
}

}  // namespace triadcal

#include "solvers/analysis/experiment_design.h"

#include <ceres/jet.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

#include "core/model/errors.h"
#include "core/model/priors.h"

namespace triadcal {
namespace {

std::vector<std::string> ConstraintExprs(const RunDescription& run) {
  std::vector<std::string> out;
  for (const Constraint& c : run.constraints) out.push_back(c.expr);
  return out;
}

DesignPoint PointFromVariant(const ObservabilityVariant& v, double duration_s) {
  DesignPoint d;
  d.duration_s = duration_s;
  d.sigma = v.cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (const Direction& dir : v.unobservable) d.directions.push_back(dir.named);
  d.unobservable = ParametersIn(d.directions);
  return d;
}

// Readings of one static position and their derivatives: J (3 x n) with
// respect to theta, H (3 x 2) with respect to the two bench angles.
template <int N>
void StaticJacobians(const ModelConfig& cfg, const Eigen::VectorXd& theta,
                     const std::array<double, 2>& pos, Eigen::MatrixXd* J, Eigen::MatrixXd* H) {
  using Jt = ceres::Jet<double, N>;
  const int n = static_cast<int>(theta.size());
  std::vector<Jt> th(N);
  for (int i = 0; i < N; ++i) th[i] = Jt(i < n ? theta[i] : 0.0, i);
  BenchAngles<Jt> b;
  for (int a = 0; a < 2; ++a) {
    b.axis[a].angle = Jt(pos[a], n + a);
    b.axis[a].rate = Jt(0.0);
    b.axis[a].accel = Jt(0.0);
  }
  const SampleContext ctx{0.0, cfg.temp_ref_C};
  const Vec3<Jt> z = PredictReadings_mV(cfg, th.data(), b, ctx);
  J->resize(3, n);
  H->resize(3, 2);
  for (int r = 0; r < 3; ++r) {
    J->row(r) = z[r].v.head(n).transpose();
    H->row(r) = z[r].v.segment(n, 2).transpose();
  }
}

}  // namespace

Scenario NoiseFreeScenario(const Scenario& s) {
  Scenario q = s;
  q.accel_noise_mV = 0.0;
  q.accel_noise_channel_mV.reset();
  q.angle_noise_rad = 0.0;
  q.quantization_mV = 0.0;
  q.truth_spread.clear();
  if (q.run.yaml_path.empty()) q.run.yaml_path = s.yaml_path;
  if (q.run.data_path.empty()) q.run.data_path = s.yaml_path.empty() ? "scenario" : s.yaml_path;
  return q;
}

Eigen::VectorXd TruthInLayout(const Scenario& s, const ParameterLayout& layout) {
  Eigen::VectorXd theta = NominalTheta(s.run, layout);
  for (int i = 0; i < layout.size(); ++i) {
    const int j = s.truth_layout.IndexOf(layout.info(i).name);
    if (j >= 0) theta[i] = s.truth[j];
  }
  return theta;
}

ObservabilityResult AnalyseScenario(const Scenario& s, const ParameterLayout& layout,
                                    const DesignOptions& opt) {
  const Scenario q = NoiseFreeScenario(s);
  const RunData data = Simulate(q);
  const RunProblem p = BuildRunProblem(q.run, data, layout, opt.epoch_s, opt.derivatives,
                                       nullptr, opt.observability.threads);
  return AnalyseObservability(q.run, p, TruthInLayout(s, layout), opt.observability);
}

DesignPoint EvaluateProfile(const Scenario& s, const HarmonicProfile& profile,
                            const ParameterLayout& layout, const DesignOptions& opt) {
  Scenario q = NoiseFreeScenario(s);
  q.profile = profile;
  const RunData data = Simulate(q);
  const RunProblem p = BuildRunProblem(q.run, data, layout, opt.epoch_s, opt.derivatives,
                                       nullptr, opt.observability.threads);
  const Eigen::MatrixXd I =
      DataInformation(p, TruthInLayout(s, layout), opt.observability.threads);
  const ObservabilityVariant v = MakeVariant(layout, I, p.prior, p.constraints,
                                             ConstraintExprs(q.run), "design",
                                             opt.observability.thresholds);
  return PointFromVariant(v, profile.duration_s);
}

std::vector<std::array<double, 2>> StaticPositions(int count) {
  if (count != 6 && count != 12 && count != 18) {
    throw OptionError("static_positions", "expected 6, 12 or 18, got " + std::to_string(count));
  }
  // Gravity directions u in the platform frame; at rest W = (cos l1,
  // sin l1 sin l2, sin l1 cos l2), so l1 = acos(u_x), l2 = atan2(u_y, u_z).
  std::vector<Eigen::Vector3d> u;
  for (int a = 0; a < 3; ++a) {
    for (double sgn : {1.0, -1.0}) {
      Eigen::Vector3d e = Eigen::Vector3d::Zero();
      e[a] = sgn;
      u.push_back(e);
    }
  }
  if (count >= 12) {
    const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
    for (const auto& pr : pairs) {
      // 12: (+,+) and (-,-) of each pair; 18 adds (+,-) and (-,+).
      const double signs[4][2] = {{1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
      for (int k = 0; k < (count == 18 ? 4 : 2); ++k) {
        Eigen::Vector3d e = Eigen::Vector3d::Zero();
        e[pr[0]] = signs[k][0];
        e[pr[1]] = signs[k][1];
        u.push_back(e.normalized());
      }
    }
  }
  std::vector<std::array<double, 2>> out;
  for (const Eigen::Vector3d& e : u) {
    const double l1 = std::acos(std::max(-1.0, std::min(1.0, e.x())));
    const double l2 = (std::abs(e.y()) + std::abs(e.z()) < 1e-12) ? 0.0 : std::atan2(e.y(), e.z());
    out.push_back({l1, l2});
  }
  return out;
}

Eigen::MatrixXd StaticTestInformation(const RunDescription& run, const ParameterLayout& layout,
                                      const Eigen::VectorXd& theta,
                                      const std::vector<std::array<double, 2>>& positions,
                                      double duration_s, double rate_hz) {
  const ModelConfig cfg = MakeModelConfig(run, layout);
  const int n = layout.size();
  const double samples_per_position =
      std::max(1.0, std::floor(duration_s * rate_hz / static_cast<double>(positions.size())));
  const double s2 = run.noise_mV * run.noise_mV;
  const double sl2 = run.angle_noise_rad * run.angle_noise_rad;
  Eigen::MatrixXd I = Eigen::MatrixXd::Zero(n, n);
  for (const auto& pos : positions) {
    Eigen::MatrixXd J, H;
    if (n + 2 <= 32) {
      StaticJacobians<32>(cfg, theta, pos, &J, &H);
    } else if (n + 2 <= 48) {
      StaticJacobians<48>(cfg, theta, pos, &J, &H);
    } else if (n + 2 <= 64) {
      StaticJacobians<64>(cfg, theta, pos, &J, &H);
    } else {
      throw std::invalid_argument("more than 62 parameters are not supported");
    }
    const Eigen::Matrix3d C =
        s2 / samples_per_position * Eigen::Matrix3d::Identity() + sl2 * H * H.transpose();
    I.noalias() += J.transpose() * Eigen::LDLT<Eigen::Matrix3d>(C).solve(J);
  }
  return 0.5 * (I + I.transpose());
}

DesignPoint EvaluateStatic(const Scenario& s, const ParameterLayout& layout,
                           const std::vector<std::array<double, 2>>& positions, double duration_s,
                           const ObservabilityThresholds& t) {
  const Eigen::MatrixXd I = StaticTestInformation(s.run, layout, TruthInLayout(s, layout),
                                                  positions, duration_s, s.profile.rate_hz);
  const ObservabilityVariant v =
      MakeVariant(layout, I, MakePrior(s.run, layout), ResolveConstraints(s.run, layout),
                  ConstraintExprs(s.run), "static", t);
  return PointFromVariant(v, duration_s);
}

const std::vector<ParameterGroup>& ParameterGroups() {
  static const std::vector<ParameterGroup> groups = {
      {"K", "scale factors K", {kKx, kKy, kKz}},
      {"W0", "zero offsets W0", {kW0x, kW0y, kW0z}},
      {"angles", "non-orthogonality angles",
       {kAlphaX, kAlphaY, kBetaX, kBetaZ, kGammaY, kGammaZ}},
      {"K_ij", "nonlinearity and cross-coupling K_ij",
       {kKxx, kKxy, kKxz, kKyx, kKyy, kKyz, kKzx, kKzy, kKzz}},
      {"bench", "bench angles dpsi, dtheta_c, dlambda2", {kDpsi, kDthetaC, kDlambda2}},
      {"dR", "lever-arm error dR", {kDx2, kDy2, kDz2}},
  };
  return groups;
}

std::vector<int> TargetIndices(const ParameterLayout& layout, const std::string& key) {
  const int i = layout.IndexOf(key);
  if (i >= 0) return {i};
  for (const ParameterGroup& g : ParameterGroups()) {
    if (g.name == key) return g.members;
  }
  std::string groups;
  for (const ParameterGroup& g : ParameterGroups()) groups += (groups.empty() ? "" : ", ") + g.name;
  throw OptionError("targets", "unknown parameter or group '" + key + "' (a parameter name or " +
                                 groups + ")");
}

TargetResult DurationForTarget(const Scenario& s, const ParameterLayout& layout,
                               const std::vector<int>& indices, double sigma_target_si,
                               double t_min, double t_max, const DesignOptions& opt,
                               double resolution) {
  TargetResult r;
  auto worst = [&](double T) {
    HarmonicProfile p = s.profile;
    p.duration_s = T;
    const DesignPoint d = EvaluateProfile(s, p, layout, opt);
    ++r.evaluations;
    double w = 0.0;
    for (int i : indices) w = std::max(w, d.sigma[i]);
    return w;
  };
  double hi_sigma = worst(t_max);
  if (hi_sigma > sigma_target_si) {
    r.duration_s = t_max;
    r.sigma_at_duration = hi_sigma;
    return r;
  }
  r.reached = true;
  const double lo_sigma = worst(t_min);
  if (lo_sigma <= sigma_target_si) {
    r.duration_s = t_min;
    r.sigma_at_duration = lo_sigma;
    return r;
  }
  double lo = t_min, hi = t_max;
  while (hi / lo > 1.0 + resolution) {
    const double mid = std::sqrt(lo * hi);
    const double w = worst(mid);
    if (w <= sigma_target_si) {
      hi = mid;
      hi_sigma = w;
    } else {
      lo = mid;
    }
  }
  r.duration_s = hi;
  r.sigma_at_duration = hi_sigma;
  return r;
}

}  // namespace triadcal

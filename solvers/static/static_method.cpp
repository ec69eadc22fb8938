// The standard static method (static_method.h): positions from still
// intervals, averaged, then one small Ceres problem over theta whose residuals
// call the model of bench_model.h (forward for angles and labels, the exact
// inverse for the gravity-norm fit).
#include "solvers/static/static_method.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>

#include <ceres/ceres.h>

#include "core/model/bench_model.h"
#include "core/io/column_mapping.h"
#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

constexpr int kN = kNumBaseParams;

// ---------------------------------------------------------------------------
// Cost functions, one per kind of position residual (static_method.h).
// ---------------------------------------------------------------------------

// A position on the bench, at rest (lambda' = lambda'' = 0):
//   W_p = C_L2(lambda_p + bench errors)^T (0 - g_L) / g      (docs/method.md)
//   r   = (Readings_mV(theta; W_p) - z_p) / sigma_p          (paper eq. 1)
// PredictReadings_mV is exactly this chain with zero rates; the lever arm
// multiplies rates only, so it drops out.
class AnglePositionCost {
 public:
  AnglePositionCost(const ModelConfig* cfg, const double (&lambda_rad)[2],
                    const Eigen::Vector3d& z_mV, const Eigen::Matrix3d& sqrt_info,
                    const SampleContext& ctx)
      : cfg_(cfg), lambda_{lambda_rad[0], lambda_rad[1]}, z_(z_mV), sqrt_info_(sqrt_info),
        ctx_(ctx) {}

  template <typename T>
  bool operator()(const T* const theta, T* residuals) const {
    BenchAngles<T> bench;  // rates and accelerations 0: at rest
    bench.axis[0].angle = T(lambda_[0]);
    bench.axis[1].angle = T(lambda_[1]);
    const Vec3<T> predicted = PredictReadings_mV(*cfg_, theta, bench, ctx_);
    Eigen::Map<Vec3<T>> r(residuals);
    r = sqrt_info_.cast<T>() * (predicted - z_.cast<T>());
    return true;
  }

  static ceres::CostFunction* Create(const ModelConfig* cfg, const double (&lambda_rad)[2],
                                     const Eigen::Vector3d& z_mV, const Eigen::Matrix3d& sqrt_info,
                                     const SampleContext& ctx) {
    return new ceres::AutoDiffCostFunction<AnglePositionCost, 3, kN>(
        new AnglePositionCost(cfg, lambda_rad, z_mV, sqrt_info, ctx));
  }

 private:
  const ModelConfig* cfg_;
  const double lambda_[2];
  const Eigen::Vector3d z_;
  const Eigen::Matrix3d sqrt_info_;
  const SampleContext ctx_;
};

// A labelled position: the specific force is the declared up direction,
//   r = (Readings_mV(theta; W_p = up_p) - z_p) / sigma_p      (paper eq. 1)
class LabelPositionCost {
 public:
  LabelPositionCost(const ModelConfig* cfg, const Eigen::Vector3d& up,
                    const Eigen::Vector3d& z_mV, const Eigen::Matrix3d& sqrt_info,
                    const SampleContext& ctx)
      : cfg_(cfg), up_(up), z_(z_mV), sqrt_info_(sqrt_info), ctx_(ctx) {}

  template <typename T>
  bool operator()(const T* const theta, T* residuals) const {
    const Vec3<T> W = up_.cast<T>();
    const Vec3<T> predicted = Readings_mV(*cfg_, theta, W, ctx_);
    Eigen::Map<Vec3<T>> r(residuals);
    r = sqrt_info_.cast<T>() * (predicted - z_.cast<T>());
    return true;
  }

  static ceres::CostFunction* Create(const ModelConfig* cfg, const Eigen::Vector3d& up,
                                     const Eigen::Vector3d& z_mV, const Eigen::Matrix3d& sqrt_info,
                                     const SampleContext& ctx) {
    return new ceres::AutoDiffCostFunction<LabelPositionCost, 3, kN>(
        new LabelPositionCost(cfg, up, z_mV, sqrt_info, ctx));
  }

 private:
  const ModelConfig* cfg_;
  const Eigen::Vector3d up_, z_;
  const Eigen::Matrix3d sqrt_info_;
  const SampleContext ctx_;
};

// A pose of unknown orientation: gravity has norm 1 g,
//   W_p = SpecificForceFromReadings_g(theta; z_p)       (exact inverse of eq. 1)
//   r   = (|W_p| - 1) / sigma_|W|,p
class NormPoseCost {
 public:
  NormPoseCost(const ModelConfig* cfg, const Eigen::Vector3d& z_mV, double inv_sigma,
               const SampleContext& ctx)
      : cfg_(cfg), z_(z_mV), inv_sigma_(inv_sigma), ctx_(ctx) {}

  template <typename T>
  bool operator()(const T* const theta, T* residuals) const {
    const Vec3<T> z = z_.cast<T>();
    const Vec3<T> W = SpecificForceFromReadings_g(*cfg_, theta, z, ctx_);
    residuals[0] = (W.norm() - T(1.0)) * T(inv_sigma_);
    return true;
  }

  static ceres::CostFunction* Create(const ModelConfig* cfg, const Eigen::Vector3d& z_mV,
                                     double inv_sigma, const SampleContext& ctx) {
    return new ceres::AutoDiffCostFunction<NormPoseCost, 1, kN>(
        new NormPoseCost(cfg, z_mV, inv_sigma, ctx));
  }

 private:
  const ModelConfig* cfg_;
  const Eigen::Vector3d z_;
  const double inv_sigma_;
  const SampleContext ctx_;
};

// Weak priors (priors.h): r_i = (theta_i - mean_i) / sigma_i. Held parameters
// sit at their mean and contribute 0.
class PriorCost : public ceres::SizedCostFunction<kN, kN> {
 public:
  explicit PriorCost(const Prior& p) : mean_(p.mean.head(kN)), sigma_(p.sigma.head(kN)) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    for (int i = 0; i < kN; ++i) residuals[i] = (parameters[0][i] - mean_[i]) / sigma_[i];
    if (jacobians && jacobians[0]) {
      Eigen::Map<Eigen::Matrix<double, kN, kN, Eigen::RowMajor>> J(jacobians[0]);
      J.setZero();
      for (int i = 0; i < kN; ++i) J(i, i) = 1.0 / sigma_[i];
    }
    return true;
  }

 private:
  const Eigen::VectorXd mean_, sigma_;
};

// A constraint of run.yaml: r = (c . theta - value) / sigma.
class ConstraintCost : public ceres::SizedCostFunction<1, kN> {
 public:
  ConstraintCost(const Eigen::VectorXd& c, double value, double sigma)
      : c_(c), value_(value), sigma_(sigma) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override {
    const Eigen::Map<const Eigen::VectorXd> theta(parameters[0], kN);
    residuals[0] = (c_.dot(theta) - value_) / sigma_;
    if (jacobians && jacobians[0]) {
      for (int i = 0; i < kN; ++i) jacobians[0][i] = c_[i] / sigma_;
    }
    return true;
  }

 private:
  const Eigen::VectorXd c_;
  const double value_, sigma_;
};

// ---------------------------------------------------------------------------

std::string Short(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", x);
  return buf;
}

bool AnglesRecorded(const RunDescription& run) {
  return !(SourceOf(run, "lambda1").constant && SourceOf(run, "lambda2").constant);
}

std::string JoinSet(const std::set<std::string>& s, std::size_t max_items = 8) {
  std::string out;
  std::size_t n = 0;
  for (const std::string& x : s) {
    if (n++ == max_items) return out + ", ...";
    out += (out.empty() ? "" : ", ") + Excerpt(x, 40);
  }
  return out;
}

// A direction for messages: "+x" for an axis, "[0.7071, 0, 0.7071]" otherwise.
std::string DirectionText(const Eigen::Vector3d& v) {
  for (int i = 0; i < 3; ++i) {
    if (std::abs(std::abs(v[i]) - 1.0) < 1e-12) {
      return std::string(v[i] > 0 ? "+" : "-") + "xyz"[i];
    }
  }
  return "[" + Short(v[0]) + ", " + Short(v[1]) + ", " + Short(v[2]) + "]";
}

// The signed axis nearest a direction ("-x").
std::string NearestAxis(const Eigen::Vector3d& v) {
  Eigen::Index i = 0;
  v.cwiseAbs().maxCoeff(&i);
  return std::string(v[i] >= 0 ? "+" : "-") + "xyz"[i];
}

// The parameters held at nominal for this reference, with their reasons.
std::vector<HeldParameter> HeldFor(StaticReference ref, const std::vector<std::string>& fixed,
                                   const ParameterLayout& layout) {
  std::map<std::string, std::string> held;
  for (const char* n : {"dx2", "dy2", "dz2"}) {
    held[n] = "at rest the readings do not depend on the lever arm";
  }
  if (ref != StaticReference::kAngles) {
    const std::string why = ref == StaticReference::kLabels
                                ? "no bench: the orientation of each position comes from its label"
                                : "no bench and no orientation reference";
    for (const char* n : {"dpsi", "dtheta_c", "dlambda2"}) held[n] = why;
  }
  if (ref == StaticReference::kNone) {
    for (const char* n : {"alpha_y", "beta_z", "gamma_z"}) {
      held[n] =
          "triad frame of the gravity-norm fit: x along the x accelerometer, y in the plane of "
          "the x and y accelerometers (a common rotation of the triad leaves |W| unchanged)";
    }
    for (int i = kKxx; i <= kKzz; ++i) {
      held[layout.info(i).name] = "not in the gravity-norm model (scale, bias, non-orthogonality)";
    }
  }
  for (const std::string& name : fixed) {
    if (name == "K_ij") {
      for (int i = kKxx; i <= kKzz; ++i) held[layout.info(i).name] = "held at nominal by --fix";
      continue;
    }
    const int i = layout.IndexOf(name);
    if (i < 0 || i >= kN) {
      throw OptionError("fixed", "unknown parameter '" + name +
                                     "' (names of docs/file-formats.md, or K_ij for all nine)");
    }
    held[name] = "held at nominal by --fix";
  }
  std::vector<HeldParameter> out;
  for (int i = 0; i < kN; ++i) {
    auto it = held.find(layout.info(i).name);
    if (it != held.end()) out.push_back({it->first, it->second});
  }
  return out;
}

// Averages the still samples of each position.
std::vector<StaticPosition> MakePositions(const RunDescription& run, const RunData& data,
                                          StaticReference ref, const StillResult& still) {
  std::vector<StaticPosition> out;
  std::map<std::string, std::size_t> by_label;
  for (const StillInterval& iv : still.intervals) {
    StaticPosition* p = nullptr;
    if (ref == StaticReference::kLabels) {
      auto it = by_label.find(iv.label);
      if (it == by_label.end()) {
        by_label[iv.label] = out.size();
        out.emplace_back();
        out.back().name = iv.label;
        out.back().up = ImuToPlatform(run, PositionsOf(run).at(iv.label));
      }
      p = &out[by_label[iv.label]];
    } else {
      out.emplace_back();
      out.back().name = "P" + std::to_string(out.size());
      p = &out.back();
    }
    p->intervals.push_back(iv);
  }
  for (StaticPosition& p : out) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
    const Eigen::Vector3d ref_mV = data.readings_mV(p.intervals.front().begin);
    double lambda_sum[2] = {0.0, 0.0};
    for (const StillInterval& iv : p.intervals) {
      for (std::size_t k = iv.begin; k < iv.end; ++k) {
        const Eigen::Vector3d d = data.readings_mV(k) - ref_mV;
        sum += d;
        sum2 += d.cwiseProduct(d);
        for (int i = 0; i < 2; ++i) lambda_sum[i] += data.lambda_rad[i][k];
      }
      p.samples += iv.samples();
      p.duration_s += iv.duration_s();
    }
    const double n = static_cast<double>(p.samples);
    const Eigen::Vector3d mean_d = sum / n;
    p.mean_mV = ref_mV + mean_d;
    p.std_mV = ((sum2 / n - mean_d.cwiseProduct(mean_d)) * (n / std::max(1.0, n - 1.0)))
                   .cwiseMax(0.0)
                   .cwiseSqrt();
    for (int i = 0; i < 2; ++i) p.lambda_rad[i] = lambda_sum[i] / n;
  }
  return out;
}

// Mean time and temperature of a position (for the drift effects; unused by
// the base model but kept honest).
SampleContext ContextOf(const RunData& data, const StaticPosition& p) {
  double t = 0.0, temp = 0.0;
  for (const StillInterval& iv : p.intervals) {
    for (std::size_t k = iv.begin; k < iv.end; ++k) {
      t += data.t_s[k];
      if (data.has_temp()) temp += data.temp_C[k];
    }
  }
  return {t / p.samples, data.has_temp() ? temp / p.samples : 0.0};
}

// Whitening of a position's mean reading (static_method.h):
//   Sigma_p = noise^2 / N_p I + sigma_o^2 D (I - u u^T) D,   D = diag(K nominal)
// u the nominal direction of gravity in the triad frame (the label's up, or
// C_L2(lambda_p)^T e_x with the nominal bench), sigma_o the placement error:
// a small rotation delta of the position moves W by delta x u, i.e. across u.
// Returns S with S^T S = Sigma_p^-1.
Eigen::Matrix3d PositionSqrtInfo(const ModelConfig& cfg, const Eigen::VectorXd& theta_nominal,
                                 const StaticPosition& p, StaticReference reference,
                                 double noise_mV, const StaticOptions& options) {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity() * (noise_mV * noise_mV / p.samples);
  if (options.placement_sigma_rad > 0.0) {
    Eigen::Vector3d u = p.up;
    if (reference == StaticReference::kAngles) {
      BenchAngles<double> bench;
      bench.axis[0].angle = p.lambda_rad[0];
      bench.axis[1].angle = p.lambda_rad[1];
      const BenchMotion<double> m = ComputeBenchMotion(cfg, theta_nominal.data(), bench);
      u = SpecificForce_g(cfg, m.C_L2, Eigen::Vector3d::Zero().eval());
    }
    const Eigen::Vector3d K = theta_nominal.segment<3>(kKx);
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - u * u.transpose();
    const double s2 = options.placement_sigma_rad * options.placement_sigma_rad;
    cov += s2 * K.asDiagonal() * P * K.asDiagonal();
  }
  const Eigen::Matrix3d L = cov.llt().matrixL();
  return L.triangularView<Eigen::Lower>().solve(Eigen::Matrix3d::Identity());
}

}  // namespace

const char* ReferenceName(StaticReference r) {
  switch (r) {
    case StaticReference::kAngles:
      return "angles";
    case StaticReference::kLabels:
      return "labels";
    case StaticReference::kNone:
      return "none";
  }
  return "?";
}

StaticReference ChooseReference(const RunDescription& run, const RunData& data,
                                const std::string& requested) {
  const bool angles = AnglesRecorded(run);
  const bool labels = data.has_label();
  if (requested == "auto") {
    return angles ? StaticReference::kAngles
                  : labels ? StaticReference::kLabels : StaticReference::kNone;
  }
  if (requested == "angles") {
    if (!angles) {
      throw InputError(run.yaml_path +
                       ": columns.lambda1/lambda2 are constants: no bench angles in this run");
    }
    return StaticReference::kAngles;
  }
  if (requested == "labels") {
    if (!labels) {
      throw InputError(run.yaml_path + ": no label column (columns.label) in this run");
    }
    return StaticReference::kLabels;
  }
  if (requested == "none") return StaticReference::kNone;
  throw OptionError("reference",
                    "expected auto, angles, labels or none, got '" + requested + "'");
}

namespace {

// Step 1: the still intervals of the run and the positions they average to.
void FindPositions(const RunDescription& run, const RunData& data, const StaticOptions& options,
                   StaticResult* r) {
  std::set<std::string> position_labels;
  const StillTest test = r->reference == StaticReference::kAngles ? StillTest::kAngleRates
                                                                  : StillTest::kReadingVariance;
  if (r->reference == StaticReference::kLabels) {
    std::set<std::string> in_data(data.label.begin(), data.label.end());
    std::set<std::string> declared, undeclared;
    for (const auto& [label, up] : PositionsOf(run)) {
      declared.insert(label);
      if (in_data.count(label) && !up.isZero()) position_labels.insert(label);
    }
    for (const std::string& label : in_data) {
      if (!declared.count(label)) undeclared.insert(label);
    }
    if (position_labels.empty()) {
      throw InputError(run.yaml_path + ": positions: none of the position labels (" +
                       JoinSet(declared) + ") occurs in column '" + LabelSource(run) +
                       "' (it has: " + JoinSet(in_data) + ")");
    }
    // A label without a direction whose samples hold still data is a position
    // the run does not declare (a typo, another convention): dropping it
    // silently loses an orientation (Kx sigma 3.4 instead of 0.03 mV/g). Labels
    // of motion (no still interval) are not positions; `LABEL: none` says so.
    if (!undeclared.empty()) {
      const StillResult probe = FindStillIntervals(data, test, run.noise_mV, run.angle_noise_rad,
                                                   undeclared, options.still);
      std::map<std::string, double> still_s;
      for (const StillInterval& iv : probe.intervals) still_s[iv.label] += iv.duration_s();
      if (!still_s.empty()) {
        const auto most =
            std::max_element(still_s.begin(), still_s.end(),
                             [](const auto& x, const auto& y) { return x.second < y.second; });
        throw InputError(run.yaml_path + ": positions: label '" + Excerpt(most->first, 40) +
                         "' of column '" + LabelSource(run) + "' holds " + Short(most->second) +
                         " s of still data but is no declared position (positions: " +
                         JoinSet(declared) + "): give the direction that points up in it, or `" +
                         Excerpt(most->first, 40) + ": none` if it is no position");
      }
    }
  }
  r->still = FindStillIntervals(data, test, run.noise_mV, run.angle_noise_rad, position_labels,
                                options.still);
  r->positions = MakePositions(run, data, r->reference, r->still);
  if (r->positions.empty()) {
    throw InputError(run.data_path + ": no still interval of at least " +
                     Short(options.still.min_still_s) + " s found (" +
                     (test == StillTest::kAngleRates
                          ? "angle rates below " + Short(r->still.threshold) +
                                " deg/s; check the still-rate threshold"
                          : "reading std below " + Short(r->still.threshold) +
                                " mV; check triad.noise_mV or the noise factor") +
                     ")");
  }
}

// Labels against the data: the gravity direction of each labelled position's
// mean reading (at the nominal scale and bias) must be within 45 deg of the
// direction declared up. Labels swapped in the data (x_p where x_a was held)
// otherwise fit "perfectly" with Kx = -171.5 mV/g.
void CheckLabelsAgreeWithData(const RunDescription& run, const Eigen::VectorXd& theta_nominal,
                              const StaticResult& r) {
  if (r.reference != StaticReference::kLabels) return;
  const double cos_bound = std::cos(kMaxLabelDisagreementDeg * kDegToRad);
  for (const StaticPosition& p : r.positions) {
    Eigen::Vector3d u;
    for (int i = 0; i < 3; ++i) {
      u[i] = (p.mean_mV[i] - theta_nominal[kW0x + i]) / theta_nominal[kKx + i];
    }
    if (!(u.norm() > 0.0)) continue;
    u.normalize();
    const double cos_angle = u.dot(p.up);
    if (cos_angle >= cos_bound) continue;
    // Which declared position the data look like, for the message.
    std::string like;
    double best = cos_bound;
    for (const StaticPosition& q : r.positions) {
      if (q.name != p.name && u.dot(q.up) > best) {
        best = u.dot(q.up);
        like = q.name;
      }
    }
    const double angle_deg = std::acos(std::clamp(cos_angle, -1.0, 1.0)) / kDegToRad;
    throw InputError(run.yaml_path + ": positions." + Excerpt(p.name, 40) + ": declared " +
                     DirectionText(PositionsOf(run).at(p.name)) +
                     " up, but its still readings have gravity along " + NearestAxis(u) +
                     " (platform axes, " + Short(angle_deg) + " deg away; bound " +
                     Short(kMaxLabelDisagreementDeg) + " deg): " +
                     (like.empty() ? std::string("a wrong label or direction?")
                                   : "are the labels " + Excerpt(p.name, 40) + " and " +
                                         Excerpt(like, 40) + " swapped?"));
  }
}

// The Ceres problem over theta and its residual blocks: data first (one per
// position), then the constraints and the prior.
struct StaticProblem {
  ceres::Problem problem;
  Eigen::VectorXd theta;  // SI, starts at the nominal values
  std::vector<int> held_idx, free_idx;
  std::vector<ceres::ResidualBlockId> data_blocks, other_blocks;
  bool held(int i) const {
    return std::find(held_idx.begin(), held_idx.end(), i) != held_idx.end();
  }
};

// sigma of |W| of a gravity-norm pose from the reading noise, at the nominal
// scale and bias: the noise of each reading projected on the direction of W.
double NormSigma(const Eigen::VectorXd& theta_nominal, const StaticPosition& p, double noise_mV) {
  Eigen::Vector3d u = p.mean_mV - theta_nominal.segment<3>(kW0x);
  for (int i = 0; i < 3; ++i) u[i] /= theta_nominal[kKx + i];
  const double un = u.norm() > 0 ? u.norm() : 1.0;
  double var = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double g = u[i] / un * noise_mV / theta_nominal[kKx + i];
    var += g * g;
  }
  return std::sqrt(var) / std::sqrt(static_cast<double>(p.samples));
}

// Step 2a: one residual block per position, of the reference's kind.
void AddPositionResiduals(const ModelConfig& cfg, const RunDescription& run, const RunData& data,
                          const StaticOptions& options, StaticProblem* sp, StaticResult* r) {
  const double noise = run.noise_mV;
  for (const StaticPosition& p : r->positions) {
    const SampleContext ctx = ContextOf(data, p);
    ceres::CostFunction* cost = nullptr;
    if (r->reference == StaticReference::kAngles) {
      cost = AnglePositionCost::Create(
          &cfg, p.lambda_rad, p.mean_mV,
          PositionSqrtInfo(cfg, sp->theta, p, r->reference, noise, options), ctx);
      r->data_residuals += 3;
    } else if (r->reference == StaticReference::kLabels) {
      cost = LabelPositionCost::Create(
          &cfg, p.up, p.mean_mV, PositionSqrtInfo(cfg, sp->theta, p, r->reference, noise, options),
          ctx);
      r->data_residuals += 3;
    } else {
      cost = NormPoseCost::Create(&cfg, p.mean_mV, 1.0 / NormSigma(sp->theta, p, noise), ctx);
      r->data_residuals += 1;
    }
    sp->data_blocks.push_back(sp->problem.AddResidualBlock(cost, nullptr, sp->theta.data()));
  }
}

// Step 2b: the constraints of run.yaml that touch a free parameter, the weak
// priors, and the held parameters fixed by a SubsetManifold.
void AddPriorAndConstraints(const RunDescription& run, StaticProblem* sp, StaticResult* r) {
  const ParameterLayout& layout = r->layout;
  for (const Constraint& k : run.constraints) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(kN);
    bool any_free = false;
    for (const auto& [name, coef] : k.terms) {
      const int i = layout.IndexOf(name);
      if (i < 0 || i >= kN) {
        throw InputError(run.yaml_path + ": constraints: '" + k.expr + "' names '" + name +
                         "', which the static method does not estimate");
      }
      c[i] += coef;
      any_free = any_free || !sp->held(i);
    }
    if (!any_free) {
      r->constraints_ignored.push_back(k.expr);
      continue;
    }
    r->constraints_used.push_back(k.expr);
    sp->other_blocks.push_back(sp->problem.AddResidualBlock(
        new ConstraintCost(c, k.value_si, k.sigma_si), nullptr, sp->theta.data()));
  }
  sp->other_blocks.push_back(
      sp->problem.AddResidualBlock(new PriorCost(r->prior), nullptr, sp->theta.data()));
  if (!sp->held_idx.empty()) {
    sp->problem.SetManifold(sp->theta.data(), new ceres::SubsetManifold(kN, sp->held_idx));
  }
}

// Step 3: Levenberg-Marquardt to tight tolerances (27 parameters, dense).
void Solve(const StaticOptions& options, StaticProblem* sp, StaticResult* r) {
  ceres::Solver::Options sopt;
  sopt.linear_solver_type = ceres::DENSE_QR;
  sopt.max_num_iterations = options.max_iterations;
  sopt.function_tolerance = 1e-15;
  sopt.gradient_tolerance = 1e-15;
  sopt.parameter_tolerance = 1e-14;
  sopt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(sopt, &sp->problem, &summary);
  r->converged = summary.termination_type == ceres::CONVERGENCE;
  r->iterations = static_cast<int>(summary.iterations.size()) - 1;
  r->theta = sp->theta;
}

// Step 4: covariance from the whitened Jacobian at the solution (tangent
// columns = free parameters in increasing index order, SubsetManifold), by a
// pseudo-inverse; chi2, its degrees of freedom (data residuals minus the
// effective number of parameters) and the sigma scale.
void EstimateCovariance(StaticProblem* sp, StaticResult* r) {
  ceres::Problem::EvaluateOptions eopt;
  eopt.residual_blocks = sp->data_blocks;
  eopt.residual_blocks.insert(eopt.residual_blocks.end(), sp->other_blocks.begin(),
                              sp->other_blocks.end());
  std::vector<double> residuals;
  ceres::CRSMatrix crs;
  sp->problem.Evaluate(eopt, nullptr, &residuals, nullptr, &crs);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k) J(row, crs.cols[k]) = crs.values[k];
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinV);
  const Eigen::VectorXd s = svd.singularValues();
  Eigen::VectorXd s_inv2 = Eigen::VectorXd::Zero(s.size());
  for (int i = 0; i < s.size(); ++i) {
    if (s[i] > 1e-12 * s[0]) s_inv2[i] = 1.0 / (s[i] * s[i]);
  }
  const Eigen::MatrixXd cov_free = svd.matrixV() * s_inv2.asDiagonal() * svd.matrixV().transpose();
  const std::vector<int>& free_idx = sp->free_idx;
  r->cov_declared = Eigen::MatrixXd::Zero(kN, kN);
  for (std::size_t a = 0; a < free_idx.size(); ++a) {
    for (std::size_t b = 0; b < free_idx.size(); ++b) {
      r->cov_declared(free_idx[a], free_idx[b]) = cov_free(a, b);
    }
  }
  const Eigen::MatrixXd Jd = J.topRows(r->data_residuals);
  r->effective_parameters = (Jd * cov_free * Jd.transpose()).trace();
  for (int i = 0; i < r->data_residuals; ++i) r->chi2 += residuals[i] * residuals[i];
  r->dof = r->data_residuals - r->effective_parameters;
  if (r->dof >= 0.5) {
    r->chi2_per_dof = r->chi2 / r->dof;
    r->sigma_scale = std::max(1.0, std::sqrt(r->chi2_per_dof));
    r->sigma_source = r->chi2_per_dof > 1.0 ? "residual scatter" : "declared noise";
  } else {
    r->sigma_source = "declared noise (no degrees of freedom left to measure the scatter)";
  }
  r->cov = r->cov_declared * (r->sigma_scale * r->sigma_scale);
  r->weak = FindWeakDirections(r->layout, r->cov_declared, r->prior.sigma);
  r->not_separable = ParametersIn(r->weak);
}

// Step 5: the residual of every position at the solution, in mV and mg (the
// norm residual for the gravity-norm fit), and their RMS.
void PositionResiduals(const ModelConfig& cfg, const RunData& data, StaticResult* r) {
  const Eigen::VectorXd& theta = r->theta;
  double sum2 = 0.0;
  int count = 0;
  for (StaticPosition& p : r->positions) {
    const SampleContext ctx = ContextOf(data, p);
    p.W_g = SpecificForceFromReadings_g(cfg, theta.data(), Eigen::Vector3d(p.mean_mV), ctx);
    p.norm_residual_mg = (p.W_g.norm() - 1.0) * 1000.0;
    if (r->reference == StaticReference::kNone) {
      sum2 += p.norm_residual_mg * p.norm_residual_mg;
      ++count;
      continue;
    }
    if (r->reference == StaticReference::kAngles) {
      BenchAngles<double> bench;
      bench.axis[0].angle = p.lambda_rad[0];
      bench.axis[1].angle = p.lambda_rad[1];
      p.predicted_mV = PredictReadings_mV(cfg, theta.data(), bench, ctx);
    } else {
      p.predicted_mV = Readings_mV(cfg, theta.data(), Eigen::Vector3d(p.up), ctx);
    }
    p.residual_mV = p.mean_mV - p.predicted_mV;
    for (int i = 0; i < 3; ++i) {
      p.residual_mg[i] = p.residual_mV[i] / theta[kKx + i] * 1000.0;
      sum2 += p.residual_mg[i] * p.residual_mg[i];
      ++count;
    }
  }
  r->residual_rms_mg = std::sqrt(sum2 / std::max(1, count));
}

}  // namespace

StaticResult SolveStatic(const RunDescription& run, const RunData& data,
                         StaticReference reference, const StaticOptions& options) {
  StaticResult r;
  r.reference = reference;
  r.layout = ParameterLayout({}, /*gyro=*/false, ReadingsUnit(run));  // units of the readings
  r.held = HeldFor(reference, options.fixed, r.layout);
  const ModelConfig cfg = MakeModelConfig(run, r.layout, data);

  FindPositions(run, data, options, &r);

  r.prior = MakePrior(run, r.layout);
  StaticProblem sp;
  sp.theta = NominalTheta(run, r.layout);
  CheckLabelsAgreeWithData(run, sp.theta, r);
  for (const HeldParameter& h : r.held) sp.held_idx.push_back(r.layout.IndexOf(h.name));
  for (int i = 0; i < kN; ++i) {
    if (!sp.held(i)) sp.free_idx.push_back(i);
  }
  AddPositionResiduals(cfg, run, data, options, &sp, &r);
  AddPriorAndConstraints(run, &sp, &r);

  Solve(options, &sp, &r);
  EstimateCovariance(&sp, &r);
  PositionResiduals(cfg, data, &r);
  return r;
}

}  // namespace triadcal

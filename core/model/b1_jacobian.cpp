#include "core/model/b1_jacobian.h"
#include "core/model/sparse_jets.h"

#include <ceres/jet.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>

namespace triadcal {
namespace {

constexpr int kMaxParams = 64;

// Jets of the angle stage: at most its parameters (latency, encoder
// harmonic, angle scale: 1 + 4 + 2).
constexpr int kJetParams = 8;

// Jets of the bench motion behind the size effect: the geometric parameters
// the motion depends on (dpsi, d, eps), the bench zeros (dtheta_c,
// dlambda2) and the angle-stage parameters: at most 3 + 2 + 7.
constexpr int kGeometryJet = 3 + 2 + kJetParams - 1;

// Rows of theta derivatives, on the stack (one sample's work allocates nothing).
using ThetaRow = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxParams>;
using ThetaRows3 = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxParams>;

// [v x]
Mat3<double> Cross(const Vec3<double>& v) {
  Mat3<double> m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// dW/dp of the specific force [g] at a point p fixed in frame 2: its
// acceleration is affine in q = C_L2 p with the linear part w' x q + w x (w x q)
// (MotionOfPoint), so dW/dp = C_L2^T ([w' x] + [w x]^2) C_L2 / g.
Mat3<double> ForceGradientByPoint(const Mat3<double>& C_L2, const Vec3<double>& w,
                                  const Vec3<double>& dw, double g) {
  return C_L2.transpose() * (Cross(dw) + Cross(w) * Cross(w)) * C_L2 / g;
}

// Misalignment angle at M(i, j), i != j, and its sign there (bench_model.h).
struct MisalignmentEntry {
  int param;
  double sign;
};
constexpr MisalignmentEntry kMisalignment[3][3] = {{{-1, 0.0}, {kAlphaY, -1.0}, {kBetaZ, 1.0}},
                                                   {{kAlphaX, 1.0}, {-1, 0.0}, {kGammaZ, -1.0}},
                                                   {{kBetaX, -1.0}, {kGammaY, 1.0}, {-1, 0.0}}};

// Reading i of the readings model at W (bench_model.h Readings_mV) without
// its zero offset, its gradient by W, and (added into *row, when given) its
// derivatives by the sensor parameters times `weight`.
double ReadingWithoutOffset(const ParameterLayout& layout, const double* th, int i,
                            const Vec3<double>& W, Eigen::RowVector3d* grad_W, double weight,
                            ThetaRow* row_or_null) {
  const Mat3<double> M = MisalignmentMatrix(th);
  const Mat3<double> K = NonlinearityMatrix(th);
  const int o_a = layout.offset(Effect::kScaleAsymmetry);
  const int o_q = layout.offset(Effect::kCrossQuadratic);
  double u = M.row(i).dot(W) + W[i] * K.row(i).dot(W);
  Eigen::RowVector3d du = M.row(i) + W[i] * K.row(i);
  du[i] += K.row(i).dot(W);
  if (o_q >= 0) {
    u += CrossQuadraticTerm(th + o_q, i, W);
    du += CrossQuadraticGradient(th + o_q, i, W);
  }
  const double sgn = u < 0.0 ? -1.0 : 1.0;
  const double s = th[kKx + i] + (o_a >= 0 ? sgn * th[o_a + i] : 0.0);
  *grad_W = s * du;
  if (!row_or_null) return s * u;
  ThetaRow& row = *row_or_null;
  row[kKx + i] += weight * u;
  if (o_a >= 0) row[o_a + i] += weight * sgn * u;
  for (int j = 0; j < 3; ++j) {
    const MisalignmentEntry& m = kMisalignment[i][j];
    if (m.param >= 0) row[m.param] += weight * s * m.sign * W[j];
    row[kKxx + 3 * i + j] += weight * s * W[i] * W[j];
  }
  if (o_q >= 0) {
    const int j = kCrossAxes[i][0], k = kCrossAxes[i][1];
    row[o_q + 2 * i] += weight * s * (W[j] * W[j] - W[k] * W[k]);
    row[o_q + 2 * i + 1] += weight * s * W[j] * W[k];
  }
  return s * u;
}

}  // namespace

bool B1HasAnalyticJacobian(const ParameterLayout& layout) {
  if (layout.size() > kMaxParams || layout.StageParams(EffectStage::kAngle).size() > kJetParams) return false;
  for (Effect e : layout.effects()) {
    if (!GetEffectSpec(e).b1_analytic_jacobian) return false;
  }
  return true;
}

// flatten: everything they call is inlined into them. GCC left the 9-wide
// Jets' arithmetic of the size effect as calls (a fit with size_effect on the
// real slow run: solve 1.97 -> 1.19 s, the same numbers). The angle stage and
// the size effect are apart from the base model's path (noinline): flattened
// into it they made one 94-kB function with an 18-kB stack frame, that the
// base model ran through for every sample. Not under the address sanitizer:
// instrumenting the flattened function took GCC over 14 minutes.
#if defined(__SANITIZE_ADDRESS__)
#define TRIADCAL_FLATTEN
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TRIADCAL_FLATTEN
#endif
#endif
#ifndef TRIADCAL_FLATTEN
#define TRIADCAL_FLATTEN __attribute__((flatten))
#endif
#if defined(__GNUC__)
#define TRIADCAL_NOINLINE __attribute__((noinline))
#else
#define TRIADCAL_NOINLINE
#endif

namespace {

// Angle stage: the bench angles from the recorded ones (*b), and the
// derivatives of their six quantities (angle, rate, acceleration of each
// axis) by the angle-stage parameters (*db, Jets over those alone, N slots:
// the loop after round 1 of diagnose carries angle_latency alone).
template <int N>
TRIADCAL_FLATTEN TRIADCAL_NOINLINE void AngleStageWith(const ModelConfig& cfg, const double* th,
                                                       const BenchAngles<double>& rec,
                                                       BenchAngles<double>* b,
                                                       Eigen::Matrix<double, 6, kJetParams>* db) {
  using AngleJet = ceres::Jet<double, N>;
  const std::vector<int>& angle_params = cfg.layout.StageParams(EffectStage::kAngle);
  // The angle stage reads only its own parameters (BenchAnglesFromRecorded).
  const int count = static_cast<int>(angle_params.size());
  const SparseJets<AngleJet, kMaxParams> t(th, angle_params.data(), count, count);
  const BenchAngles<AngleJet> bj = BenchAnglesFromRecorded<AngleJet>(cfg, t.data(), rec);
  for (int i = 0; i < 2; ++i) {
    const AxisState<AngleJet>& a = bj.axis[i];
    b->axis[i] = AxisState<double>{a.angle.a, a.rate.a, a.accel.a};
    db->block<1, N>(3 * i, 0) = a.angle.v.transpose();
    db->block<1, N>(3 * i + 1, 0) = a.rate.v.transpose();
    db->block<1, N>(3 * i + 2, 0) = a.accel.v.transpose();
  }
}

void AngleStage(const ModelConfig& cfg, const double* th, const BenchAngles<double>& rec,
                BenchAngles<double>* b, Eigen::Matrix<double, 6, kJetParams>* db) {
  const std::size_t count = cfg.layout.StageParams(EffectStage::kAngle).size();
  if (count <= 1) {
    AngleStageWith<1>(cfg, th, rec, b, db);
  } else if (count <= 4) {
    AngleStageWith<4>(cfg, th, rec, b, db);
  } else {
    AngleStageWith<kJetParams>(cfg, th, rec, b, db);
  }
}

// The size effect's correction of the readings and its derivatives.
struct SizeCorrection {
  Eigen::Vector3d z;  // the readings less D
  ThetaRows3 dD;      // 3 x n, empty without the size effect or at r = 0
  Eigen::Matrix3d dD_r = Eigen::Matrix3d::Zero();  // at r = 0: row i is dD_i/dr_i
  bool r_zero = false;
};

// The size effect away from r = 0 (SizeEffect), with Jets of N slots:
// dpsi, d, eps (those in the layout), dtheta_c, dlambda2, then the
// angle-stage parameters, which reach the motion through the bench angles'
// derivatives db. The points' positions (O at R, accelerometer i at R +
// r_i) enter their accelerations linearly, so the columns of R and r are by
// ForceGradientByPoint.
template <int N>
TRIADCAL_FLATTEN TRIADCAL_NOINLINE void SizeEffectAwayFromZero(
    const ModelConfig& cfg, const double* th, const BenchAngles<double>& b,
    const Eigen::Matrix<double, 6, kJetParams>& db, SizeCorrection* out) {
  using GeoJet = ceres::Jet<double, N>;
  const ParameterLayout& layout = cfg.layout;
  const int n = layout.size();
  const double g = cfg.g_mps2;
  const std::vector<int>& angle_params = layout.StageParams(EffectStage::kAngle);
  const int n_angle = static_cast<int>(angle_params.size());
  const int o_s = layout.offset(Effect::kSizeEffect);
  // The motion reads dpsi, d, eps (seeded), the bench zeros and the lever
  // arm (ComputeBenchMotion, SensingPoint_m of O).
  std::array<int, 8> read = {kDpsi, -1, -1};
  int n_geo = 1;
  const int o_d = layout.offset(Effect::kAxisNonintersection);
  if (o_d >= 0) read[n_geo++] = o_d;
  const int o_e = layout.offset(Effect::kAxisNonperpendicularity);
  if (o_e >= 0) read[n_geo++] = o_e;
  int n_read = n_geo;
  for (int i : {kDthetaC, kDlambda2, kDx2, kDy2, kDz2}) read[n_read++] = i;
  const SparseJets<GeoJet, kMaxParams> t(th, read.data(), n_read, n_geo);
  // The bench angles: angle l_i enters as l_i + dtheta_c (l_i + dlambda2),
  // and every quantity moves with the angle-stage parameters by db.
  const int slot_c = n_geo, slot_a = n_geo + 2;
  BenchAngles<GeoJet> bj;
  for (int i = 0; i < 2; ++i) {
    AxisState<GeoJet>& a = bj.axis[i];
    a.angle = GeoJet(b.axis[i].angle);
    a.rate = GeoJet(b.axis[i].rate);
    a.accel = GeoJet(b.axis[i].accel);
    a.angle.v[slot_c + i] = 1.0;
    for (int q = 0; q < n_angle; ++q) {
      a.angle.v[slot_a + q] = db(3 * i, q);
      a.rate.v[slot_a + q] = db(3 * i + 1, q);
      a.accel.v[slot_a + q] = db(3 * i + 2, q);
    }
  }
  const BenchMotion<GeoJet> m = ComputeBenchMotion(cfg, t.data(), bj);
  auto value = [](const Vec3<GeoJet>& v) { return Vec3<double>(v[0].a, v[1].a, v[2].a); };
  Mat3<double> C_L2;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) C_L2(r, c) = m.C_L2(r, c).a;
  const Mat3<double> dW_dp = ForceGradientByPoint(C_L2, value(m.w1_L) + value(m.w12_L),
                                                  value(m.dw1_L) + value(m.dw12_L), g);
  // W at O by the motion; at accelerometer i, W_O + (w2' x r_i + w2 x (w2 x r_i)) / g
  // with w2, w2' the rate of frame 2 and its derivative in frame 2 (rigid
  // body: MotionOfPoint in frame 2; r_i = p_i - p_O fixed in it).
  const Vec3<GeoJet> Wj_O =
      SpecificForce_g(cfg, m.C_L2, MotionOfPoint(m, SensingPoint_m(cfg, t.data(), 0)).a_L);
  const Vec3<GeoJet> w2 = m.C_L2.transpose() * (m.w1_L + m.w12_L);
  const Vec3<GeoJet> dw2 = m.C_L2.transpose() * (m.dw1_L + m.dw12_L);
  auto split = [](const Vec3<GeoJet>& Wj, Vec3<double>* W_p, Eigen::Matrix<double, 3, N>* dW_p) {
    for (int r = 0; r < 3; ++r) {
      (*W_p)[r] = Wj[r].a;
      dW_p->row(r) = Wj[r].v.transpose();
    }
  };
  Vec3<double> W_O;
  Eigen::Matrix<double, 3, N> dW_O;
  split(Wj_O, &W_O, &dW_O);
  Eigen::Vector3d& z = out->z;
  ThetaRows3& dD = out->dD;
  dD = ThetaRows3::Zero(3, n);
  ThetaRow drow(n);
  for (int i = 1; i < 3; ++i) {  // x senses at O: D_0 = 0
    const double* ri = th + o_s + 3 * (i - 1);
    const Vec3<GeoJet> r{GeoJet(ri[0]), GeoJet(ri[1]), GeoJet(ri[2])};
    Vec3<double> W_i;
    Eigen::Matrix<double, 3, N> dW_i;
    split(Wj_O + (dw2.cross(r) + w2.cross(w2.cross(r))) / GeoJet(g), &W_i, &dW_i);
    drow.setZero();
    Eigen::RowVector3d grad_i, grad_O;
    const double d = ReadingWithoutOffset(layout, th, i, W_i, &grad_i, 1.0, &drow) -
                     ReadingWithoutOffset(layout, th, i, W_O, &grad_O, -1.0, &drow);
    z[i] -= d;
    // By the Jet slots: grad R_i(W_i) dW_i - grad R_i(W_O) dW_O.
    const Eigen::Matrix<double, 1, N> dx = grad_i * dW_i - grad_O * dW_O;
    for (int q = 0; q < n_geo; ++q) drow[read[q]] += dx[q];
    drow[kDthetaC] += dx[slot_c];
    drow[kDlambda2] += dx[slot_c + 1];
    for (int q = 0; q < n_angle; ++q) drow[angle_params[q]] += dx[slot_a + q];
    // By R (moves both points) and r_i (moves accelerometer i's).
    drow.segment<3>(kDx2) += (grad_i - grad_O) * dW_dp;
    drow.segment<3>(o_s + 3 * (i - 1)) += grad_i * dW_dp;
    dD.row(i) = drow;
  }
}

// Size effect: accelerometer i senses W_i at its own point; B1 removes
// D_i = R_i(W_i) - R_i(W_O) from reading i first (AccelerationFromReadings_L).
// dD/dtheta: by W through Jets of the geometry (SizeEffectAwayFromZero), and
// by the sensor parameters written out.
// With r = 0 (the score tests of `diagnose` linearise there) D vanishes for
// every other parameter value, and only its columns by r remain:
// dD_i/dr_i = grad R_i(W_O) dW/dp (ForceGradientByPoint).
TRIADCAL_FLATTEN TRIADCAL_NOINLINE void SizeEffect(const ModelConfig& cfg, const double* th,
                                                   const BenchAngles<double>& b,
                                                   const Eigen::Matrix<double, 6, kJetParams>& db,
                                                   SizeCorrection* out) {
  const ParameterLayout& layout = cfg.layout;
  const double g = cfg.g_mps2;
  const std::vector<int>& angle_params = layout.StageParams(EffectStage::kAngle);
  Eigen::Matrix3d& dD_r = out->dD_r;
  const int o_s = layout.offset(Effect::kSizeEffect);
  bool r_zero = true;
  for (int q = 0; q < 6 && r_zero; ++q) r_zero = th[o_s + q] == 0.0;
  out->r_zero = r_zero;
  if (r_zero) {
    const BenchMotion<double> m = ComputeBenchMotion(cfg, th, b);
    const Vec3<double> W_O =
        SpecificForce_g(cfg, m.C_L2, MotionOfPoint(m, SensingPoint_m(cfg, th, 0)).a_L);
    const Mat3<double> dW_dr =
        ForceGradientByPoint(m.C_L2, m.w1_L + m.w12_L, m.dw1_L + m.dw12_L, g);
    for (int i = 1; i < 3; ++i) {
      Eigen::RowVector3d grad_O;
      ReadingWithoutOffset(layout, th, i, W_O, &grad_O, 0.0, nullptr);
      dD_r.row(i) = grad_O * dW_dr;
    }
  } else {
    // Slots: dpsi, d, eps, the bench zeros dtheta_c and dlambda2, and the
    // angle-stage parameters (through the bench angles' derivatives db).
    const int slots = 3 + static_cast<int>(angle_params.size()) +
                      (layout.offset(Effect::kAxisNonintersection) >= 0 ? 1 : 0) +
                      (layout.offset(Effect::kAxisNonperpendicularity) >= 0 ? 1 : 0);
    if (slots <= 4) {
      SizeEffectAwayFromZero<4>(cfg, th, b, db, out);
    } else if (slots <= 8) {
      SizeEffectAwayFromZero<8>(cfg, th, b, db, out);
    } else {
      SizeEffectAwayFromZero<kGeometryJet>(cfg, th, b, db, out);
    }
  }
}

// The sensor stage at readings z (size-corrected): u_i = (z_i - W0_i(t)) /
// s_i with s_i = K_i (+- dK_i with the scale asymmetry, the sign of z_i -
// W0_i), and W solving F(W) = M W + W o (K W) + Q(W) - u = 0 with J^-1 =
// (dF/dW)^-1 there.
struct SensorStage {
  Vec3<double> W, u, s, sgn;
  Mat3<double> Jf_inv;
};

SensorStage SensorStageAt(const ModelConfig& cfg, const double* th, const Eigen::Vector3d& z,
                          const SampleContext& ctx) {
  SensorStage st;
  st.W = SpecificForceFromReadings_g(cfg, th, Vec3<double>(z), ctx, &st.Jf_inv);
  const Vec3<double> w0 = ZeroOffset_mV(cfg, th, ctx);
  const int o_a = cfg.layout.offset(Effect::kScaleAsymmetry);
  for (int i = 0; i < 3; ++i) {
    const double v = z[i] - w0[i];
    st.sgn[i] = v < 0.0 ? -1.0 : 1.0;
    st.s[i] = th[kKx + i] + (o_a >= 0 ? st.sgn[i] * th[o_a + i] : 0.0);
    st.u[i] = v / st.s[i];
  }
  return st;
}

// The sensor stage's columns: each of its parameters moves F along one axis
// e_i (the columns of dF/dtheta in b1_jacobian.h), so its column is A's
// column i times that: A = -J^-1 gives dW/dtheta, A = -g C J^-1 da/dtheta.
void SensorStageColumns(const ModelConfig& cfg, const double* th, const SensorStage& st,
                        const SampleContext& ctx, const Mat3<double>& A,
                        Eigen::Ref<Eigen::MatrixXd> J) {
  const ParameterLayout& layout = cfg.layout;
  const Vec3<double>& W = st.W;
  const Vec3<double>& u = st.u;
  const Vec3<double>& s = st.s;
  for (int i = 0; i < 3; ++i) {
    J.col(kKx + i) = A.col(i) * (u[i] / s[i]);
    J.col(kW0x + i) = A.col(i) * (1.0 / s[i]);
  }
  J.col(kAlphaX) = A.col(1) * W.x();
  J.col(kAlphaY) = -A.col(0) * W.y();
  J.col(kBetaX) = -A.col(2) * W.x();
  J.col(kBetaZ) = A.col(0) * W.z();
  J.col(kGammaY) = A.col(2) * W.y();
  J.col(kGammaZ) = -A.col(1) * W.z();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) J.col(kKxx + 3 * i + j) = A.col(i) * (W[i] * W[j]);
  }
  // Zero-offset effects (catalogue): dF/d theta_e,i = x_e / s_i e_i.
  for (const ParameterLayout::ZeroOffsetTerm& term : layout.zero_offset_terms()) {
    const double x = ZeroOffsetSignalValue(cfg, term.signal, ctx);
    for (int i = 0; i < 3; ++i) J.col(term.offset + i) = A.col(i) * (x / s[i]);
  }
  // scale_asymmetry: dF/d dK_i = sgn_i u_i / s_i e_i.
  const int o_a = layout.offset(Effect::kScaleAsymmetry);
  if (o_a >= 0) {
    for (int i = 0; i < 3; ++i) J.col(o_a + i) = A.col(i) * (st.sgn[i] * u[i] / s[i]);
  }
  // cross_quadratic: dF/d d_i = (W_j^2 - W_k^2) e_i, dF/d p_i = W_j W_k e_i.
  const int o_q = layout.offset(Effect::kCrossQuadratic);
  if (o_q >= 0) {
    for (int i = 0; i < 3; ++i) {
      const int j = kCrossAxes[i][0], k = kCrossAxes[i][1];
      J.col(o_q + 2 * i) = A.col(i) * (W[j] * W[j] - W[k] * W[k]);
      J.col(o_q + 2 * i + 1) = A.col(i) * (W[j] * W[k]);
    }
  }
}

// One fill when J is contiguous (a Ref's setZero goes column by column, a
// memset call each: 8 % of a 40-min fit's time).
void FillZero(Eigen::Ref<Eigen::MatrixXd> J) {
  if (J.outerStride() == J.rows()) {
    std::fill_n(J.data(), J.size(), 0.0);
  } else {
    J.setZero();
  }
}

}  // namespace

void SpecificForceWithJacobian(const ModelConfig& cfg, const double* theta,
                               const Eigen::Vector3d& readings_mV, const SampleContext& ctx,
                               Eigen::Vector3d* W, Eigen::Ref<Eigen::MatrixXd> dW) {
  FillZero(dW);
  const SensorStage st = SensorStageAt(cfg, theta, readings_mV, ctx);
  *W = st.W;
  SensorStageColumns(cfg, theta, st, ctx, -st.Jf_inv, dW);
}

TRIADCAL_FLATTEN void AccelerationWithJacobian(const ModelConfig& cfg, const double* th,
                              const BenchAngles<double>& rec, const Eigen::Vector3d& z_in,
                              const SampleContext& ctx, Eigen::Vector3d* a_out,
                              Eigen::Ref<Eigen::MatrixXd> J) {
  const ParameterLayout& layout = cfg.layout;
  const double g = cfg.g_mps2;
  FillZero(J);

  BenchAngles<double> b = rec;
  const std::vector<int>& angle_params = layout.StageParams(EffectStage::kAngle);
  Eigen::Matrix<double, 6, kJetParams> db = Eigen::Matrix<double, 6, kJetParams>::Zero();
  if (!angle_params.empty()) AngleStage(cfg, th, rec, &b, &db);

  SizeCorrection size;
  size.z = z_in;
  const int o_s = layout.offset(Effect::kSizeEffect);
  if (o_s >= 0) SizeEffect(cfg, th, b, db, &size);
  const Eigen::Vector3d& z = size.z;

  // C = C_L1 C_12 with C_12 = Rz(eps) Rx Rz(-eps) (ComputeBenchMotion).
  const Mat3<double> Rzp = Rz(th[kDpsi]);
  const Mat3<double> Ryp = Ry(b.axis[0].angle + th[kDthetaC]);
  const int o_eps = layout.offset(Effect::kAxisNonperpendicularity);
  const Mat3<double> Reps = o_eps >= 0 ? Rz(th[o_eps]) : Mat3<double>::Identity();
  const Mat3<double> C_12 =
      o_eps >= 0 ? Mat3<double>(Reps * Rx(b.axis[1].angle + th[kDlambda2]) * Reps.transpose())
                 : Rx(b.axis[1].angle + th[kDlambda2]);
  const Mat3<double> C_L1 = Rzp * Ryp;
  const Mat3<double> C = C_L1 * C_12;

  const SensorStage st = SensorStageAt(cfg, th, z, ctx);
  const Vec3<double>& W = st.W;
  const Vec3<double>& s = st.s;
  // gC J^-1: each column of dF/dtheta maps to da by -gC J^-1.
  const Mat3<double> T = -g * C * st.Jf_inv;

  const Vec3<double> CW = C * W;
  *a_out = g * CW;
  (*a_out).x() -= g;

  const Vec3<double> C12W = C_12 * W;
  J.col(kDpsi) = g * Vec3<double>::UnitZ().cross(CW);
  J.col(kDthetaC) = g * Rzp * Vec3<double>::UnitY().cross(Ryp * C12W);
  // d C_12 / d l2 = [n x] C_12 with n = Rz(eps) e_x (the inner axis in frame 1);
  // d C_12 / d eps = [e_z x] C_12 - C_12 [e_z x].
  J.col(kDlambda2) = g * C_L1 * Reps.col(0).cross(C12W);
  if (o_eps >= 0) {
    J.col(o_eps) =
        g * C_L1 * (Vec3<double>::UnitZ().cross(C12W) - C_12 * Vec3<double>::UnitZ().cross(W));
  }
  SensorStageColumns(cfg, th, st, ctx, T, J);
  // Angle-stage effects move C only through the two bench angles, as
  // dtheta_c and dlambda2 do: chain rule.
  for (std::size_t q = 0; q < angle_params.size(); ++q) {
    J.col(angle_params[q]) = J.col(kDthetaC) * db(0, q) + J.col(kDlambda2) * db(3, q);
  }
  // The size effect's correction enters as u_i = (z_i - D_i - W0_i) / s_i:
  // dF/dD_i = 1 / s_i e_i, so da/dD_i = T.col(i) / s_i.
  if (size.dD.size() > 0) {
    for (int i = 1; i < 3; ++i) J += (T.col(i) / s[i]) * size.dD.row(i);
  } else if (size.r_zero) {
    for (int i = 1; i < 3; ++i) {
      J.middleCols<3>(o_s + 3 * (i - 1)) += (T.col(i) / s[i]) * size.dD_r.row(i);
    }
  }
}

void ReferenceMotionWithJacobian(const ModelConfig& cfg, const double* th,
                                 const BenchAngles<double>& rec, Eigen::Vector3d* v_out,
                                 Eigen::Vector3d* p_out, Eigen::Ref<Eigen::MatrixXd> J) {
  const ParameterLayout& layout = cfg.layout;
  J.setZero();
  BenchAngles<double> b = rec;
  const std::vector<int>& angle_params = layout.StageParams(EffectStage::kAngle);
  Eigen::Matrix<double, 6, kJetParams> db = Eigen::Matrix<double, 6, kJetParams>::Zero();
  if (!angle_params.empty()) AngleStage(cfg, th, rec, &b, &db);
  const BenchMotion<double> m = ComputeBenchMotion(cfg, th, b);
  const Vec3<double> R = LeverArm_m(cfg, th);
  const Vec3<double> q = m.C_L2 * R;
  const Vec3<double> p = m.axis_offset_L + q;
  const Vec3<double>& w1 = m.w1_L;
  const Vec3<double>& w12 = m.w12_L;
  const Vec3<double> v = w1.cross(p) + w12.cross(q);
  *v_out = v;
  *p_out = p;
  const Vec3<double> e_z = Vec3<double>::UnitZ();
  const Vec3<double> u1 = m.C_L1.col(1);  // Rz(dpsi) e_y: Ry keeps e_y
  const int o_e = layout.offset(Effect::kAxisNonperpendicularity);
  const double eps = o_e >= 0 ? th[o_e] : 0.0;
  const Vec3<double> n_1(std::cos(eps), std::sin(eps), 0.0);  // Rz(eps) e_x
  const Vec3<double> n_L = m.C_L1 * n_1;
  auto add = [&J](int col, const Vec3<double>& dv, const Vec3<double>& dp) {
    J.col(col).head<3>() += dv;
    J.col(col).tail<3>() += dp;
  };
  add(kDpsi, e_z.cross(v), e_z.cross(p));
  // The outer angle A, the inner angle B, and the two rates.
  const Vec3<double> dp_A = u1.cross(p), dq_A = u1.cross(q), dw12_A = u1.cross(w12);
  const Vec3<double> dv_A = w1.cross(dp_A) + dw12_A.cross(q) + w12.cross(dq_A);
  const Vec3<double> dq_B = n_L.cross(q);
  const Vec3<double> dv_B = (w1 + w12).cross(dq_B);
  const Vec3<double> dv_r0 = u1.cross(p), dv_r1 = n_L.cross(q);
  add(kDthetaC, dv_A, dp_A);
  add(kDlambda2, dv_B, dq_B);
  for (std::size_t a = 0; a < angle_params.size(); ++a) {
    add(angle_params[a],
        dv_A * db(0, a) + dv_r0 * db(1, a) + dv_B * db(3, a) + dv_r1 * db(4, a),
        dp_A * db(0, a) + dq_B * db(3, a));
  }
  for (int j = 0; j < 3; ++j) {
    const Vec3<double> dq = m.C_L2.col(j);
    add(kDx2 + j, (w1 + w12).cross(dq), dq);
  }
  const int o_d = layout.offset(Effect::kAxisNonintersection);
  if (o_d >= 0) add(o_d, w1.cross(m.C_L1.col(2)), m.C_L1.col(2));
  if (o_e >= 0) {
    const Vec3<double> q1 = m.C_L1.transpose() * q;  // C_12 R
    const Mat3<double> C_12 = m.C_L1.transpose() * m.C_L2;
    const Vec3<double> dq = m.C_L1 * (e_z.cross(q1) - C_12 * e_z.cross(R));
    const Vec3<double> dw12 = m.C_L1 * e_z.cross(n_1) * b.axis[1].rate;
    add(o_e, w1.cross(dq) + dw12.cross(q) + w12.cross(dq), dq);
  }
}

}  // namespace triadcal

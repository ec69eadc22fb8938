#include "core/model/b1_jacobian.h"
#include "core/model/sparse_jets.h"

#include <ceres/jet.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace triadcal {
namespace {

constexpr int kMaxParams = 64;

// Jets of the angle stage: at most its parameters (latency, encoder
// harmonic, angle scale: 1 + 4 + 2).
constexpr int kJetParams = 8;

// Rows of theta derivatives, on the stack (one sample's work allocates nothing).
using ThetaRow = Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, kMaxParams>;
using ThetaRows3 = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxParams>;

// Column c, and columns c..c+2, of a Jacobian of 3 rows as fixed-size
// objects: a Ref's rows are known only at run time, and Eigen's loop over
// 3 entries of a dynamic column cost more than its arithmetic.
Eigen::Map<Eigen::Vector3d> Col3(Eigen::Ref<Eigen::MatrixXd>& J, int c) {
  return Eigen::Map<Eigen::Vector3d>(J.data() + c * J.outerStride());
}
using Map3x3 = Eigen::Map<Eigen::Matrix3d, 0, Eigen::OuterStride<>>;
Map3x3 Cols3(Eigen::Ref<Eigen::MatrixXd>& J, int c) {
  return Map3x3(J.data() + c * J.outerStride(), Eigen::OuterStride<>(J.outerStride()));
}

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

// The quantities the motion of frame 2 depends on: dpsi, the outer angle A =
// l1 + dtheta_c with its rate and acceleration, the inner angle B = l2 +
// dlambda2 with its rate and acceleration (the order of db's rows), eps and d.
enum MotionVar { kVarPsi, kVarA, kVarA1, kVarA2, kVarB, kVarB1, kVarB2, kVarEps, kVarD, kMotionVars };
using MotionRows = Eigen::Matrix<double, 3, kMotionVars>;
using MotionRow = Eigen::Matrix<double, 1, kMotionVars>;

// Frame 2's motion in its own axes and its derivatives by the MotionVars.
// With y2 = C_12^T e_y and n_1 = Rz(eps) e_x (C_L1^T u1 = e_y, C_12^T n_1 = n_1):
//
//   w2  = A' y2 + B' n_1,   w2' = A'' y2 + A' B' (y2 x n_1) + B'' n_1,
//   W_P = (C_12^T s_1 + w2' x P + w2 x (w2 x P)) / g   at the point P of frame 2,
//   s_1 = d (A'' e_x - A'^2 e_z) + g C_L1^T e_x
//
// (s_1: the axis offset's acceleration and gravity's, in frame 1). And
// d(C_L1^T e_x)/d dpsi = -C_L1^T e_y, d(C_L1^T e_x)/dA = -e_y x C_L1^T e_x,
// d(C_12^T x)/dB = -n_1 x C_12^T x, d(C_12^T x)/d eps = e_z x C_12^T x -
// C_12^T (e_z x x), d n_1/d eps = e_z x n_1.
struct Frame2Motion {
  Vec3<double> w2, dw2;
  MotionRows d_w2, d_dw2;
  MotionRows d_s2;  // of C_12^T s_1 [m/s^2]
  // u . dW_P by the MotionVars, for a row u on W (1/g of it): by the
  // triple product, u . (a x P) = a . (P x u).
  MotionRow Along(const Eigen::RowVector3d& u, const Vec3<double>& P, double inv_g) const {
    const Vec3<double> ut = u.transpose();
    const Vec3<double> by_dw = P.cross(ut);
    const Vec3<double> by_w = w2.cross(P).cross(ut) + P.cross(ut.cross(w2));
    return (u * d_s2 + by_dw.transpose() * d_dw2 + by_w.transpose() * d_w2) * inv_g;
  }
};

Frame2Motion Frame2MotionAt(const ModelConfig& cfg, const double* th, const BenchAngles<double>& b,
                            const BenchMotion<double>& m) {
  const ParameterLayout& layout = cfg.layout;
  const double g = cfg.g_mps2;
  const int o_e = layout.offset(Effect::kAxisNonperpendicularity);
  const int o_d = layout.offset(Effect::kAxisNonintersection);
  const double d = o_d >= 0 ? th[o_d] : 0.0;
  const double A1 = b.axis[0].rate, A2 = b.axis[0].accel;
  const double B1 = b.axis[1].rate, B2 = b.axis[1].accel;
  const Vec3<double> e_x = Vec3<double>::UnitX(), e_y = Vec3<double>::UnitY(),
                     e_z = Vec3<double>::UnitZ();
  const Mat3<double> C_21 = m.C_L2.transpose() * m.C_L1;  // C_12^T
  const Vec3<double> n_1 =
      o_e >= 0 ? Vec3<double>(std::cos(th[o_e]), std::sin(th[o_e]), 0.0) : e_x;
  const Vec3<double> dn_1 = e_z.cross(n_1);
  const Vec3<double> y2 = C_21.col(1);
  // C_12^T's derivatives on a vector x of frame 1 (x2 = C_12^T x).
  auto by_B = [&](const Vec3<double>& x2) { return Vec3<double>(-n_1.cross(x2)); };
  auto by_eps = [&](const Vec3<double>& x1, const Vec3<double>& x2) {
    return Vec3<double>(e_z.cross(x2) - C_21 * e_z.cross(x1));
  };
  const Vec3<double> dy2_B = by_B(y2), dy2_eps = by_eps(e_y, y2);
  const Vec3<double> yxn = y2.cross(n_1);

  Frame2Motion f;
  f.w2 = A1 * y2 + B1 * n_1;
  f.dw2 = A2 * y2 + A1 * B1 * yxn + B2 * n_1;
  f.d_w2.setZero();
  f.d_dw2.setZero();
  f.d_w2.col(kVarA1) = y2;
  f.d_w2.col(kVarB) = A1 * dy2_B;
  f.d_w2.col(kVarB1) = n_1;
  f.d_w2.col(kVarEps) = A1 * dy2_eps + B1 * dn_1;
  f.d_dw2.col(kVarA1) = B1 * yxn;
  f.d_dw2.col(kVarA2) = y2;
  f.d_dw2.col(kVarB) = A2 * dy2_B + A1 * B1 * dy2_B.cross(n_1);
  f.d_dw2.col(kVarB1) = A1 * yxn;
  f.d_dw2.col(kVarB2) = n_1;
  f.d_dw2.col(kVarEps) =
      A2 * dy2_eps + A1 * B1 * (dy2_eps.cross(n_1) + y2.cross(dn_1)) + B2 * dn_1;

  const Vec3<double> h1 = m.C_L1.row(0).transpose();  // C_L1^T e_x
  const Vec3<double> s_1 = d * (A2 * e_x - A1 * A1 * e_z) + g * h1;
  MotionRows ds_1 = MotionRows::Zero();
  ds_1.col(kVarPsi) = -g * m.C_L1.row(1).transpose();
  ds_1.col(kVarA) = -g * e_y.cross(h1);
  ds_1.col(kVarA1) = -2.0 * d * A1 * e_z;
  ds_1.col(kVarA2) = d * e_x;
  ds_1.col(kVarD) = A2 * e_x - A1 * A1 * e_z;
  const Vec3<double> s_2 = C_21 * s_1;
  f.d_s2.noalias() = C_21 * ds_1;
  f.d_s2.col(kVarB) += by_B(s_2);
  f.d_s2.col(kVarEps) += by_eps(s_1, s_2);
  return f;
}

// The size effect away from r = 0 (SizeEffect): D_i = R_i(W_i) - R_i(W_O),
// W_O and W_i at O (R) and at accelerometer i's point (R + r_i), by
// Frame2MotionAt, mapped from the MotionVars onto theta: dpsi, dtheta_c (A),
// dlambda2 (B), eps and d, and the angle-stage parameters through the bench
// angles' derivatives db. The points' positions enter their accelerations
// linearly: their columns are by ForceGradientByPoint.
TRIADCAL_FLATTEN TRIADCAL_NOINLINE void SizeEffectAwayFromZero(
    const ModelConfig& cfg, const double* th, const BenchAngles<double>& b,
    const BenchMotion<double>& m, const Eigen::Matrix<double, 6, kJetParams>& db,
    SizeCorrection* out) {
  const ParameterLayout& layout = cfg.layout;
  const int n = layout.size();
  const double g = cfg.g_mps2, inv_g = 1.0 / g;
  const std::vector<int>& angle_params = layout.StageParams(EffectStage::kAngle);
  const int n_angle = static_cast<int>(angle_params.size());
  const int o_s = layout.offset(Effect::kSizeEffect);
  const int o_d = layout.offset(Effect::kAxisNonintersection);
  const int o_e = layout.offset(Effect::kAxisNonperpendicularity);
  const Vec3<double> R = SensingPoint_m(cfg, th, 0);
  const Vec3<double> W_O = SpecificForce_g(cfg, m.C_L2, MotionOfPoint(m, R).a_L);
  const Mat3<double> dW_dp =
      ForceGradientByPoint(m.C_L2, m.w1_L + m.w12_L, m.dw1_L + m.dw12_L, g);
  const Frame2Motion f = Frame2MotionAt(cfg, th, b, m);
  Eigen::Vector3d& z = out->z;
  ThetaRows3& dD = out->dD;
  dD = ThetaRows3::Zero(3, n);
  ThetaRow drow(n);
  for (int i = 1; i < 3; ++i) {  // x senses at O: D_0 = 0
    const Vec3<double> r(th + o_s + 3 * (i - 1));
    const Vec3<double> W_i = W_O + (f.dw2.cross(r) + f.w2.cross(f.w2.cross(r))) * inv_g;
    drow.setZero();
    Eigen::RowVector3d grad_i, grad_O;
    const double d = ReadingWithoutOffset(layout, th, i, W_i, &grad_i, 1.0, &drow) -
                     ReadingWithoutOffset(layout, th, i, W_O, &grad_O, -1.0, &drow);
    z[i] -= d;
    // grad R_i(W_i) dW_i - grad R_i(W_O) dW_O, W_i's point at R + r.
    const MotionRow dx = f.Along(grad_i, R + r, inv_g) - f.Along(grad_O, R, inv_g);
    drow[kDpsi] += dx[kVarPsi];
    drow[kDthetaC] += dx[kVarA];
    drow[kDlambda2] += dx[kVarB];
    if (o_e >= 0) drow[o_e] += dx[kVarEps];
    if (o_d >= 0) drow[o_d] += dx[kVarD];
    for (int q = 0; q < n_angle; ++q) {
      drow[angle_params[q]] += dx.segment<6>(kVarA).dot(db.col(q));
    }
    // By R (moves both points) and r_i (moves accelerometer i's).
    drow.segment<3>(kDx2) += (grad_i - grad_O) * dW_dp;
    drow.segment<3>(o_s + 3 * (i - 1)) += grad_i * dW_dp;
    dD.row(i) = drow;
  }
}

// Size effect: accelerometer i senses W_i at its own point; B1 removes
// D_i = R_i(W_i) - R_i(W_O) from reading i first (AccelerationFromReadings_L).
// dD/dtheta: by W through frame 2's motion, and by the sensor parameters,
// written out (SizeEffectAwayFromZero).
// With r = 0 (the score tests of `diagnose` linearise there) D vanishes for
// every other parameter value, and only its columns by r remain:
// dD_i/dr_i = grad R_i(W_O) dW/dp (ForceGradientByPoint).
TRIADCAL_FLATTEN TRIADCAL_NOINLINE void SizeEffect(const ModelConfig& cfg, const double* th,
                                                   const BenchAngles<double>& b,
                                                   const BenchMotion<double>& m,
                                                   const Eigen::Matrix<double, 6, kJetParams>& db,
                                                   SizeCorrection* out) {
  const ParameterLayout& layout = cfg.layout;
  const double g = cfg.g_mps2;
  Eigen::Matrix3d& dD_r = out->dD_r;
  const int o_s = layout.offset(Effect::kSizeEffect);
  bool r_zero = true;
  for (int q = 0; q < 6 && r_zero; ++q) r_zero = th[o_s + q] == 0.0;
  out->r_zero = r_zero;
  if (r_zero) {
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
    SizeEffectAwayFromZero(cfg, th, b, m, db, out);
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
    Col3(J, kKx + i) = A.col(i) * (u[i] / s[i]);
    Col3(J, kW0x + i) = A.col(i) * (1.0 / s[i]);
  }
  Col3(J, kAlphaX) = A.col(1) * W.x();
  Col3(J, kAlphaY) = -A.col(0) * W.y();
  Col3(J, kBetaX) = -A.col(2) * W.x();
  Col3(J, kBetaZ) = A.col(0) * W.z();
  Col3(J, kGammaY) = A.col(2) * W.y();
  Col3(J, kGammaZ) = -A.col(1) * W.z();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) Col3(J, kKxx + 3 * i + j) = A.col(i) * (W[i] * W[j]);
  }
  // Zero-offset effects (catalogue): dF/d theta_e,i = x_e / s_i e_i.
  for (const ParameterLayout::ZeroOffsetTerm& term : layout.zero_offset_terms()) {
    const double x = ZeroOffsetSignalValue(cfg, term.signal, ctx);
    for (int i = 0; i < 3; ++i) Col3(J, term.offset + i) = A.col(i) * (x / s[i]);
  }
  // scale_asymmetry: dF/d dK_i = sgn_i u_i / s_i e_i.
  const int o_a = layout.offset(Effect::kScaleAsymmetry);
  if (o_a >= 0) {
    for (int i = 0; i < 3; ++i) Col3(J, o_a + i) = A.col(i) * (st.sgn[i] * u[i] / s[i]);
  }
  // cross_quadratic: dF/d d_i = (W_j^2 - W_k^2) e_i, dF/d p_i = W_j W_k e_i.
  const int o_q = layout.offset(Effect::kCrossQuadratic);
  if (o_q >= 0) {
    for (int i = 0; i < 3; ++i) {
      const int j = kCrossAxes[i][0], k = kCrossAxes[i][1];
      Col3(J, o_q + 2 * i) = A.col(i) * (W[j] * W[j] - W[k] * W[k]);
      Col3(J, o_q + 2 * i + 1) = A.col(i) * (W[j] * W[k]);
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
  eigen_assert(dW.rows() == 3);  // Col3
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
  eigen_assert(J.rows() == 3);  // Col3
  FillZero(J);

  BenchAngles<double> b = rec;
  const std::vector<int>& angle_params = layout.StageParams(EffectStage::kAngle);
  Eigen::Matrix<double, 6, kJetParams> db = Eigen::Matrix<double, 6, kJetParams>::Zero();
  if (!angle_params.empty()) AngleStage(cfg, th, rec, &b, &db);

  // C = C_L1 C_12 with C_12 = Rz(eps) Rx Rz(-eps) (bench_model.h), formed
  // once: the size effect's motion of frame 2 turns with them too.
  const BenchRotations<double> rot = ComputeBenchRotations(cfg, th, b);
  const Mat3<double>& Rzp = rot.Rpsi;
  const Mat3<double>& Ryp = rot.Ry;
  const Mat3<double>& C_12 = rot.C_12;
  const Mat3<double>& C_L1 = rot.C_L1;
  const Mat3<double>& C = rot.C_L2;
  const int o_eps = layout.offset(Effect::kAxisNonperpendicularity);

  SizeCorrection size;
  size.z = z_in;
  const int o_s = layout.offset(Effect::kSizeEffect);
  if (o_s >= 0) SizeEffect(cfg, th, b, ComputeBenchMotion(cfg, th, b, rot), db, &size);
  const Eigen::Vector3d& z = size.z;

  const SensorStage st = SensorStageAt(cfg, th, z, ctx);
  const Vec3<double>& W = st.W;
  const Vec3<double>& s = st.s;
  // gC J^-1: each column of dF/dtheta maps to da by -gC J^-1.
  const Mat3<double> T = -g * C * st.Jf_inv;

  const Vec3<double> CW = C * W;
  *a_out = g * CW;
  (*a_out).x() -= g;

  const Vec3<double> C12W = C_12 * W;
  Col3(J, kDpsi) = g * Vec3<double>::UnitZ().cross(CW);
  Col3(J, kDthetaC) = g * Rzp * Vec3<double>::UnitY().cross(Ryp * C12W);
  // d C_12 / d l2 = [n x] C_12 with n = Rz(eps) e_x (the inner axis in frame 1);
  // d C_12 / d eps = [e_z x] C_12 - C_12 [e_z x].
  Col3(J, kDlambda2) = g * C_L1 * rot.n_1.cross(C12W);
  if (o_eps >= 0) {
    Col3(J, o_eps) =
        g * C_L1 * (Vec3<double>::UnitZ().cross(C12W) - C_12 * Vec3<double>::UnitZ().cross(W));
  }
  SensorStageColumns(cfg, th, st, ctx, T, J);
  // Angle-stage effects move C only through the two bench angles, as
  // dtheta_c and dlambda2 do: chain rule.
  for (std::size_t q = 0; q < angle_params.size(); ++q) {
    Col3(J, angle_params[q]) = Col3(J, kDthetaC) * db(0, q) + Col3(J, kDlambda2) * db(3, q);
  }
  // The size effect's correction enters as u_i = (z_i - D_i - W0_i) / s_i:
  // dF/dD_i = 1 / s_i e_i, so da/dD_i = T.col(i) / s_i.
  if (size.dD.size() > 0) {
    for (int i = 1; i < 3; ++i) J += (T.col(i) / s[i]) * size.dD.row(i);
  } else if (size.r_zero) {
    for (int i = 1; i < 3; ++i) {
      Cols3(J, o_s + 3 * (i - 1)) += (T.col(i) / s[i]) * size.dD_r.row(i);
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

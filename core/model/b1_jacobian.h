// Block B1 (AccelerationFromReadings_L in bench_model.h) with its Jacobian with
// respect to theta written out analytically, for the estimators' hot loop: an
// order of magnitude faster than pushing Jets through the chain. It covers the
// base model and the effects whose catalogue entry says b1_analytic_jacobian:
// the angle stage (latency, encoder harmonic, angle scale: they move C only
// through the two bench angles, so their columns are those of dtheta_c and
// dlambda2 times the angles' derivatives, taken by small Jets of the angle
// stage alone), the sensor stage (drifts through the zero offsets, scale
// asymmetry through s_i, cross_quadratic through F and its Jacobian),
// axis_nonintersection (B2 only), the axis non-perpendicularity (through C)
// and the size effect (the correction D of the readings, with its derivatives
// by W through frame 2's motion, by the lever arm and r (the points enter
// linearly) and by the sensor parameters, all written out; with r = 0, where
// the score tests of `diagnose` linearise, only its columns by r). A layout with an effect
// that has no written-out columns, more than 64 parameters or more than 8
// angle-stage ones takes the Jet path (B1HasAnalyticJacobian false).
//
//   a = g C W - g e_x,   C = C_L1 C_12,   C_L1 = Rz(dpsi) Ry(l1 + dtheta_c),
//   C_12 = Rz(eps) Rx(l2 + dlambda2) Rz(-eps)
//
//   da/d dpsi     = g e_z x (C W)
//   da/d dtheta_c = g Rz (e_y x (Ry C_12 W))
//   da/d dlambda2 = g C_L1 (n x (C_12 W)),   n = Rz(eps) e_x
//   da/d eps      = g C_L1 (e_z x (C_12 W) - C_12 (e_z x W))
//   da/d theta_W  = g C dW/d theta_W,   dW/d theta_W = -J^-1 dF/d theta_W
//
// with F(W) = M W + W o (K W) + Q(W) - u = 0, u_i = (z_i - W0_i(t)) / s_i,
// J = M + diag(K W) + diag(W) K + dQ/dW, and the columns of dF/d theta_W:
//
//   K_i: +u_i / s_i e_i        W0_i: +1 / s_i e_i      (s_i = K_i [+- dK_i])
//   dK_i: +sgn(z_i - W0_i) u_i / s_i e_i
//   cross_quadratic d_i: (W_j^2 - W_k^2) e_i,   p_i: W_j W_k e_i
//   alpha_x: W_x e_y   alpha_y: -W_y e_x   beta_x: -W_x e_z
//   beta_z: W_z e_x    gamma_y: W_y e_z    gamma_z: -W_z e_y
//   K_ij: W_i W_j e_i
//   zero-offset effect theta_e,i: x_e / s_i e_i   (x = t for thermal_drift,
//                                               T - T_ref for thermal_drift_temp)
#pragma once

#include <Eigen/Core>

#include "core/model/bench_model.h"

namespace triadcal {

// True when AccelerationWithJacobian covers the layout: every effect has
// written-out columns (catalogue b1_analytic_jacobian), at most 64
// parameters, at most 8 of them in the angle stage.
bool B1HasAnalyticJacobian(const ParameterLayout& layout);

// Requires B1HasAnalyticJacobian(cfg.layout).
// a [m/s^2] and da/dtheta (3 x layout.size(), written into *J which must have
// that size; columns of parameters B1 does not depend on are set to zero).
void AccelerationWithJacobian(const ModelConfig& cfg, const double* theta,
                              const BenchAngles<double>& recorded,
                              const Eigen::Vector3d& readings_mV, const SampleContext& ctx,
                              Eigen::Vector3d* a, Eigen::Ref<Eigen::MatrixXd> J);

// The specific force W [g] at O from the readings as they are (no size
// correction: SpecificForceFromReadings_g) and dW/dtheta (3 x layout.size(),
// into *dW: the readings model's columns, zero elsewhere), written out as in
// AccelerationWithJacobian (dW/dtheta = -J^-1 dF/dtheta). The gyro's
// g-sensitivity acts through it. Any layout: every readings-model parameter
// of the catalogue is written out, and no Jets are needed.
void SpecificForceWithJacobian(const ModelConfig& cfg, const double* theta,
                               const Eigen::Vector3d& readings_mV, const SampleContext& ctx,
                               Eigen::Vector3d* W, Eigen::Ref<Eigen::MatrixXd> dW);

// Block B2 (ReferenceMotion in bench_model.h) with its Jacobian written out:
// the velocity and position of O in L and their derivatives (J: 6 x
// layout.size(), rows v then p, zero where B2 does not depend). Requires
// B1HasAnalyticJacobian(cfg.layout). With p = C_L1 e_z d + q, q = C_L2 R,
// v = w1 x p + w12 x q (w1 = u1 l1', w12 = n_L l2', u1 = Rz(dpsi) e_y the
// outer axis, n_L = C_L1 Rz(eps) e_x the inner one):
//
//   d/d dpsi: e_z x (p, v)           d/d A (A = l1 + dtheta_c): u1 x (p, q, w12)
//   d/d B (B = l2 + dlambda2): n_L x q in p and q    d/d l1': u1 x p in v
//   d/d l2': n_L x q in v            d/d R: C_L2 (q and p)     d/d d: C_L1 e_z (p)
//   d/d eps: C_L1 (e_z x C_12 R - C_12 (e_z x R)) in q and p, C_L1 (e_z x n_1) l2' in w12
//
// and the angle stage's parameters through l1, l1', l2, l2' (their small Jets,
// as in AccelerationWithJacobian).
void ReferenceMotionWithJacobian(const ModelConfig& cfg, const double* theta,
                                 const BenchAngles<double>& recorded, Eigen::Vector3d* v,
                                 Eigen::Vector3d* p, Eigen::Ref<Eigen::MatrixXd> J);

}  // namespace triadcal

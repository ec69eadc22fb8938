// Block B1 (AccelerationFromReadings_L in bench_model.h) with its Jacobian with
// respect to theta written out analytically, for the estimators' hot loop: an
// order of magnitude faster than pushing Jets through the chain. It covers the
// base model and the effects whose catalogue entry says b1_analytic_jacobian:
// those that act on B1 through the zero offsets (zero_offset_signal: the
// thermal drifts) and those that do not touch B1 (axis_nonintersection).
// For other effects use the Jet path (B1HasAnalyticJacobian says which).
//
//   a = g C W - g e_x,   C = Rz(dpsi) Ry(l1 + dtheta_c) Rx(l2 + dlambda2)
//
//   da/d dpsi     = g e_z x (C W)
//   da/d dtheta_c = g Rz (e_y x (Ry Rx W))
//   da/d dlambda2 = g C (e_x x W)
//   da/d theta_W  = g C dW/d theta_W,   dW/d theta_W = -J^-1 dF/d theta_W
//
// with F(W) = M W + W o (K W) - u = 0, u_i = (z_i - W0_i(t)) / K_i,
// J = M + diag(K W) + diag(W) K, and the columns of dF/d theta_W:
//
//   K_i: +u_i / K_i e_i        W0_i: +1 / K_i e_i
//   alpha_x: W_x e_y   alpha_y: -W_y e_x   beta_x: -W_x e_z
//   beta_z: W_z e_x    gamma_y: W_y e_z    gamma_z: -W_z e_y
//   K_ij: W_i W_j e_i
//   zero-offset effect theta_e,i: x_e / K_i e_i   (x = t for thermal_drift,
//                                               T - T_ref for thermal_drift_temp)
#pragma once

#include <Eigen/Core>

#include "core/model/bench_model.h"

namespace triadcal {

bool B1HasAnalyticJacobian(const ParameterLayout& layout);

// a [m/s^2] and da/dtheta (3 x layout.size(), written into *J which must have
// that size; columns of parameters B1 does not depend on are set to zero).
void AccelerationWithJacobian(const ModelConfig& cfg, const double* theta,
                              const BenchAngles<double>& recorded,
                              const Eigen::Vector3d& readings_mV, const SampleContext& ctx,
                              Eigen::Vector3d* a, Eigen::Ref<Eigen::MatrixXd> J);

}  // namespace triadcal

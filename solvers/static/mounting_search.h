// Which way the IMU sits on the platform, from the data: the signed
// permutation of its axes (a proper rotation, SPEC section 1 frames) and the
// angle-sensor zeros that make the readings follow gravity best.
//
// Derivation. At the low rates of a calibration bench the readings follow the
// gravity projection of bench_model.h: W = C_L2^T (0 - g_L) / g with
// C_L2 = Ry(lambda1 + z1) Rx(lambda2 + z2) (z1: outer zero merged with the
// bench tilt, dtheta_c; z2: the inner zero, dlambda2). Platform axis i of a
// mounting P reads  w_i = sign_i * imu[src_i] = b_i + K_i W_i + e_i. For each P
// and zeros (z1, z2), b_i and K_i follow by linear least squares per axis; the
// fit is judged by the RMS of e_i in g (e_i / K_i), with K_i > 0 required (a
// negative scale is a flipped axis, i.e. another P). The dynamic terms (a few
// 0.01 g at 0.14 m and 75 deg/s) and the triad's own errors set the floor of
// the RMS; a wrong axis or sign leaves about 0.5 g.
#pragma once

#include <string>
#include <vector>

#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

struct MountingFit {
  int axis_source[3] = {0, 1, 2};
  double axis_sign[3] = {1.0, 1.0, 1.0};
  double zero_rad[2] = {0.0, 0.0};    // z1 (outer, dtheta_c), z2 (inner, dlambda2)
  double rms_g = 0.0;                 // RMS misfit of the gravity projection [g]
  double scale[3] = {0.0, 0.0, 0.0};  // fitted K_i [readings unit per g]
  double bias[3] = {0.0, 0.0, 0.0};
  std::string AxesText() const;  // ["+y", "-z", "-x"]
};

// Readings of the IMU's own axes at the samples idx of a loaded run
// (LoadRunData applied the declared mounting; this takes it back off).
std::vector<std::vector<double>> ImuReadings(const RunDescription& run, const RunData& data,
                                             const std::vector<std::size_t>& idx);

// Every proper signed permutation (24), best first, each with its best zeros
// within +-zero_range_rad (searched on a grid of zero_step_rad, then refined).
// Uses at most max_samples samples (evenly spaced).
std::vector<MountingFit> SearchMountings(const RunDescription& run, const RunData& data,
                                         double zero_range_rad, double zero_step_rad,
                                         std::size_t max_samples = 2000);

// A line when the declared angles turn gravity on the platform (by over 0.5
// g on an axis) but the readings hardly move (below 0.15 g on every channel
// at its nominal scale): a vertical shaft recorded as a horizontal axis.
// Empty otherwise.
std::string StillGravityNote(const RunDescription& run, const RunData& data);

// A warning line (StillGravityNote's when it has one) when the declared mounting (zeros near 0, within +-5 deg) fits
// clearly worse (RMS over 3 times and 0.05 g more) than another; nullopt-like
// empty string otherwise, or when the angles do not move enough to tell.
std::string MountingWarning(const RunDescription& run, const RunData& data);

}  // namespace triadcal

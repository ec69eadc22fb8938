// The white noise of a sampled series, without any model: the second
// difference d_k = x_{k+1} - 2 x_k + x_{k-1} of white noise of sigma has
// variance 6 sigma^2, while a smooth signal adds only (2 pi dt / T)^2 times
// its amplitude (4e-4 of it for a 6-s swing sampled at 50 Hz). The largest
// 2 % of |d| are left out (gaps, repeated stamps, spikes) and the Gaussian
// truncation corrected. Used as the start of `noise_mV: auto` and as the
// noise the unit checks allow for (time-stamp jitter and vibration count in
// it, as they do in the residuals).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

// sigma of the white part of x, in x's unit (0 for fewer than 10 samples).
double SecondDifferenceNoise(const std::vector<double>& x);

// The reading noise of each channel of a run [mV]: the declared figures, or
// with `noise_mV: auto` each channel's own white noise (SecondDifferenceNoise;
// the declared figure where a channel has too few samples) - what `fit`
// starts from. For analyses that take the noise as known (observability).
Eigen::Vector3d RunReadingNoise_mV(const RunDescription& run, const RunData& data);

// `run` with RunReadingNoise_mV declared per channel and noise_auto off; the
// gyro's `noise_dps: auto` likewise (each gyro channel's own white noise).
RunDescription WithReadingNoise(RunDescription run, const RunData& data);

}  // namespace triadcal

// Checks of run data as read, before it becomes a RunData: fatal problems throw
// InputError naming the file, the line (or MAT sample) and the column; findings
// worth telling come back as one warning line each, with counts.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/io/data_table.h"

namespace triadcal {

// One channel as read, in our units (t s, angles deg, rates deg/s, readings mV
// on the IMU's own axes, temp_C degC).
struct ChannelValues {
  std::string name;   // our channel name: t, lambda1, ..., wx (IMU x)
  std::string label;  // for messages: "column 'acc_x' (wx)", "variable 'all_time' (t)"
  std::vector<double> values;

  bool present() const { return !values.empty(); }
};

constexpr std::size_t kMinSamples = 10;

// Fatal checks.
void CheckSampleCount(const DataTable& table, std::size_t n, const std::string& what);
void CheckFinite(const DataTable& table, const std::vector<const ChannelValues*>& channels);
void CheckTimeNotDecreasing(const DataTable& table, const ChannelValues& t);
// All |w| < 2% of (nominal scale + |nominal bias|): readings in V or g, not mV.
void CheckReadingsInMillivolts(const DataTable& table, const ChannelValues& w,
                               double nominal_range_mV);
// Both angle spans below 2 pi + 0.1 "deg" while a reading swings by more than
// 0.5 g of nominal scale: the angles were recorded in radians.
void CheckAnglesInDegrees(const DataTable& table, const ChannelValues (&lambda)[2],
                          const ChannelValues (&w)[3], const double (&scale_mV_per_g)[3]);

// Indices of the samples to keep: the first of each run of equal time stamps.
std::vector<std::size_t> FirstOfEqualTimes(const std::vector<double>& t_s);

// Warnings (empty when there is nothing to say).
std::optional<std::string> DuplicateWarning(std::size_t n_dropped);
std::optional<std::string> GapWarning(const std::vector<double>& t_s);
std::optional<std::string> SaturationWarning(const ChannelValues& c,
                                             const std::string& unit = "mV");
// The samples of c held at its maximum or minimum in runs of 3 or more, where
// SaturationWarning would name that extreme (a clipped reading); sets
// (*clipped)[k] for each. Returns how many it set.
std::size_t MarkClipped(const ChannelValues& c, std::vector<char>* clipped);

// Removes the wrap-arounds of a [0, 360) or (-180, 180] recording: every jump
// of more than 180 deg between consecutive samples is taken as a wrap.
void UnwrapDegrees(std::vector<double>* deg);

}  // namespace triadcal

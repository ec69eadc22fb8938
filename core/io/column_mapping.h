// Our data channels, their units, and the `columns:` and `mounting:` sections
// of run.yaml that map a foreign file onto them.
//
//   columns:
//     t: all_time                          # a name: column (CSV) or variable (MAT)
//     lambda1: {source: enc, unit: deg, scale: -1, offset: 12.5}
//     lambda2: {value: 0}                  # held constant (in the source unit)
//     wx: {var: acc_x, unit: g}            # `var` is a synonym of `source`
//     label: part                          # optional text column: position label
//   mounting:
//     axes: ["+y", "-z", "-x"]  # platform x = +IMU y, platform y = -IMU z, z = -IMU x
//   positions:                  # optional, with label: which IMU direction points up
//     x_p: "+x"                 # (default: the Ferraris convention, see below)
//     tilted: [0.7071, 0, 0.7071]
//
// A channel value is  our = source * unit_factor * scale + offset, in our units
// (t: s, angles: deg, rates: deg/s, readings: mV, temp_C: degC, gyro: deg/s),
// then SI. Source units: t s|ms; angles deg|rad; rates deg/s|rad/s; readings
// mV|V|g|mg; temp_C C; gyro gx gy gz deg/s|rad/s|counts (counts with
// counts_per_dps: {source: gyr_x, unit: counts, counts_per_dps: 131}).
// Readings in g, mg or m/s^2 (at standard gravity) become mg, so the triad's
// nominal scale is then 1000 per g (and the bias 0); readings in counts
// ({unit: counts, counts_per_g: 16384}) stay counts, and the nominal scale is
// counts_per_g. Output units are named for what was read (ReadingsUnit).
// The readings channels wx, wy, wz and the gyro channels gx, gy, gz are the
// IMU's own axes; the mounting turns both into the platform frame
// (docs/method.md) after the mapping.
#pragma once

#include <yaml-cpp/yaml.h>

#include <map>
#include <string>
#include <vector>

#include "core/model/run_description.h"
#include "core/io/yaml_fields.h"

namespace triadcal {

enum class ChannelKind { kTime, kAngle, kRate, kReading, kTemperature, kGyro };

struct ChannelInfo {
  std::string name;  // t, lambda1, ..., as in the CSV contract
  ChannelKind kind;
  bool required;
};

// The channels of the CSV contract, in its column order, then the optional
// gyro channels gx, gy, gz (SPEC section 10).
const std::vector<ChannelInfo>& Channels();
const ChannelInfo* FindChannel(const std::string& name);  // nullptr if unknown

// The unit of our files for a kind ("s", "deg", "deg/s", "mV", "C", "deg/s"), the
// allowed source units, and the factor from a source unit to ours (0 if the
// unit is not allowed for the kind).
std::string DefaultUnit(ChannelKind kind);
std::vector<std::string> AllowedUnits(ChannelKind kind);
double OurUnitsPerSourceUnit(ChannelKind kind, const std::string& unit);

// The optional text channel `label` (a position label per sample) is kept in
// the same map under kLabelChannel, with only `source` set.
std::map<std::string, ColumnSource> ParseColumns(const YAML::Node& node, const YamlPlace& at);
void ParseMounting(const YAML::Node& node, const YamlPlace& at, RunDescription* run);

constexpr const char* kLabelChannel = "label";
// The source column of the label channel, or "" when the run has none.
std::string LabelSource(const RunDescription& run);

// positions: {LABEL: "+x" | [x, y, z] | none} -> unit vectors in IMU axes;
// `none` (a zero vector) declares a label that is no still position (a
// rotation between positions). Two positions within kSamePositionDeg of each
// other are an error.
std::map<std::string, Eigen::Vector3d> ParsePositions(const YAML::Node& node, const YamlPlace& at);
constexpr double kSamePositionDeg = 5.0;
// The Ferraris convention (imucal): x_p means +x points up and reads +1 g,
// x_a that it points down; the same for y and z. Other labels are not positions.
const std::map<std::string, Eigen::Vector3d>& DefaultLabelPositions();
// run.positions, or the default when it is empty.
const std::map<std::string, Eigen::Vector3d>& PositionsOf(const RunDescription& run);
// An IMU-axes vector in the platform frame, through run.mounting (as the readings).
Eigen::Vector3d ImuToPlatform(const RunDescription& run, const Eigen::Vector3d& v_imu);

// Where channel `name` comes from: the `columns` entry or the contract name.
ColumnSource SourceOf(const RunDescription& run, const std::string& name);

// The unit the readings are in after the mapping, for naming the output units
// (scale "UNIT/g", bias "UNIT"): "counts" when read in counts, "mg" when read
// in g, mg or m/s^2 (1000 per g), "mV" otherwise (mV, V).
std::string ReadingsUnit(const RunDescription& run);

// +1 for a proper rotation, -1 for a reflection.
int MountingDeterminant(const RunDescription& run);
bool IsIdentityMounting(const RunDescription& run);
// "+y" style text of platform axis i.
std::string MountingAxisText(const RunDescription& run, int i);

void EmitColumns(const std::map<std::string, ColumnSource>& columns, YAML::Emitter* out);

}  // namespace triadcal

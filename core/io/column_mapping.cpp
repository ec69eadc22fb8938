// Channel table, unit factors, and parsing/writing of `columns:` and `mounting:`.
#include "core/io/column_mapping.h"

#include <cmath>

#include "core/io/file_util.h"
#include "core/model/errors.h"
#include "core/model/units.h"

namespace triadcal {

namespace {

const char* kAxisNames = "xyz";

std::string JoinNames(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

ColumnSource ParseOneColumn(const ChannelInfo& ch, const YAML::Node& node, const YamlPlace& at) {
  ColumnSource c;
  c.unit = DefaultUnit(ch.kind);
  if (node.IsScalar()) {
    c.source = node.Scalar();
    if (c.source.empty()) at.Fail("empty column name");
    double number = 0.0;
    if (node.Tag() == "?" && YAML::convert<double>::decode(node, number)) {
      at.Fail("got the number " + c.source + "; write {value: " + c.source +
              "} for a constant channel, or quote a column named \"" + c.source + "\"");
    }
    return c;
  }
  if (!node.IsMap()) {
    at.Fail(
        "expected a column name or a map {source: NAME, unit: ..., scale: ..., offset: ...}, "
        "got " +
        DescribeNode(node));
  }
  // The count scale of a channel in counts: per g for the accelerometer's
  // readings, per deg/s for the gyro's.
  const bool gyro = ch.kind == ChannelKind::kGyro;
  const char* counts_key = gyro ? "counts_per_dps" : "counts_per_g";
  CheckKeys(node, at, {"source", "var", "unit", "scale", "offset", "value", counts_key});
  int given = 0;
  for (const char* key : {"source", "var"}) {
    if (node[key]) {
      c.source = ReadString(node[key], at.Child(key));
      if (c.source.empty()) at.Child(key).Fail("empty column name");
      ++given;
    }
  }
  if (node["value"]) {
    c.constant = ReadNumber(node["value"], at.Child("value"));
    ++given;
  }
  if (given != 1) at.Fail("give exactly one of source, var or value");
  if (node["unit"]) {
    c.unit = ReadString(node["unit"], at.Child("unit"));
    if (OurUnitsPerSourceUnit(ch.kind, c.unit) == 0.0) {
      at.Child("unit").Fail("unknown unit '" + c.unit + "' for " + ch.name +
                            " (allowed: " + JoinNames(AllowedUnits(ch.kind)) + ")");
    }
  }
  if (node["scale"]) {
    c.scale = ReadNumber(node["scale"], at.Child("scale"));
    if (c.scale == 0.0) at.Child("scale").Fail("must not be 0");
  }
  if (node["offset"]) c.offset = ReadNumber(node["offset"], at.Child("offset"));
  if (node[counts_key]) {
    if (c.unit != "counts") at.Child(counts_key).Fail("only with unit: counts");
    const double per = ReadPositive(node[counts_key], at.Child(counts_key));
    (gyro ? c.counts_per_dps : c.counts_per_g) = per;
  } else if (c.unit == "counts") {
    at.Fail(gyro ? "gyro readings in counts need their count scale: counts_per_dps (e.g. 131)"
                 : "readings in counts need their count scale: counts_per_g (e.g. 16384)");
  }
  return c;
}

// columns.label: a column name, or {source: NAME} (no unit, scale or offset).
ColumnSource ParseLabelColumn(const YAML::Node& node, const YamlPlace& at) {
  ColumnSource c;
  if (node.IsMap()) {
    CheckKeys(node, at, {"source"});
    if (!node["source"]) at.Fail("expected {source: NAME}");
    c.source = ReadString(node["source"], at.Child("source"));
  } else {
    c.source = ReadString(node, at);
  }
  if (c.source.empty()) at.Fail("empty column name");
  return c;
}

}  // namespace

const std::vector<ChannelInfo>& Channels() {
  static const std::vector<ChannelInfo> channels = {
      {"t", ChannelKind::kTime, true},
      {"lambda1", ChannelKind::kAngle, true},
      {"lambda2", ChannelKind::kAngle, true},
      {"wx", ChannelKind::kReading, true},
      {"wy", ChannelKind::kReading, true},
      {"wz", ChannelKind::kReading, true},
      {"lambda1_rate", ChannelKind::kRate, false},
      {"lambda2_rate", ChannelKind::kRate, false},
      {"temp_C", ChannelKind::kTemperature, false},
      {"gx", ChannelKind::kGyro, false},
      {"gy", ChannelKind::kGyro, false},
      {"gz", ChannelKind::kGyro, false},
  };
  return channels;
}

const ChannelInfo* FindChannel(const std::string& name) {
  for (const ChannelInfo& c : Channels()) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

std::string DefaultUnit(ChannelKind kind) { return AllowedUnits(kind).front(); }

std::vector<std::string> AllowedUnits(ChannelKind kind) {
  switch (kind) {
    case ChannelKind::kTime:
      return {"s", "ms"};
    case ChannelKind::kAngle:
      return {"deg", "rad"};
    case ChannelKind::kRate:
      return {"deg/s", "rad/s"};
    case ChannelKind::kReading:
      return {"mV", "V", "g", "mg", "m/s^2", "m/s\u00b2", "counts"};
    case ChannelKind::kTemperature:
      return {"C"};
    case ChannelKind::kGyro:
      return {"deg/s", "rad/s", "counts"};
  }
  return {};
}

double OurUnitsPerSourceUnit(ChannelKind kind, const std::string& unit) {
  const std::string u = unit.empty() ? DefaultUnit(kind) : unit;
  switch (kind) {
    case ChannelKind::kTime:
      return u == "s" ? 1.0 : u == "ms" ? kMsToS : 0.0;
    case ChannelKind::kAngle:
      return u == "deg" ? 1.0 : u == "rad" ? 1.0 / kDegToRad : 0.0;
    case ChannelKind::kRate:
      return u == "deg/s" ? 1.0 : u == "rad/s" ? 1.0 / kDegToRad : 0.0;
    case ChannelKind::kReading:
      // g and mg: 1 g = 1000 mV, i.e. a nominal scale of 1000 mV/g.
      // m/s^2: at standard gravity, as accelerometer datasheets. counts stay counts
      // (the triad's nominal scale is then counts_per_g, in counts/g).
      if (u == "m/s^2" || u == "m/s\u00b2") return 1000.0 / kStandardGravity;
      if (u == "counts") return 1.0;
      return u == "mV" ? 1.0 : u == "V" ? 1000.0 : u == "g" ? 1000.0 : u == "mg" ? 1.0 : 0.0;
    case ChannelKind::kTemperature:
      return u == "C" ? 1.0 : 0.0;
    case ChannelKind::kGyro:
      // counts: divided by the column's counts_per_dps when read (run_io.cpp).
      if (u == "counts") return 1.0;
      return u == "deg/s" ? 1.0 : u == "rad/s" ? 1.0 / kDegToRad : 0.0;
  }
  return 0.0;
}

std::map<std::string, ColumnSource> ParseColumns(const YAML::Node& node, const YamlPlace& at) {
  std::map<std::string, ColumnSource> out;
  if (node.IsNull()) return out;
  std::vector<std::string> names;
  for (const ChannelInfo& c : Channels()) names.push_back(c.name);
  names.push_back(kLabelChannel);
  CheckKeys(node, at, names);
  for (const auto& kv : node) {
    const std::string name = KeyOf(kv.first, at);
    if (name == kLabelChannel) {
      out[name] = ParseLabelColumn(kv.second, at.Child(name));
      continue;
    }
    out[name] = ParseOneColumn(*FindChannel(name), kv.second, at.Child(name));
  }
  return out;
}

std::string LabelSource(const RunDescription& run) {
  auto it = run.columns.find(kLabelChannel);
  return it == run.columns.end() ? "" : it->second.source;
}

std::map<std::string, Eigen::Vector3d> ParsePositions(const YAML::Node& node,
                                                      const YamlPlace& at) {
  if (!node.IsMap() || node.size() == 0) {
    at.Fail("expected a map {LABEL: \"+x\" or [x, y, z]} of the direction that points up");
  }
  std::map<std::string, Eigen::Vector3d> out;
  for (const auto& kv : node) {
    const std::string label = KeyOf(kv.first, at);
    const YamlPlace p = at.Child(label);
    if (out.count(label)) p.Fail("given twice");
    Eigen::Vector3d v;
    if (kv.second.IsScalar() && kv.second.Scalar() == "none") {
      out[label] = Eigen::Vector3d::Zero();  // a label that is no still position
      continue;
    }
    if (kv.second.IsSequence()) {
      v = ReadVector3(kv.second, p);
      if (!(v.norm() > 0.0)) p.Fail("the up direction must not be [0, 0, 0]");
      v.normalize();
    } else {
      const std::string s = ReadString(kv.second, p);
      const int axis = s.size() == 2 && (s[0] == '+' || s[0] == '-')
                           ? static_cast<int>(std::string("xyz").find(s[1]))
                           : -1;
      if (axis < 0 || axis > 2) {
        p.Fail("expected +x, -x, +y, -y, +z, -z, a list [x, y, z] or none, got '" + Excerpt(s) +
               "'");
      }
      v.setZero();
      v[axis] = s[0] == '-' ? -1.0 : 1.0;
    }
    // Two positions pointing the same way hold one orientation twice: the
    // fit then has one direction less than it thinks (Kx 0 +- 160 mV/g from
    // two "+x" positions).
    for (const auto& [other, w] : out) {
      if (w.dot(v) > std::cos(kSamePositionDeg * kDegToRad)) {
        p.Fail("points the same way as positions." + other +
               " (two positions need two "
               "directions; one label written twice, or a sign lost?)");
      }
    }
    out[label] = v;
  }
  return out;
}

const std::map<std::string, Eigen::Vector3d>& DefaultLabelPositions() {
  static const std::map<std::string, Eigen::Vector3d> positions = {
      {"x_p", Eigen::Vector3d::UnitX()},  {"x_a", -Eigen::Vector3d::UnitX()},
      {"y_p", Eigen::Vector3d::UnitY()},  {"y_a", -Eigen::Vector3d::UnitY()},
      {"z_p", Eigen::Vector3d::UnitZ()},  {"z_a", -Eigen::Vector3d::UnitZ()},
  };
  return positions;
}

const std::map<std::string, Eigen::Vector3d>& PositionsOf(const RunDescription& run) {
  return run.positions.empty() ? DefaultLabelPositions() : run.positions;
}

Eigen::Vector3d ImuToPlatform(const RunDescription& run, const Eigen::Vector3d& v_imu) {
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = run.axis_sign[i] * v_imu[run.axis_source[i]];
  return v;
}

void ParseMounting(const YAML::Node& node, const YamlPlace& at, RunDescription* run) {
  CheckKeys(node, at, {"axes"});
  if (!node["axes"]) at.Fail("missing 'axes' (e.g. axes: [\"+y\", \"-z\", \"-x\"])");
  const YamlPlace axes_at = at.Child("axes");
  const YAML::Node axes = node["axes"];
  if (!axes.IsSequence() || axes.size() != 3) {
    axes_at.Fail(
        "expected a list of 3 signed IMU axes like [\"+y\", \"-z\", \"-x\"], got " +
        (axes.IsSequence() ? std::to_string(axes.size()) + " entries" : DescribeNode(axes)));
  }
  bool used[3] = {false, false, false};
  for (std::size_t i = 0; i < 3; ++i) {
    const std::string s = ReadString(axes[i], axes_at.Index(i));
    std::string letter = s;
    double sign = 1.0;
    if (!s.empty() && (s[0] == '+' || s[0] == '-')) {
      sign = s[0] == '-' ? -1.0 : 1.0;
      letter = s.substr(1);
    }
    int src = -1;
    if (letter == "x" || letter == "X") src = 0;
    if (letter == "y" || letter == "Y") src = 1;
    if (letter == "z" || letter == "Z") src = 2;
    if (src < 0) axes_at.Index(i).Fail("expected +x, -x, +y, -y, +z or -z, got '" + s + "'");
    if (used[src]) {
      axes_at.Fail(std::string("IMU axis ") + kAxisNames[src] +
                   " used twice: the axes must be a signed permutation of x, y, z");
    }
    used[src] = true;
    run->axis_source[i] = src;
    run->axis_sign[i] = sign;
  }
  if (MountingDeterminant(*run) < 0) {
    RunDescription flipped = *run;
    flipped.axis_sign[2] = -flipped.axis_sign[2];
    const std::string axes = "[" + MountingAxisText(*run, 0) + ", " + MountingAxisText(*run, 1) +
                             ", " + MountingAxisText(*run, 2) + "]";
    axes_at.Fail(axes + " is a reflection (determinant -1), not a rotation: flip the sign of "
                 "one axis (e.g. [" + MountingAxisText(flipped, 0) + ", " +
                 MountingAxisText(flipped, 1) + ", " + MountingAxisText(flipped, 2) + "])");
  }
}

ColumnSource SourceOf(const RunDescription& run, const std::string& name) {
  auto it = run.columns.find(name);
  if (it != run.columns.end()) return it->second;
  ColumnSource c;
  c.source = name;
  c.unit = DefaultUnit(FindChannel(name)->kind);
  return c;
}

std::string ReadingsUnit(const RunDescription& run) {
  std::string unit;
  for (const char* ch : {"wx", "wy", "wz"}) {
    const std::string u = SourceOf(run, ch).unit;
    const std::string named = u == "counts" ? "counts"
                              : (u == "g" || u == "mg" || u == "m/s^2" || u == "m/s\u00b2") ? "mg"
                                                                                          : "mV";
    if (!unit.empty() && named != unit) return "mV";  // mixed: the parser refuses counts mixed
    unit = named;
  }
  return unit;
}

int MountingDeterminant(const RunDescription& run) {
  // det of the signed permutation matrix P (row i has axis_sign[i] at column axis_source[i]).
  int inversions = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = i + 1; j < 3; ++j) inversions += run.axis_source[i] > run.axis_source[j];
  }
  double det = inversions % 2 ? -1.0 : 1.0;
  for (int i = 0; i < 3; ++i) det *= run.axis_sign[i];
  return det > 0 ? 1 : -1;
}

bool IsIdentityMounting(const RunDescription& run) {
  for (int i = 0; i < 3; ++i) {
    if (run.axis_source[i] != i || run.axis_sign[i] != 1.0) return false;
  }
  return true;
}

std::string MountingAxisText(const RunDescription& run, int i) {
  return std::string(run.axis_sign[i] < 0 ? "-" : "+") + kAxisNames[run.axis_source[i]];
}

void EmitColumns(const std::map<std::string, ColumnSource>& columns, YAML::Emitter* out) {
  *out << YAML::BeginMap;
  if (auto it = columns.find(kLabelChannel); it != columns.end()) {
    *out << YAML::Key << kLabelChannel << YAML::Value << YAML::DoubleQuoted << it->second.source;
  }
  for (const ChannelInfo& ch : Channels()) {
    auto it = columns.find(ch.name);
    if (it == columns.end()) continue;
    const ColumnSource& c = it->second;
    const std::string unit = c.unit.empty() ? DefaultUnit(ch.kind) : c.unit;
    *out << YAML::Key << ch.name << YAML::Value;
    const bool plain =
        !c.constant && unit == DefaultUnit(ch.kind) && c.scale == 1.0 && c.offset == 0.0;
    if (plain) {
      *out << YAML::DoubleQuoted << c.source;
      continue;
    }
    *out << YAML::Flow << YAML::BeginMap;
    if (c.constant) {
      *out << YAML::Key << "value" << YAML::Value << FormatDouble(*c.constant);
    } else {
      *out << YAML::Key << "source" << YAML::Value << YAML::DoubleQuoted << c.source;
    }
    if (unit != DefaultUnit(ch.kind)) *out << YAML::Key << "unit" << YAML::Value << unit;
    if (c.scale != 1.0) *out << YAML::Key << "scale" << YAML::Value << FormatDouble(c.scale);
    if (c.offset != 0.0) *out << YAML::Key << "offset" << YAML::Value << FormatDouble(c.offset);
    if (c.counts_per_g) {
      *out << YAML::Key << "counts_per_g" << YAML::Value << FormatDouble(*c.counts_per_g);
    }
    if (c.counts_per_dps) {
      *out << YAML::Key << "counts_per_dps" << YAML::Value << FormatDouble(*c.counts_per_dps);
    }
    *out << YAML::EndMap;
  }
  *out << YAML::EndMap;
}

}  // namespace triadcal

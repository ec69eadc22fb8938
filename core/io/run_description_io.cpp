// run.yaml in and out (docs/file-formats.md): the bench and triad nominal values, the
// constraints, and the column mapping and mounting for foreign data files.
#include "core/io/run_description_io.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>

#include "core/io/column_mapping.h"
#include "core/io/constraint_parser.h"
#include "core/io/data_table.h"
#include "core/io/file_util.h"
#include "core/io/plausibility.h"
#include "core/io/yaml_fields.h"
#include "core/model/errors.h"

namespace triadcal {

namespace {

void ParseBench(const YAML::Node& node, const YamlPlace& at, RunDescription* run) {
  CheckKeys(node, at,
            {"lever_arm_mm", "angle_noise_arcsec", "g_mps2", "latitude_deg", "heading_deg"});
  if (node["lever_arm_mm"]) {
    run->lever_arm0_m = ReadVector3(node["lever_arm_mm"], at.Child("lever_arm_mm")) * kMmToM;
  }
  if (node["angle_noise_arcsec"]) {
    run->angle_noise_rad =
        ReadNonNegative(node["angle_noise_arcsec"], at.Child("angle_noise_arcsec")) * kArcsecToRad;
  }
  if (node["g_mps2"]) run->g_mps2 = ReadPositive(node["g_mps2"], at.Child("g_mps2"));
  // latitude_deg and heading_deg (the azimuth of the outer axis, L's y, from
  // north towards east): Earth's rate in the gyro's input rate. One without
  // the other cannot place Earth's rate.
  const bool latitude = bool(node["latitude_deg"]), heading = bool(node["heading_deg"]);
  if (latitude != heading) {
    const char* given = latitude ? "latitude_deg" : "heading_deg";
    const char* missing = latitude ? "heading_deg" : "latitude_deg";
    at.Child(given).Fail(std::string("given without bench.") + missing +
                         " (Earth's rate needs both; give both, or neither)");
  }
  if (latitude) {
    const YamlPlace p = at.Child("latitude_deg");
    const double lat = ReadNumber(node["latitude_deg"], p);
    if (!(lat >= -90.0 && lat <= 90.0)) {
      p.Fail("must be within [-90, 90] deg, got " + FormatDouble(lat));
    }
    run->latitude_rad = lat * kDegToRad;
    run->heading_rad = ReadNumber(node["heading_deg"], at.Child("heading_deg")) * kDegToRad;
  }
}

// noise_mV: a number (every channel), [x, y, z] (per channel) or `auto`
// (estimated from the run's residuals).
void ParseNoise(const YAML::Node& node, const YamlPlace& at, RunDescription* run) {
  if (node.IsScalar() && node.Scalar() == "auto") {
    run->noise_auto = true;
    return;
  }
  if (node.IsSequence()) {
    const Eigen::Vector3d v = ReadVector3(node, at);
    for (int i = 0; i < 3; ++i) {
      if (!(v[i] > 0.0)) at.Index(i).Fail("must be > 0, got " + FormatDouble(v[i]));
    }
    run->noise_channel_mV = v;
    run->noise_mV = std::sqrt(v.squaredNorm() / 3.0);
    return;
  }
  run->noise_mV = ReadPositive(node, at);
}

void ParseTriad(const YAML::Node& node, const YamlPlace& at, RunDescription* run) {
  CheckKeys(node, at, {"scale_mV_per_g", "bias_mV", "noise_mV"});
  if (node["scale_mV_per_g"]) {
    const YamlPlace p = at.Child("scale_mV_per_g");
    run->scale_mV_per_g = ReadVector3(node["scale_mV_per_g"], p);
    for (int i = 0; i < 3; ++i) {
      if (!(run->scale_mV_per_g[i] > 0.0)) {
        p.Index(i).Fail("must be > 0, got " + FormatDouble(run->scale_mV_per_g[i]) +
                        " (an inverted axis belongs in mounting.axes)");
      }
    }
  }
  if (node["bias_mV"]) run->bias_mV = ReadVector3(node["bias_mV"], at.Child("bias_mV"));
  if (node["noise_mV"]) ParseNoise(node["noise_mV"], at.Child("noise_mV"), run);
}

// gyro: {scale: [x, y, z], bias_dps: [x, y, z], noise_dps: N | [x, y, z] | auto}
// (SPEC section 10): the nominal gyro, SI inside. A scale may be negative (an
// axis of the gyro reversed against the accelerometer's) but not 0.
GyroDescription ParseGyro(const YAML::Node& node, const YamlPlace& at) {
  CheckKeys(node, at, {"scale", "bias_dps", "noise_dps"});
  GyroDescription g;
  if (node["scale"]) {
    const YamlPlace p = at.Child("scale");
    g.scale = ReadVector3(node["scale"], p);
    for (int i = 0; i < 3; ++i) {
      if (g.scale[i] == 0.0) p.Index(i).Fail("must not be 0 (readings per deg/s; nominal 1)");
    }
  }
  if (node["bias_dps"]) {
    g.bias_rad_s = ReadVector3(node["bias_dps"], at.Child("bias_dps")) * kDegToRad;
  }
  if (node["noise_dps"]) {
    const YamlPlace p = at.Child("noise_dps");
    const YAML::Node n = node["noise_dps"];
    if (n.IsScalar() && n.Scalar() == "auto") {
      g.noise_auto = true;
    } else if (n.IsSequence()) {
      const Eigen::Vector3d v = ReadVector3(n, p);
      for (int i = 0; i < 3; ++i) {
        if (!(v[i] > 0.0)) p.Index(i).Fail("must be > 0, got " + FormatDouble(v[i]));
      }
      g.noise_rad_s = v * kDegToRad;
    } else {
      g.noise_rad_s = Eigen::Vector3d::Constant(ReadPositive(n, p) * kDegToRad);
    }
  }
  return g;
}

// Readings in g or mg become mV at 1000 mV/g: without a triad section saying
// otherwise, the nominal triad is then 1000 mV/g with no bias.
void DefaultTriadForGReadings(const YAML::Node& triad, RunDescription* run) {
  const char* channels[3] = {"wx", "wy", "wz"};
  int in_g = 0, in_counts = 0;
  for (const char* ch : channels) {
    const std::string unit = SourceOf(*run, ch).unit;
    in_g += unit == "g" || unit == "mg" || unit == "m/s^2" || unit == "m/s\u00b2";
    in_counts += unit == "counts";
  }
  if (in_counts > 0 && in_counts < 3) {
    throw InputError(run->yaml_path + ": columns: readings in counts and in other units cannot "
                                      "be mixed (give all three in counts)");
  }
  if (in_g < 3 && in_counts < 3) return;
  for (int i = 0; i < 3; ++i) {
    const ColumnSource src = SourceOf(*run, channels[run->axis_source[i]]);
    const double implied = in_counts == 3 ? *src.counts_per_g : 1000.0;
    if (!triad || !triad["scale_mV_per_g"]) {
      run->scale_mV_per_g[i] = implied;
      continue;
    }
    // A nominal scale factor is the readings' own gain: readings in g are
    // taken at 1000 mV/g (counts at the column's counts_per_g), so a nominal
    // far from that is one left over from another sensor (the README's
    // 174 mV/g with `unit: g`: Kx came out 35 +- 10 mg/g, exit 0).
    const double k = run->scale_mV_per_g[i];
    if (k < 0.5 * implied || k > 2.0 * implied) {
      char what[320];
      std::snprintf(what, sizeof(what),
                    ": triad.scale_mV_per_g[%d]: %s declared for readings in %s, which are "
                    "taken at %s per g; remove scale_mV_per_g or give the readings' own gain "
                    "(within a factor 2 of it)",
                    i, FormatDouble(k).c_str(), in_counts == 3 ? "counts" : src.unit.c_str(),
                    FormatDouble(implied).c_str());
      throw InputError(run->yaml_path + what);
    }
  }
  if (!triad || !triad["bias_mV"]) run->bias_mV.setZero();
}

YAML::Emitter& EmitVector(YAML::Emitter& out, const Eigen::Vector3d& v) {
  out << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < 3; ++i) out << FormatDouble(v[i]);
  return out << YAML::EndSeq;
}

// An SI value in a file unit (si_per_unit SI each) with the fewest digits that
// read back, as the parser does (value * si_per_unit), to exactly si: 0.02
// deg/s stays 0.02, not 0.020000000000000004.
std::string FormatInUnit(double si, double si_per_unit) {
  const double v = si / si_per_unit;
  for (int digits = 1; digits <= 17; ++digits) {
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
    const double d = std::strtod(buf, nullptr);
    if (d * si_per_unit == si) return FormatDouble(d);
  }
  return FormatDouble(v);
}

YAML::Emitter& EmitVectorInUnit(YAML::Emitter& out, const Eigen::Vector3d& si, double si_per_unit) {
  out << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < 3; ++i) out << FormatInUnit(si[i], si_per_unit);
  return out << YAML::EndSeq;
}

// priors: {NAME: SIGMA} in file units, for any base, effect or (with a gyro
// block) gyro parameter.
void ParsePriors(const YAML::Node& node, const YamlPlace& at, RunDescription* run) {
  if (!node.IsMap()) at.Fail("expected a map {parameter: sigma in file units}");
  std::vector<Effect> all;
  for (const EffectSpec& e : EffectCatalogue()) all.push_back(e.id);
  const ParameterLayout every(all, /*gyro=*/true);
  for (const auto& kv : node) {
    const std::string name = KeyOf(kv.first, at);
    const YamlPlace p = at.Child(name);
    const int i = every.IndexOf(name);
    if (i < 0) p.Fail("unknown parameter (see `triadcal params`)");
    if (every.is_gyro(i) && !run->gyro) {
      p.Fail("a gyro parameter, but this run has no gyro block");
    }
    run->prior_sigma[name] = ReadPositive(kv.second, p);
  }
}

// data_format: {header: [names...], sort_by_time: bool}, for text files.
void ParseDataFormat(const YAML::Node& node, const YamlPlace& at, RunDescription* run) {
  CheckKeys(node, at, {"header", "sort_by_time"});
  if (node["header"]) {
    const YamlPlace p = at.Child("header");
    const YAML::Node h = node["header"];
    if (!h.IsSequence() || h.size() == 0) {
      p.Fail("expected the list of column names of a file without a header line, got " +
             DescribeNode(h));
    }
    if (h.size() > kMaxColumns) {
      p.Fail(std::to_string(h.size()) + " column names, more than the bound " +
             std::to_string(kMaxColumns));
    }
    std::set<std::string> seen;
    for (std::size_t i = 0; i < h.size(); ++i) {
      const std::string name = ReadString(h[i], p.Index(i));
      if (name.empty()) p.Index(i).Fail("empty column name");
      if (!seen.insert(name).second) {
        p.Index(i).Fail("column name '" + Excerpt(name) + "' given twice");
      }
      run->data_header.push_back(name);
    }
  }
  if (node["sort_by_time"]) {
    const YamlPlace p = at.Child("sort_by_time");
    if (!node["sort_by_time"].IsScalar() ||
        !YAML::convert<bool>::decode(node["sort_by_time"], run->sort_by_time)) {
      p.Fail("expected true or false, got " + DescribeNode(node["sort_by_time"]));
    }
  }
}

// sensor: {serial: TEXT, model: TEXT}, both optional, for the provenance.
void ParseSensor(const YAML::Node& node, const YamlPlace& at, RunDescription* run) {
  CheckKeys(node, at, {"serial", "model"});
  if (node["serial"]) run->sensor_serial = ReadString(node["serial"], at.Child("serial"));
  if (node["model"]) run->sensor_model = ReadString(node["model"], at.Child("model"));
}

}  // namespace

RunDescription LoadRunDescription(const std::string& yaml_path) {
  const YAML::Node root = LoadYamlFile(yaml_path);
  const YamlPlace at{yaml_path, ""};
  if (!root.IsMap()) at.Fail("expected a map of keys (data, bench, triad, ...)");
  if (!root["data"]) {
    at.Child("data").Fail("missing: the data file (relative to this file, or shared:PATH)");
  }
  return ParseRunDescription(root, yaml_path, yaml_path);
}

RunDescription ParseRunDescription(const YAML::Node& node, const std::string& yaml_path,
                                   const std::string& where) {
  RunDescription run;
  run.yaml_path = yaml_path;
  run.constraints = DefaultConstraints();
  const YamlPlace at{where, ""};
  if (!node.IsDefined() || node.IsNull()) return run;
  CheckKeys(node, at,
            {"data", "bench", "triad", "gyro", "constraints", "columns", "mounting", "priors",
             "data_format", "positions", "sensor", "time_range_s", "temperature_C"});
  if (node["data"]) {
    const std::string data = ReadString(node["data"], at.Child("data"));
    if (data.empty()) at.Child("data").Fail("empty file name");
    run.data_path = ResolveDataPath(yaml_path, data);
    if (run.data_path.empty()) {
      at.Child("data").Fail("shared data folder not found for '" + data +
                            "' (set TRIADCAL_SHARED)");
    }
  }
  if (node["bench"]) ParseBench(node["bench"], at.Child("bench"), &run);
  if (node["triad"]) ParseTriad(node["triad"], at.Child("triad"), &run);
  if (node["gyro"]) run.gyro = ParseGyro(node["gyro"], at.Child("gyro"));
  if (node["constraints"]) {
    run.constraints = ParseConstraints(node["constraints"], at.Child("constraints"));
  }
  if (node["columns"]) run.columns = ParseColumns(node["columns"], at.Child("columns"));
  if (node["mounting"]) ParseMounting(node["mounting"], at.Child("mounting"), &run);
  if (node["priors"]) ParsePriors(node["priors"], at.Child("priors"), &run);
  if (node["data_format"]) ParseDataFormat(node["data_format"], at.Child("data_format"), &run);
  if (node["positions"]) run.positions = ParsePositions(node["positions"], at.Child("positions"));
  if (node["sensor"]) ParseSensor(node["sensor"], at.Child("sensor"), &run);
  if (node["time_range_s"]) {
    // time_range_s: [from, to]: only the samples with from <= t <= to (in the
    // time column's seconds), e.g. to fit the halves of a run separately.
    const YamlPlace p = at.Child("time_range_s");
    const YAML::Node& r = node["time_range_s"];
    if (!r.IsSequence() || r.size() != 2) {
      p.Fail("expected [from, to] in seconds, got " + DescribeNode(r));
    }
    run.time_range_s = {ReadNumber(r[0], p.Index(0)), ReadNumber(r[1], p.Index(1))};
    if (!(run.time_range_s->first < run.time_range_s->second)) {
      char got[96];
      std::snprintf(got, sizeof(got), "[%g, %g]", run.time_range_s->first,
                    run.time_range_s->second);
      p.Fail(std::string("from must be before to, got ") + got);
    }
  }
  if (node["temperature_C"]) {
    // The run's temperature, for a calibration with a temperature model
    // (docs/multi-run.md) when the data have no temp_C column.
    const YamlPlace p = at.Child("temperature_C");
    const double t = ReadNumber(node["temperature_C"], p);
    if (!(t >= -100.0 && t <= 200.0)) {
      p.Fail("expected a temperature of -100 to 200 degC, got " + FormatDouble(t));
    }
    run.temperature_C = t;
  }
  DefaultTriadForGReadings(node["triad"], &run);
  CheckDescriptionPlausible(run, where);
  return run;
}

std::string RunDescriptionToYaml(const RunDescription& run, const std::string& data_relative) {
  YAML::Emitter out;
  out << YAML::Comment("triadcal run description (docs/file-formats.md)") << YAML::Newline;
  out << YAML::BeginMap;
  out << YAML::Key << "data" << YAML::Value << data_relative;

  out << YAML::Key << "bench" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "lever_arm_mm" << YAML::Value;
  EmitVector(out, run.lever_arm0_m / kMmToM);
  out << YAML::Key << "angle_noise_arcsec" << YAML::Value
      << FormatDouble(run.angle_noise_rad / kArcsecToRad);
  if (run.g_mps2 != kStandardGravity) {
    out << YAML::Key << "g_mps2" << YAML::Value << FormatDouble(run.g_mps2);
  }
  if (run.latitude_rad && run.heading_rad) {
    out << YAML::Key << "latitude_deg" << YAML::Value << FormatInUnit(*run.latitude_rad, kDegToRad);
    out << YAML::Key << "heading_deg" << YAML::Value << FormatInUnit(*run.heading_rad, kDegToRad);
  }
  out << YAML::EndMap;

  out << YAML::Key << "triad" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "scale_mV_per_g" << YAML::Value;
  EmitVector(out, run.scale_mV_per_g);
  out << YAML::Key << "bias_mV" << YAML::Value;
  EmitVector(out, run.bias_mV);
  if (run.noise_auto) {
    out << YAML::Key << "noise_mV" << YAML::Value << "auto";
  } else if (run.noise_channel_mV) {
    out << YAML::Key << "noise_mV" << YAML::Value;
    EmitVector(out, *run.noise_channel_mV);
  } else {
    out << YAML::Key << "noise_mV" << YAML::Value << FormatDouble(run.noise_mV);
  }
  out << YAML::EndMap;

  if (run.gyro) {
    const GyroDescription& g = *run.gyro;
    out << YAML::Key << "gyro" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "scale" << YAML::Value;
    EmitVector(out, g.scale);
    out << YAML::Key << "bias_dps" << YAML::Value;
    EmitVectorInUnit(out, g.bias_rad_s, kDegToRad);
    out << YAML::Key << "noise_dps" << YAML::Value;
    const Eigen::Vector3d& noise = g.noise_rad_s;
    if (g.noise_auto) {
      out << "auto";
    } else if (noise[0] == noise[1] && noise[1] == noise[2]) {
      out << FormatInUnit(noise[0], kDegToRad);
    } else {
      EmitVectorInUnit(out, noise, kDegToRad);
    }
    out << YAML::EndMap;
  }

  out << YAML::Key << "constraints" << YAML::Value;
  if (run.constraints.empty()) {
    out << YAML::Flow << YAML::BeginSeq << YAML::EndSeq;
  } else {
    out << YAML::BeginSeq;
    for (const Constraint& c : run.constraints) EmitConstraint(c, &out);
    out << YAML::EndSeq;
  }

  if (!run.columns.empty()) {
    out << YAML::Key << "columns" << YAML::Value;
    EmitColumns(run.columns, &out);
  }
  if (!run.prior_sigma.empty()) {
    out << YAML::Key << "priors" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, sigma] : run.prior_sigma) {
      out << YAML::Key << name << YAML::Value << FormatDouble(sigma);
    }
    out << YAML::EndMap;
  }
  if (!run.data_header.empty() || run.sort_by_time) {
    out << YAML::Key << "data_format" << YAML::Value << YAML::BeginMap;
    if (!run.data_header.empty()) {
      out << YAML::Key << "header" << YAML::Value << YAML::Flow << run.data_header;
    }
    if (run.sort_by_time) out << YAML::Key << "sort_by_time" << YAML::Value << true;
    out << YAML::EndMap;
  }
  if (!run.positions.empty()) {
    out << YAML::Key << "positions" << YAML::Value << YAML::BeginMap;
    for (const auto& [label, up] : run.positions) {
      out << YAML::Key << label << YAML::Value;
      if (up.isZero()) {
        out << "none";
      } else {
        EmitVector(out, up);
      }
    }
    out << YAML::EndMap;
  }
  if (!IsIdentityMounting(run)) {
    out << YAML::Key << "mounting" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "axes" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int i = 0; i < 3; ++i) out << YAML::DoubleQuoted << MountingAxisText(run, i);
    out << YAML::EndSeq << YAML::EndMap;
  }
  if (!run.sensor_serial.empty() || !run.sensor_model.empty()) {
    out << YAML::Key << "sensor" << YAML::Value << YAML::BeginMap;
    if (!run.sensor_serial.empty()) {
      out << YAML::Key << "serial" << YAML::Value << YAML::DoubleQuoted << run.sensor_serial;
    }
    if (!run.sensor_model.empty()) {
      out << YAML::Key << "model" << YAML::Value << YAML::DoubleQuoted << run.sensor_model;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (!out.good()) throw std::logic_error("run.yaml emitter: " + out.GetLastError());
  return std::string(out.c_str()) + "\n";
}

}  // namespace triadcal

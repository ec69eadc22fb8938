// Run data in and out: reads the data file of a run.yaml (text or MATLAB),
// maps its columns onto our channels, converts units, unwraps the angles,
// validates, applies the IMU mounting (to the accelerometer's readings and the
// gyro's alike), and writes the CSV contract back.
#include "core/io/run_io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <utility>

#include "core/io/column_mapping.h"
#include "core/io/data_table.h"
#include "core/model/errors.h"
#include "core/model/sample_noise.h"
#include "core/io/file_util.h"
#include "core/io/plausibility.h"
#include "core/io/run_validation.h"
#include "core/model/units.h"

namespace triadcal {

namespace {

namespace fs = std::filesystem;

bool IsMatFile(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".mat";
}

// The names of a file's columns or variables for a message: each an
// excerpt, at most 12 of them (a header line may be anything: a binary file,
// /proc/self/environ, a million names).
std::string JoinNames(const std::vector<std::string>& v) {
  std::string s;
  const std::size_t shown = std::min<std::size_t>(v.size(), 12);
  for (std::size_t i = 0; i < shown; ++i) s += (i ? ", " : "") + Excerpt(v[i], 40);
  if (shown < v.size()) s += ", ... (" + std::to_string(v.size()) + " in all)";
  return s;
}

std::string Label(const DataTable& table, const std::string& name, const ColumnSource& src) {
  if (src.constant) return name + " (constant)";
  std::string s = (table.is_mat ? "variable '" : "column '") + Excerpt(src.source) + "'";
  return src.source == name ? s : s + " (" + name + ")";
}

[[noreturn]] void MissingColumn(const DataTable& table, const std::string& name,
                                const ColumnSource& src) {
  const std::string what = src.source == name ? "" : " (for " + name + ")";
  if (table.is_mat) {
    throw InputError(table.path + ": variable '" + Excerpt(src.source) + "'" + what +
                     " not found (the file has: " + JoinNames(table.names) + ")");
  }
  throw InputError(table.path + ":" + std::to_string(table.header_line) + ": missing column '" +
                   Excerpt(src.source) + "'" + what + " (header: " + JoinNames(table.names) + ")");
}

// Channel `name` in our units, or empty values when it is optional and absent.
// The channel's column is moved out of the table when no other channel is
// still to read it (uses: the channels left per source): a long run is not
// held twice.
ChannelValues ReadChannel(DataTable& table, std::map<std::string, int>& uses,
                          const RunDescription& run, const ChannelInfo& ch) {
  const ColumnSource src = SourceOf(run, ch.name);
  ChannelValues out;
  out.name = ch.name;
  out.label = Label(table, ch.name, src);
  double factor = OurUnitsPerSourceUnit(ch.kind, src.unit) * src.scale;
  if (src.counts_per_dps) factor /= *src.counts_per_dps;  // gyro counts -> deg/s
  if (factor == 0.0) {
    throw InputError(run.yaml_path + ": columns." + ch.name + ": unit '" + src.unit +
                     "' or scale 0 not allowed");
  }
  if (src.constant) {
    out.values.assign(table.rows, *src.constant * factor + src.offset);
    return out;
  }
  auto it = table.columns.find(src.source);
  if (it == table.columns.end()) {
    if (ch.required || run.columns.count(ch.name)) MissingColumn(table, ch.name, src);
    return out;
  }
  if (--uses[src.source] <= 0) {
    out.values = std::move(it->second);
  } else {
    out.values = it->second;
  }
  if (factor != 1.0 || src.offset != 0.0) {
    for (double& v : out.values) v = v * factor + src.offset;
  }
  return out;
}

// Keeps rows keep[0], keep[1], ... in that order (a selection or a permutation).
template <typename V>
void KeepRows(const std::vector<std::size_t>& keep, std::vector<V>* values) {
  if (values->empty()) return;
  std::vector<V> out(keep.size());
  for (std::size_t j = 0; j < keep.size(); ++j) out[j] = std::move((*values)[keep[j]]);
  values->swap(out);
}

void KeepRows(const std::vector<std::size_t>& keep, ChannelValues* c) {
  KeepRows(keep, &c->values);
}

void Warn(RunWarnings* warnings, const std::optional<std::string>& line) {
  if (warnings && line) warnings->lines.push_back(*line);
}

bool IsGyroChannel(const ChannelInfo& ch) { return ch.kind == ChannelKind::kGyro; }

// Whether channel `name` is in the file (or held constant by the mapping).
bool InTable(const DataTable& table, const RunDescription& run, const std::string& name) {
  const ColumnSource src = SourceOf(run, name);
  if (src.constant) return true;
  return std::find(table.names.begin(), table.names.end(), src.source) != table.names.end();
}

// A run with a gyro block needs the three gyro channels: the ones the file
// lacks, in one line.
void CheckGyroColumnsPresent(const DataTable& table, const RunDescription& run) {
  std::vector<std::string> missing;
  for (const char* name : {"gx", "gy", "gz"}) {
    if (InTable(table, run, name)) continue;
    const ColumnSource src = SourceOf(run, name);
    missing.push_back("'" + Excerpt(src.source) + "'" +
                      (src.source == name ? "" : " (" + std::string(name) + ")"));
  }
  if (missing.empty()) return;
  std::string list;
  for (const std::string& m : missing) list += (list.empty() ? "" : ", ") + m;
  const std::string what = missing.size() == 1 ? "" : "s";
  const std::string why = " (run.yaml has a gyro block: give gx, gy and gz, or remove the block; ";
  if (table.is_mat) {
    throw InputError(table.path + ": gyro variable" + what + " " + list + " not found" + why +
                     "the file has: " + JoinNames(table.names) + ")");
  }
  throw InputError(table.path + ":" + std::to_string(table.header_line) + ": missing gyro column" +
                   what + " " + list + why + "header: " + JoinNames(table.names) + ")");
}

std::vector<double> Scaled(std::vector<double>&& v, double factor) {
  for (double& x : v) x *= factor;
  return std::move(v);
}

void AppendDouble(double x, std::string* out) {
  char buf[32];  // the same shortest round-trip text as FormatDouble
  const auto res = std::to_chars(buf, buf + sizeof(buf), x);
  out->append(buf, res.ptr);
}

}  // namespace

RunData LoadRunData(const RunDescription& run, RunWarnings* warnings, int threads) {
  const std::string where = run.yaml_path.empty() ? run.data_path : run.yaml_path + ": data";
  if (run.data_path.empty()) throw InputError(where + ": no data file given");
  const std::string problem = InputFileProblem(run.data_path);
  if (problem == "no such file") {
    throw InputError(where + ": no such file '" + PathForMessage(run.data_path) + "'");
  }
  if (!problem.empty()) {
    throw InputError(where + ": cannot read '" + PathForMessage(run.data_path) + "': " + problem);
  }

  // Read the columns the mapping asks for.
  std::vector<std::string> wanted;
  std::map<std::string, int> uses;  // channels per source column
  for (const ChannelInfo& ch : Channels()) {
    if (IsGyroChannel(ch) && !run.gyro) continue;  // not calibrated: not read
    const ColumnSource src = SourceOf(run, ch.name);
    if (!src.constant) {
      wanted.push_back(src.source);
      ++uses[src.source];
    }
  }
  const std::string label_source = LabelSource(run);
  if (IsMatFile(run.data_path) && (!label_source.empty() || !run.data_header.empty())) {
    throw InputError(run.yaml_path + ": " +
                     (label_source.empty() ? "data_format.header" : "columns.label") +
                     ": only for text data files, not MATLAB");
  }
  TextTableOptions text_options;
  text_options.header = run.data_header;
  text_options.threads = threads;
  if (!label_source.empty()) text_options.wanted_text.push_back(label_source);
  DataTable table = IsMatFile(run.data_path)
                              ? ReadMatTable(run.data_path, wanted)
                              : ReadTextTable(run.data_path, wanted, text_options);
  std::vector<std::string> labels;
  if (!label_source.empty()) {
    auto it = table.text_columns.find(label_source);
    if (it == table.text_columns.end()) {
      ColumnSource src;
      src.source = label_source;
      MissingColumn(table, kLabelChannel, src);
    }
    labels = std::move(it->second);
  }
  // t, l1, l2, wx, wy, wz, r1, r2, temp, gx, gy, gz
  const std::vector<ChannelInfo>& chs = Channels();
  auto read = [&](const ChannelInfo& ch) { return ReadChannel(table, uses, run, ch); };
  ChannelValues t = read(chs[0]);
  ChannelValues lambda[2] = {read(chs[1]), read(chs[2])};
  ChannelValues w[3] = {read(chs[3]), read(chs[4]), read(chs[5])};
  ChannelValues rate[2] = {read(chs[6]), read(chs[7])};
  ChannelValues temp = read(chs[8]);
  // The gyro (SPEC section 10), in deg/s on the IMU's own axes: read with a
  // gyro block, all three; without one, the columns are left alone.
  ChannelValues g[3];
  if (run.gyro) {
    CheckGyroColumnsPresent(table, run);
    for (int i = 0; i < 3; ++i) g[i] = read(chs[9 + i]);
  } else if (InTable(table, run, "gx") && InTable(table, run, "gy") && InTable(table, run, "gz")) {
    Warn(warnings, std::string("gx gy gz present but run.yaml has no gyro block: the gyro is "
                               "not calibrated"));
  }
  std::vector<ChannelValues*> all = {&t,       &lambda[0], &lambda[1], &w[0], &w[1], &w[2],
                                     &rate[0], &rate[1],   &temp,      &g[0], &g[1], &g[2]};
  if (rate[0].present() != rate[1].present()) {
    const ChannelValues& given = rate[0].present() ? rate[0] : rate[1];
    throw InputError(table.path + ": " + given.label +
                     " without the other rate channel (give lambda1_rate and lambda2_rate, "
                     "or neither)");
  }

  // Fatal checks on the samples as recorded.
  CheckSampleCount(table, table.rows, "samples");
  CheckFinite(table, {all.begin(), all.end()});
  if (run.sort_by_time) {  // data_format.sort_by_time: rows stored in another order
    std::vector<std::size_t> order(table.rows);
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return t.values[a] < t.values[b]; });
    for (ChannelValues* c : all) KeepRows(order, c);
    KeepRows(order, &labels);
  }
  CheckTimeNotDecreasing(table, t);

  // Repeated time stamps: keep the first sample of each (an index per
  // sample only when there are some).
  if (std::adjacent_find(t.values.begin(), t.values.end()) != t.values.end()) {
    const std::vector<std::size_t> keep = FirstOfEqualTimes(t.values);
    for (ChannelValues* c : all) KeepRows(keep, c);
    KeepRows(keep, &labels);
    Warn(warnings, DuplicateWarning(table.rows - keep.size()));
    CheckSampleCount(table, keep.size(), "distinct time stamps");
  }
  if (run.time_range_s) {
    const auto [from, to] = *run.time_range_s;
    std::vector<std::size_t> in;
    for (std::size_t k = 0; k < t.values.size(); ++k) {
      if (t.values[k] >= from && t.values[k] <= to) in.push_back(k);
    }
    if (in.size() < 2) {
      char span[160];
      std::snprintf(span, sizeof(span), "[%g, %g] s holds %zu sample(s); the run spans %g to %g s",
                    from, to, in.size(), t.values.front(), t.values.back());
      throw InputError(run.yaml_path + ": time_range_s: " + span);
    }
    for (ChannelValues* c : all) KeepRows(in, c);
    KeepRows(in, &labels);
    CheckSampleCount(table, in.size(), "samples in time_range_s");
  }
  Warn(warnings, GapWarning(t.values));

  // Units of the readings and angles, judged against the nominal triad.
  const ImuAxesNominal nominal = NominalOfImuAxes(run);
  const double(&scale_of_imu_axis)[3] = nominal.scale;
  const double(&bias_of_imu_axis)[3] = nominal.bias;
  double range_of_imu_axis[3];
  for (int j = 0; j < 3; ++j) {
    range_of_imu_axis[j] = scale_of_imu_axis[j] + std::abs(bias_of_imu_axis[j]);
  }
  CheckSamplesPlausible(table, {&t, {&lambda[0], &lambda[1]}, {&w[0], &w[1], &w[2]},
                                {&rate[0], &rate[1]}},
                        scale_of_imu_axis, bias_of_imu_axis);
  for (ChannelValues& l : lambda) UnwrapDegrees(&l.values);
  CheckAngleRates(table, t, lambda);
  {
    const bool lambda_from_file[2] = {!SourceOf(run, "lambda1").constant,
                                      !SourceOf(run, "lambda2").constant};
    bool w_from_file[3];
    for (int j = 0; j < 3; ++j) w_from_file[j] = !SourceOf(run, w[j].name).constant;
    for (const std::string& line :
         CheckConstantChannels(table, lambda, lambda_from_file, w, w_from_file)) {
      Warn(warnings, line);
    }
  }
  for (int j = 0; j < 3; ++j) {
    // Only readings taken as mV: a declared V, g or mg is the user's word.
    const std::string unit = SourceOf(run, w[j].name).unit;
    if (unit.empty() || unit == "mV") {
      CheckReadingsInMillivolts(table, w[j], range_of_imu_axis[j]);
    }
  }
  // Both angles held constant (a run without a bench: static positions by label
  // or by gravity only): there is nothing to judge the angle unit by.
  if (!SourceOf(run, "lambda1").constant || !SourceOf(run, "lambda2").constant) {
    CheckAnglesInDegrees(table, lambda, w, scale_of_imu_axis);
    // The noise allowed for: the declared one (none with noise_mV: auto) or
    // the readings' own, whichever is larger (a vibrating run is not one in
    // radians).
    double noise_mV = run.noise_auto ? 0.0 : run.ChannelNoise_mV().maxCoeff();
    for (const ChannelValues& c : w) noise_mV = std::max(noise_mV, SecondDifferenceNoise(c.values));
    CheckAnglesNotRadiansWindowed(table, lambda, w, scale_of_imu_axis, noise_mV);
  }
  for (const ChannelValues& c : w) Warn(warnings, SaturationWarning(c));
  if (run.gyro) {
    std::string unit = SourceOf(run, "gx").unit;
    for (const char* name : {"gy", "gz"}) {
      if (SourceOf(run, name).unit != unit) unit.clear();  // mixed: no single unit to name
    }
    CheckGyroUnits(table, t, lambda, g, unit, std::sqrt(run.gyro->scale.squaredNorm() / 3.0));
  }

  RunData data;
  data.t_s = std::move(t.values);
  for (int i = 0; i < 2; ++i) {
    data.lambda_rad[i] = Scaled(std::move(lambda[i].values), kDegToRad);
    if (rate[i].present()) data.rate_rad_s[i] = Scaled(std::move(rate[i].values), kDegToRad);
  }
  for (int i = 0; i < 3; ++i) {
    data.w_mV[i] = Scaled(std::move(w[run.axis_source[i]].values), run.axis_sign[i]);
  }
  if (run.gyro) {
    // Readings held at the gyro's range: never fitted through (gyro_term.h
    // leaves their intervals out).
    std::vector<char> clipped(data.t_s.size(), 0);
    std::size_t n_clipped = 0;
    for (const ChannelValues& c : g) {
      if (auto line = SaturationWarning(c, "deg/s")) Warn(warnings, *line);
      n_clipped += MarkClipped(c, &clipped);
    }
    if (n_clipped > 0) {
      data.gyro_clipped = std::move(clipped);
      Warn(warnings, std::to_string(n_clipped) +
                         " gyro samples at the range's limit: the gyro fit leaves out the "
                         "intervals that hold them");
    }
    // The mounting turns the gyro's axes as the accelerometer's (one IMU).
    for (int i = 0; i < 3; ++i) {
      data.gyro_rad_s[i] =
          Scaled(std::move(g[run.axis_source[i]].values), run.axis_sign[i] * kDegToRad);
    }
  }
  data.temp_C = std::move(temp.values);
  data.label = std::move(labels);
  return data;
}

void WriteRunCsv(const RunData& run, const std::string& path, const std::string& comment,
                 const WriteOptions& options) {
  std::string out;
  out.reserve(128 + run.size() * 160);
  std::string text = comment;
  if (!text.empty() && text.back() == '\n') text.pop_back();
  if (!text.empty()) {
    std::size_t start = 0;
    while (start <= text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      out += "# " + text.substr(start, end - start) + "\n";
      start = end + 1;
    }
  }
  out += "t,lambda1,lambda2,wx,wy,wz";
  if (run.has_rates()) out += ",lambda1_rate,lambda2_rate";
  if (run.has_temp()) out += ",temp_C";
  if (run.has_gyro()) out += ",gx,gy,gz";
  out += "\n";
  for (std::size_t k = 0; k < run.size(); ++k) {
    AppendDouble(run.t_s[k], &out);
    for (int i = 0; i < 2; ++i) {
      out += ',';
      AppendDouble(run.lambda_rad[i][k] / kDegToRad, &out);
    }
    for (int i = 0; i < 3; ++i) {
      out += ',';
      AppendDouble(run.w_mV[i][k], &out);
    }
    if (run.has_rates()) {
      for (int i = 0; i < 2; ++i) {
        out += ',';
        AppendDouble(run.rate_rad_s[i][k] / kDegToRad, &out);
      }
    }
    if (run.has_temp()) {
      out += ',';
      AppendDouble(run.temp_C[k], &out);
    }
    if (run.has_gyro()) {
      for (int i = 0; i < 3; ++i) {
        out += ',';
        AppendDouble(run.gyro_rad_s[i][k] / kDegToRad, &out);
      }
    }
    out += '\n';
  }
  WriteFileAtomically(path, out, options);
}

}  // namespace triadcal

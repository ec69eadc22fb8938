// The Python module `triadcal`: the library's main jobs on numpy arrays and
// dicts (python/README in docs/library.md).
//
//   triadcal.fit(run, **options) -> dict         the OUT of `triadcal fit` (its job)
//   triadcal.filter(run, **options) -> dict      the OUT of `triadcal filter`
//   triadcal.diagnose(run, **options) -> dict    the OUT of `triadcal diagnose`
//   triadcal.apply(calibration, readings_mV, t_s=None, temp_C=None) -> (N, 3)
//   triadcal.apply_gyro(calibration, gyro_dps, W_g) -> (N, 3)     [deg/s]
//   triadcal.simulate(scenario, seed=None, out_dir=None) -> dict of arrays
//   triadcal.load_run(run) -> dict of arrays
//
// `run` is a run.yaml path or a dict with run.yaml's keys (a relative `data`
// path is then relative to the working folder); `calibration` an OUT file's
// path or its dict. Bad input raises triadcal.InputError (a ValueError) with
// the command line's message.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "core/io/calibration_io.h"
#include "core/io/data_table.h"
#include "core/io/run_description_io.h"
#include "core/io/run_io.h"
#include "core/model/apply_calibration.h"
#include "core/model/errors.h"
#include "core/model/units.h"
#include "core/simulation/simulator.h"
#include "app/diagnose_job.h"
#include "app/filter_job.h"
#include "app/fit_job.h"
#include "app/run_loading.h"
#include "app/session.h"
#include "core/version/version.h"

namespace py = pybind11;

namespace triadcal {
namespace {

using json = nlohmann::json;

// Python object -> JSON, through the json module (dicts, lists, numbers, str).
json ToJson(const py::object& o) {
  const py::object dumps = py::module_::import("json").attr("dumps");
  return json::parse(dumps(o).cast<std::string>());
}

py::object FromJson(const json& j) { return py::module_::import("json").attr("loads")(j.dump()); }

YAML::Node ToYaml(const json& j) {
  YAML::Node n;
  if (j.is_object()) {
    n = YAML::Node(YAML::NodeType::Map);
    for (const auto& [k, v] : j.items()) n[k] = ToYaml(v);
  } else if (j.is_array()) {
    n = YAML::Node(YAML::NodeType::Sequence);
    for (const auto& v : j) n.push_back(ToYaml(v));
  } else if (j.is_string()) {
    n = j.get<std::string>();
  } else if (j.is_boolean()) {
    n = j.get<bool>();
  } else if (j.is_number()) {
    n = j.dump();  // exact text of the number
  }
  return n;
}

// A run.yaml path, or a dict of its keys (paths relative to the working folder).
RunDescription RunFrom(const py::object& run) {
  if (py::isinstance<py::str>(run)) return LoadRunDescription(run.cast<std::string>());
  if (!py::isinstance<py::dict>(run)) {
    throw InputError("run: expected a run.yaml path or a dict of its keys");
  }
  const YAML::Node node = ToYaml(ToJson(run));
  if (!node["data"]) throw InputError("run: data: missing: the data file");
  const std::string where = (std::filesystem::current_path() / "run.yaml").string();
  return ParseRunDescription(node, where, "run (dict)");
}

Calibration CalibrationFrom(const py::object& cal) {
  if (py::isinstance<py::str>(cal)) return LoadCalibration(cal.cast<std::string>());
  if (!py::isinstance<py::dict>(cal)) {
    throw InputError("calibration: expected an OUT file's path or its dict");
  }
  return CalibrationFromJson(ToJson(cal), "calibration (dict)");
}

py::array_t<double> Column(const std::vector<double>& v) {
  py::array_t<double> a(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

// Three channels of N samples as an (N, 3) array, each times `factor`.
py::array_t<double> Triple(const std::vector<double> (&c)[3], double factor = 1.0) {
  const std::size_t n = c[0].size();
  py::array_t<double> a({static_cast<py::ssize_t>(n), py::ssize_t(3)});
  auto r = a.mutable_unchecked<2>();
  for (std::size_t k = 0; k < n; ++k) {
    for (int i = 0; i < 3; ++i) r(k, i) = c[i][k] * factor;
  }
  return a;
}

// An (N, 3) array argument as three channels; InputError naming it otherwise.
void ReadTriple(const py::array_t<double, py::array::c_style | py::array::forcecast>& a,
                const char* name, std::vector<double> (&out)[3]) {
  if (a.ndim() != 2 || a.shape(1) != 3) {
    throw InputError(std::string(name) + ": expected an array of shape (N, 3)");
  }
  auto r = a.unchecked<2>();
  for (int i = 0; i < 3; ++i) {
    out[i].resize(static_cast<std::size_t>(a.shape(0)));
    for (std::size_t k = 0; k < out[i].size(); ++k) out[i][k] = r(k, i);
  }
}

py::array_t<double> Rows(const std::vector<Eigen::Vector3d>& v, double factor = 1.0) {
  py::array_t<double> out({static_cast<py::ssize_t>(v.size()), py::ssize_t(3)});
  auto o = out.mutable_unchecked<2>();
  for (std::size_t k = 0; k < v.size(); ++k) {
    for (int i = 0; i < 3; ++i) o(k, i) = v[k][i] * factor;
  }
  return out;
}

py::dict RunDataDict(const RunData& d) {
  py::dict out;
  out["t_s"] = Column(d.t_s);
  std::vector<double> l1(d.lambda_rad[0]), l2(d.lambda_rad[1]);
  for (double& x : l1) x /= kDegToRad;
  for (double& x : l2) x /= kDegToRad;
  out["lambda1_deg"] = Column(l1);
  out["lambda2_deg"] = Column(l2);
  out["readings_mV"] = Triple(d.w_mV);
  if (d.has_gyro()) out["gyro_dps"] = Triple(d.gyro_rad_s, 1.0 / kDegToRad);
  if (d.has_temp()) out["temp_C"] = Column(d.temp_C);
  return out;
}

// A job on a run: `job(run_yaml, run, session)` in a session whose provenance
// is what a written OUT carries (app/provenance.h): the tool, the call, and
// the run's and data's SHA-256, recorded as they are read. Returns the job's
// OUT with that provenance. The GIL is released while the job runs.
// threads: the job's (the run's loading follows it: LoadRun).
template <typename Job>
py::object RunJob(const py::object& run_arg, const std::string& call, int threads,
                  const Job& job) {
  const RunDescription description = RunFrom(run_arg);
  const bool from_file = py::isinstance<py::str>(run_arg);  // a dict has no file
  json out;
  {
    py::gil_scoped_release release;
    Session session;
    session.provenance = Provenance(ToolVersion(), ToolGitCommit(), "python: triadcal." + call);
    if (from_file) session.RecordInput("run", description.yaml_path);
    const LoadedRun run = LoadRun(description, &session, threads);
    out = job(description.yaml_path, run, session);
    out["provenance"] = session.provenance.Json();
  }
  return FromJson(out);
}

// `triadcal fit` through its job (app/fit_job.h): the same settings (their
// defaults those of the command line), the same OUT.
py::object Fit(const py::object& run_arg, const std::string& effects, double epoch_s,
               double rate_window_s, const std::string& init, const std::string& sigma,
               int threads, bool correlations, bool auto_hold,
               const std::vector<std::string>& hold, const std::vector<std::string>& free) {
  FitSettings settings;
  settings.effects = effects;
  settings.epoch_s = epoch_s;
  settings.rate_window_s = rate_window_s;
  settings.init = ParseFitInit(init);
  settings.sigma = ParseSigmaMethod(sigma);
  settings.threads = threads;
  settings.correlations = correlations;
  settings.auto_hold = auto_hold;
  settings.hold = hold;
  settings.free = free;
  settings.Validate();
  return RunJob(run_arg, "fit", settings.threads,
                [&](const std::string& yaml, const LoadedRun& run, const Session& session) {
    return FitRun(settings, yaml, run, session).json;
  });
}

// `triadcal filter` through its job (app/filter_job.h). A diverged filter
// raises InputError with the command's sentence.
py::object FilterOut(const py::object& run_arg, const std::string& effects, double epoch_s,
                  double rate_window_s, int iterations, bool correlations, bool auto_hold,
                  const std::vector<std::string>& hold, const std::vector<std::string>& free) {
  FilterSettings settings;
  settings.effects = effects;
  settings.epoch_s = epoch_s;
  settings.rate_window_s = rate_window_s;
  settings.iterations = iterations;
  settings.correlations = correlations;
  settings.auto_hold = auto_hold;
  settings.hold = hold;
  settings.free = free;
  settings.Validate();
  return RunJob(run_arg, "filter", 0,
                [&](const std::string& yaml, const LoadedRun& run, const Session& session) {
    FilterOutcome f = FilterRun(settings, yaml, run, session);
    if (!f.error.empty()) throw InputError(f.error);
    return f.json;
  });
}

// `triadcal diagnose` through its job (app/diagnose_job.h).
py::object DiagnoseOut(const py::object& run_arg, const std::string& candidates, double alpha,
                    int max_effects, double epoch_s, double rate_window_s, int threads) {
  DiagnoseSettings settings;
  settings.candidates = candidates;
  settings.alpha = alpha;
  settings.max_effects = max_effects;
  settings.epoch_s = epoch_s;
  settings.rate_window_s = rate_window_s;
  settings.threads = threads;
  settings.Validate();
  return RunJob(run_arg, "diagnose", settings.threads,
                [&](const std::string& yaml, const LoadedRun& run, const Session& session) {
    return DiagnoseRun(settings, yaml, run, nullptr, session).json;
  });
}

py::array_t<double> Apply(const py::object& cal_arg,
                          py::array_t<double, py::array::c_style | py::array::forcecast> z,
                          std::optional<py::array_t<double, py::array::forcecast>> t_s,
                          std::optional<py::array_t<double, py::array::forcecast>> temp_C) {
  const Calibration cal = CalibrationFrom(cal_arg);
  RunData data;
  ReadTriple(z, "readings_mV", data.w_mV);
  const std::size_t n = data.w_mV[0].size();
  data.t_s.assign(n, 0.0);
  auto copy = [n](const py::array_t<double, py::array::forcecast>& a, const char* name,
                  std::vector<double>* out) {
    if (a.ndim() != 1 || static_cast<std::size_t>(a.shape(0)) != n) {
      throw InputError(std::string(name) +
                       ": expected an array of shape (N,), N = " + std::to_string(n));
    }
    out->assign(a.data(), a.data() + n);
  };
  if (t_s) copy(*t_s, "t_s", &data.t_s);
  if (temp_C) copy(*temp_C, "temp_C", &data.temp_C);
  if (cal.layout.has(Effect::kThermalDrift) && !t_s) {
    throw InputError("t_s: needed by the calibration's thermal_drift");
  }
  if (cal.layout.has(Effect::kThermalDriftTemp) && !temp_C) {
    throw InputError("temp_C: needed by the calibration's thermal_drift_temp");
  }
  return Rows(ApplyCalibration(cal, RunDescription(), data));
}

// Gyro readings (N, 3) [deg/s] and the specific force W (N, 3) [g] of the same
// samples (from Apply) -> angular rate (N, 3) [deg/s], as `triadcal apply`.
py::array_t<double> ApplyGyro(const py::object& cal_arg,
                              py::array_t<double, py::array::c_style | py::array::forcecast> g,
                              py::array_t<double, py::array::c_style | py::array::forcecast> W) {
  const Calibration cal = CalibrationFrom(cal_arg);
  RunData data;
  ReadTriple(g, "gyro_dps", data.gyro_rad_s);
  for (std::vector<double>& c : data.gyro_rad_s) {
    for (double& x : c) x *= kDegToRad;
  }
  std::vector<double> w[3];
  ReadTriple(W, "W_g", w);
  const std::size_t n = data.gyro_rad_s[0].size();
  if (w[0].size() != n) {
    throw InputError("W_g: expected the " + std::to_string(n) + " samples of gyro_dps, got " +
                     std::to_string(w[0].size()));
  }
  data.t_s.assign(n, 0.0);
  std::vector<Eigen::Vector3d> W_g(n);
  for (std::size_t k = 0; k < n; ++k) W_g[k] = {w[0][k], w[1][k], w[2][k]};
  return Rows(ApplyGyroCalibration(cal, RunDescription(), data, W_g), 1.0 / kDegToRad);
}

py::dict SimulateScenario(const std::string& scenario, std::optional<std::uint64_t> seed,
                          const std::string& out_dir) {
  Scenario s = LoadScenario(scenario);
  if (seed) s.seed = *seed;
  SampleTruth(&s);
  RunData data;
  {
    py::gil_scoped_release release;
    data = triadcal::Simulate(s);
  }
  if (!out_dir.empty()) WriteSimulation(s, data, out_dir);
  py::dict out = RunDataDict(data);
  py::dict truth;
  for (int i = 0; i < s.truth_layout.size(); ++i) {
    truth[py::str(TruthFileKey(s.truth_layout, i))] = TruthFileValue(s.truth_layout, s.truth, i);
  }
  out["truth"] = truth;
  out["seed"] = s.seed;
  return out;
}

py::dict LoadRunArrays(const py::object& run_arg) {
  const RunDescription run = RunFrom(run_arg);
  return RunDataDict(LoadRunData(run, nullptr));
}

}  // namespace
}  // namespace triadcal

PYBIND11_MODULE(triadcal, m) {
  using namespace pybind11::literals;
  m.doc() = "triadcal: calibrate a MEMS accelerometer triad from a two-axis bench run";
  m.attr("__version__") = triadcal::ToolVersion();  // project()'s, core/version/version.h
  // A damaged v7.3 file raises InputError without HDF5's report on stderr.
  triadcal::SilenceMatioDiagnostics();
  static py::exception<triadcal::InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const triadcal::InputError& e) {
      input_error(e.what());
    }
  });
  const triadcal::FitSettings defaults;  // those of `triadcal fit`
  m.def("fit", &triadcal::Fit, "run"_a, py::kw_only(), "effects"_a = defaults.effects,
        "epoch_s"_a = defaults.epoch_s, "rate_window_s"_a = defaults.rate_window_s,
        "init"_a = triadcal::FitInitName(defaults.init),
        "sigma"_a = triadcal::SigmaMethodName(defaults.sigma), "threads"_a = defaults.threads,
        "correlations"_a = defaults.correlations, "auto_hold"_a = defaults.auto_hold,
        "hold"_a = defaults.hold, "free"_a = defaults.free,
        "Batch least-squares fit of a run (run.yaml path or dict), as `triadcal fit` fits it "
        "(the same job); returns its OUT as a dict (parameters: {name: {value, sigma, unit, "
        "...}}, sigma, residual_analysis, settings, ..., and the provenance a written file "
        "carries: the tool, the call and the SHA-256 of the run and its data).");
  const triadcal::FilterSettings filtering;  // those of `triadcal filter`
  m.def("filter", &triadcal::FilterOut, "run"_a, py::kw_only(), "effects"_a = filtering.effects,
        "epoch_s"_a = filtering.epoch_s, "rate_window_s"_a = filtering.rate_window_s,
        "iterations"_a = filtering.iterations, "correlations"_a = filtering.correlations,
        "auto_hold"_a = filtering.auto_hold, "hold"_a = filtering.hold, "free"_a = filtering.free,
        "The paper's EKF + RTS smoother on a run (run.yaml path or dict), as `triadcal filter` "
        "runs it (the same job); returns its OUT as a dict (ekf, rts, innovations, held, ...) "
        "with the provenance a written file carries.");
  const triadcal::DiagnoseSettings diagnosing;  // those of `triadcal diagnose`
  m.def("diagnose", &triadcal::DiagnoseOut, "run"_a, py::kw_only(),
        "candidates"_a = diagnosing.candidates, "alpha"_a = diagnosing.alpha,
        "max_effects"_a = diagnosing.max_effects, "epoch_s"_a = diagnosing.epoch_s,
        "rate_window_s"_a = diagnosing.rate_window_s, "threads"_a = diagnosing.threads,
        "The closed loop of SPEC section 8 on a run (run.yaml path or dict), as `triadcal "
        "diagnose` runs it (the same job); returns its OUT as a dict (selected, could_hide, "
        "states, ...) with the provenance a written file carries.");
  m.def("apply", &triadcal::Apply, "calibration"_a, "readings_mV"_a, "t_s"_a = py::none(),
        "temp_C"_a = py::none(),
        "Raw readings (N, 3) [mV, triad axes] -> specific force W (N, 3) [g] by the exact "
        "inverse of the readings model, as `triadcal apply`. temp_C counts from its first "
        "value (thermal_drift_temp).");
  m.def("apply_gyro", &triadcal::ApplyGyro, "calibration"_a, "gyro_dps"_a, "W_g"_a,
        "Gyro readings (N, 3) [deg/s, triad axes] and the specific force W (N, 3) [g] of the "
        "same samples (from apply) -> angular rate (N, 3) [deg/s] in the triad frame by the "
        "exact inverse of the gyro's readings model, as `triadcal apply`; the calibration "
        "must have the gyro (gyro.*).");
  m.def("simulate", &triadcal::SimulateScenario, "scenario"_a, "seed"_a = py::none(),
        "out_dir"_a = "",
        "Simulate a scenario.yaml: dict with t_s, lambda1_deg, lambda2_deg, readings_mV (N, 3), "
        "gyro_dps (N, 3) with a gyro, truth {name: value in file units}; also writes run.csv, "
        "run.yaml, truth.json to "
        "out_dir when given.");
  m.def("load_run", &triadcal::LoadRunArrays, "run"_a,
        "The data of a run (run.yaml path or dict) as numpy arrays (gyro_dps (N, 3) when it "
        "has a gyro block).");
}

#include "app/joint_fit_job.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "app/option_lists.h"
#include "app/run_loading.h"
#include "core/io/column_mapping.h"
#include "core/model/errors.h"
#include "app/fit_report.h"

namespace triadcal {
namespace {

nlohmann::json Entry(const JointParam& p, double value, double var, Treatment t) {
  const bool estimated = t == Treatment::kEstimated;
  nlohmann::json e;
  e["value"] = value / p.si_per_unit;
  e["sigma"] = estimated ? nlohmann::json(std::sqrt(std::max(0.0, var)) / p.si_per_unit)
                         : nlohmann::json(nullptr);
  e["unit"] = p.unit;
  e["estimable"] = estimated;
  if (t == Treatment::kHeld) {
    e["held"] = true;
    e["reason"] =
        "held at its nominal value: no information in the runs together beyond the others "
        "(a structural null), or held with --hold";
  } else if (t == Treatment::kConsidered) {
    e["considered"] = true;
    e["reason"] =
        "not determined by the runs together: kept at its nominal value, its prior "
        "uncertainty carried into the others' sigma";
    e["prior_sigma"] = p.prior_sigma / p.si_per_unit;
  }
  return e;
}

nlohmann::json BetweenJson(const JointParam& p, const BetweenRuns& b, double sigma) {
  return {{"runs", b.runs},
          {"q", b.q},
          {"dof", b.dof},
          {"p_value", b.p_value},
          {"disagree", b.disagree},
          {"largest_z", b.largest_z},
          {"tau", b.tau / p.si_per_unit},
          {"sigma_factor", b.sigma_factor},
          {"sigma_within", sigma / b.sigma_factor / p.si_per_unit},
          {"unit", p.unit}};
}

}  // namespace

std::vector<Treatment> TreatmentOf(const JointResult& r, int m) {
  std::vector<Treatment> t(m, Treatment::kEstimated);
  for (int j : r.consider) t[j] = Treatment::kConsidered;
  for (int j : r.held) t[j] = Treatment::kHeld;
  return t;
}

RunsFile RunsOfCommandLine(const std::vector<std::string>& inputs) {
  if (inputs.size() == 1) return LoadRunsFile(inputs[0]);
  for (const std::string& in : inputs) {
    if (IsRunsFile(in)) {
      throw InputError(in + ": a runs file is given alone (fit runs.yaml), not with other runs");
    }
  }
  return RunsFromCommandLine(inputs);
}

std::vector<JointRun> LoadJointRuns(const RunsFile& file, Session* session, int threads) {
  std::vector<JointRun> runs;
  for (const RunsFile::Entry& e : file.runs) {
    LoadedRun lr = LoadRun(e.run_yaml, session, threads);
    session->RecordInput("run " + e.name, e.run_yaml);
    JointRun r;
    r.name = e.name;
    r.source = e.where;
    r.run = std::move(lr.description);
    r.data = std::move(lr.data);
    if (e.temperature_C) {
      r.temperature_C = *e.temperature_C;
      r.has_temperature = true;
    } else if (r.run.temperature_C) {
      r.temperature_C = *r.run.temperature_C;
      r.has_temperature = true;
    } else if (r.data.has_temp()) {
      r.temperature_C = std::accumulate(r.data.temp_C.begin(), r.data.temp_C.end(), 0.0) /
                        static_cast<double>(r.data.temp_C.size());
      r.has_temperature = true;
    }
    runs.push_back(std::move(r));
  }
  return runs;
}

JointInput LoadJointInput(const std::vector<std::string>& inputs, const std::string& effects,
                          Session* session, int threads) {
  JointInput in;
  in.file = RunsOfCommandLine(inputs);
  if (!in.file.path.empty()) session->NoteInput(in.file.path);  // the runs file
  in.runs = LoadJointRuns(in.file, session, threads);
  // The effects must suit every run's data.
  std::vector<Effect> list;
  for (const JointRun& r : in.runs) list = ParseEffectList(effects, r.data);
  const std::string unit =
      in.runs.empty() ? std::string(kDefaultReadingsUnit) : ReadingsUnit(in.runs.front().run);
  in.layout = std::make_unique<JointLayout>(in.runs, ParameterLayout(list, false, unit),
                                            JointSpecOf(in.file),
                                            in.file.path.empty() ? "command line" : in.file.path);
  for (const JointRun& r : in.runs) {
    if (r.run.gyro && r.data.has_gyro()) in.gyro_not_calibrated.push_back(r.name);
  }
  if (!in.gyro_not_calibrated.empty() && session->warning) {
    std::string names;
    for (const std::string& n : in.gyro_not_calibrated) names += (names.empty() ? "" : ", ") + n;
    const bool one = in.gyro_not_calibrated.size() == 1;
    session->warning(std::string(one ? "run " : "runs ") + names + (one ? " carries" : " carry") +
                     " a gyro, which several runs together do not calibrate yet: the "
                     "accelerometer triad only (fit each run alone for its gyro)");
  }
  return in;
}

JointSpec JointSpecOf(const RunsFile& file) {
  JointSpec spec;
  spec.per_run = file.per_run;
  spec.shared = file.shared;
  spec.temperature_degree = file.temperature_degree;
  spec.temperature_ref_C = file.temperature_ref_C;
  return spec;
}

namespace {

// An estimated unknown is "determined" unless the runs determine it only
// with the considered ones at nominal: then "determined_with_considered",
// their names (as `fit`'s OUT has it).
void AddWithConsidered(const JointLayout& jl, const JointResult& r, int j, Treatment t,
                       nlohmann::json* entry) {
  if (t != Treatment::kEstimated) return;
  const auto w = r.with_considered.find(j);
  (*entry)["determined"] = w == r.with_considered.end();
  if (w == r.with_considered.end()) return;
  nlohmann::json names = nlohmann::json::array();
  for (int c : w->second) names.push_back(jl.param(c).name);
  (*entry)["determined_with_considered"] = names;
}

// The verdict's clause naming them, or "".
std::string WithConsideredClause(const JointLayout& jl, const JointResult& r) {
  if (r.with_considered.empty()) return "";
  std::string s =
      "; DETERMINED ONLY WITH the considered parameters at nominal (their prior uncertainty is "
      "most of the sigma):";
  for (const auto& [j, with] : r.with_considered) {
    s += " " + jl.param(j).name + " (with";
    for (int c : with) s += " " + jl.param(c).name;
    s += ")";
  }
  return s;
}

// Whether the runs agree, and where not, how.
std::string Agreement(const JointLayout& jl, const JointResult& r) {
  std::vector<std::string> bad;
  int tested = 0;
  for (const JointRunResult& rr : r.runs) {
    tested += rr.consistency.tested;
    if (rr.consistency.tested && !rr.consistency.consistent) {
      char b[200];
      std::snprintf(b, sizeof(b), "%s (chi2 %.1f for %d, p %.2g", rr.name.c_str(),
                    rr.consistency.chi2, rr.consistency.dof, rr.consistency.p_value);
      std::string s = b;
      for (std::size_t k = 0; k < rr.consistency.pulls.size() && k < 3; ++k) {
        std::snprintf(b, sizeof(b), "%s %s z %+.1f", k ? "," : "; pulls",
                      rr.consistency.pulls[k].first.c_str(), rr.consistency.pulls[k].second);
        s += b;
      }
      bad.push_back(s + ")");
    }
  }
  std::string spread;
  for (const BetweenRuns& b : r.between) {
    if (!b.disagree) continue;
    const JointParam& p = jl.param(b.index);
    char buf[120];
    std::snprintf(buf, sizeof(buf), "%s%s %.3g %s (sigma x%.3g)", spread.empty() ? "" : ", ",
                  p.name.c_str(), b.tau / p.si_per_unit, p.unit.c_str(), b.sigma_factor);
    spread += buf;
  }
  if (!bad.empty() || !spread.empty()) {
    std::string s = "RUNS DISAGREE: ";
    for (std::size_t k = 0; k < bad.size(); ++k) s += (k ? "; " : "") + bad[k];
    if (!spread.empty()) s += (bad.empty() ? "" : "; ") + ("spread between the runs " + spread);
    return s +
           " -- a remount, a turn-on bias or an effect that differs between the runs; the "
           "joint sigma carry the spread";
  }
  if (tested < 2) return "converged (fewer than two runs could be compared with the others)";
  return "converged; the runs agree within their sigma";
}

}  // namespace

std::string JointVerdict(const JointLayout& jl, const JointResult& r) {
  if (!r.converged) return "NOT CONVERGED: " + r.termination;
  return Agreement(jl, r) + WithConsideredClause(jl, r);
}

nlohmann::json GyroNotCalibratedJson(const std::vector<std::string>& runs) {
  return {{"runs", runs},
          {"reason", runs.empty() ? "no run carries a gyro"
                                  : "several runs together calibrate the accelerometer triad "
                                    "only; fit each run alone for its gyro"}};
}

nlohmann::json JointJson(const JointLayout& jl, const JointInput& in, const JointResult& r) {
  const std::vector<JointRun>& runs = in.runs;
  const RunsFile& file = in.file;
  nlohmann::json out;
  out["command"] = "fit";
  out["kind"] = "joint";
  out["axes"] = "imu";
  out["runs_file"] = file.path.empty() ? nlohmann::json(nullptr) : nlohmann::json(file.path);
  const std::vector<Treatment> treat = TreatmentOf(r, jl.size());
  nlohmann::json shared = nlohmann::json::object();
  for (int j = 0; j < jl.size(); ++j) {
    const JointParam& p = jl.param(j);
    if (p.run >= 0) continue;
    shared[p.name] = Entry(p, r.phi[j], r.cov(j, j), treat[j]);
    AddWithConsidered(jl, r, j, treat[j], &shared[p.name]);
    nlohmann::json share = nlohmann::json::object();
    for (int q = 0; q < jl.runs(); ++q) share[jl.run_name(q)] = r.share(q, j);
    if (treat[j] == Treatment::kEstimated) shared[p.name]["information_share"] = share;
  }
  nlohmann::json between = nlohmann::json::array();
  for (const BetweenRuns& b : r.between) {
    const JointParam& p = jl.param(b.index);
    const double sigma = std::sqrt(std::max(0.0, r.cov(b.index, b.index)));
    shared[p.name]["between_runs"] = BetweenJson(p, b, sigma);
    if (b.sigma_factor > 1.0) between.push_back(p.name);
  }
  out["parameters"] = shared;
  // The shared parameters whose sigma carry a spread between the runs.
  out["between_run_component"] = between;
  if (!file.temperature_degree.empty()) {
    out["temperature_model"] = {{"reference_C", file.temperature_ref_C},
                                {"degree", file.temperature_degree}};
  } else {
    out["temperature_model"] = nullptr;
  }
  out["determined_jointly_only"] = r.jointly_only;
  nlohmann::json held_names = nlohmann::json::array();
  for (int j : r.held) held_names.push_back(jl.param(j).name);
  out["held"] = held_names;
  nlohmann::json considered = nlohmann::json::array();
  for (int j : r.consider) considered.push_back(jl.param(j).name);
  out["considered"] = considered;
  nlohmann::json jr = nlohmann::json::array();
  for (int q = 0; q < jl.runs(); ++q) {
    const JointRunResult& rr = r.runs[q];
    nlohmann::json e;
    e["name"] = rr.name;
    e["run"] = file.runs[q].run_yaml;
    e["samples"] = runs[q].data.size();
    e["temperature_C"] =
        runs[q].has_temperature ? nlohmann::json(runs[q].temperature_C) : nlohmann::json(nullptr);
    e["noise_mV"] = {rr.noise_mV[0], rr.noise_mV[1], rr.noise_mV[2]};
    e["noise_source"] = rr.alone.noise_source;
    e["chi2_per_dof"] = rr.chi2_per_dof;
    e["sigma_method"] = rr.sigma_method;
    e["hac_bandwidth_epochs"] = rr.sigma_method == "hac" ? nlohmann::json(rr.hac_bandwidth_epochs)
                                                         : nlohmann::json(nullptr);
    nlohmann::json own = nlohmann::json::object();
    for (int j = 0; j < jl.size(); ++j) {
      const JointParam& p = jl.param(j);
      if (p.run != q) continue;
      nlohmann::json& entry = own[p.name.substr(0, p.name.rfind('@'))];
      entry = Entry(p, r.phi[j], r.cov(j, j), treat[j]);
      AddWithConsidered(jl, r, j, treat[j], &entry);
    }
    e["parameters"] = own;
    const BatchResult& a = rr.alone;
    nlohmann::json alone;
    alone["converged"] = a.converged;
    alone["chi2_per_dof"] = a.chi2_per_dof;
    alone["held"] = a.held;
    alone["considered"] = a.consider;
    nlohmann::json ap = nlohmann::json::object();
    for (int i = 0; i < jl.layout().size(); ++i) {
      const ParameterInfo& info = jl.layout().info(i);
      const bool h = !IsEstimated(a, info.name);
      auto sigma_of = [&](const Eigen::MatrixXd& cov) {
        return h || cov.rows() <= i
                   ? nlohmann::json(nullptr)
                   : nlohmann::json(std::sqrt(std::max(0.0, cov(i, i))) / info.si_per_unit);
      };
      ap[info.name] = {
          {"value", a.estimate.theta[i] / info.si_per_unit},
          {"sigma", sigma_of(a.estimate.cov)},
          {"sigma_given_consider",
           a.consider.empty() ? sigma_of(a.estimate.cov) : sigma_of(a.cov_given_consider)},
          {"unit", info.unit}};
    }
    alone["parameters"] = ap;
    alone["axes"] = "platform";
    e["alone"] = alone;
    const RunConsistency& c = rr.consistency;
    nlohmann::json cj;
    cj["tested"] = c.tested;
    cj["chi2"] = c.chi2;
    cj["dof"] = c.dof;
    cj["p_value"] = c.p_value;
    cj["consistent"] = c.consistent;
    nlohmann::json pulls = nlohmann::json::array();
    for (const auto& [name, z] : c.pulls) pulls.push_back({{"parameter", name}, {"z", z}});
    cj["pulls"] = pulls;
    e["consistency"] = cj;
    jr.push_back(e);
  }
  out["runs"] = jr;
  out["gyro_not_calibrated"] = GyroNotCalibratedJson(in.gyro_not_calibrated);
  out["chi2_per_dof"] = r.chi2_per_dof;
  out["degrees_of_freedom"] = r.degrees_of_freedom;
  out["converged"] = r.converged;
  out["iterations"] = r.iterations;
  out["termination"] = r.termination;
  out["verdict"] = JointVerdict(jl, r);
  out["timing_s"] = {{"runs_alone", r.seconds_alone}, {"joint", r.seconds_joint}};
  return out;
}

JointFitOutcome JointFitRun(const FitSettings& s, const JointInput& in, const Session& session) {
  s.Validate();
  JointOptions opt;
  opt.batch = MakeBatchOptions(s);
  opt.batch.progress = session.stage;
  opt.batch.fraction = session.fraction;
  JointFitOutcome out;
  out.result = SolveJoint(in.runs, *in.layout, opt);
  out.json = JointJson(*in.layout, in, out.result);
  return out;
}

}  // namespace triadcal

#include "solvers/multirun/joint_layout.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "core/io/column_mapping.h"
#include "core/model/effects.h"
#include "core/model/errors.h"
#include "core/model/mounting.h"
#include "core/model/priors.h"
#include "core/model/units.h"

namespace triadcal {
namespace {

std::string ReadingsUnitOf(const RunDescription& run) {
  const ColumnSource s = SourceOf(run, "wx");
  std::string unit = s.unit.empty() ? "mV" : s.unit;
  if (unit == "counts" && s.counts_per_g) unit += " at " + std::to_string(*s.counts_per_g) + "/g";
  return unit;
}

std::string Vec3Text(const Eigen::Vector3d& v) {
  char b[96];
  std::snprintf(b, sizeof(b), "[%g, %g, %g]", v[0], v[1], v[2]);
  return b;
}

}  // namespace

JointLayout::JointLayout(const std::vector<JointRun>& runs, const ParameterLayout& layout,
                         const JointSpec& spec, const std::string& spec_source)
    : layout_(layout) {
  const int n = layout.size();
  if (runs.empty()) throw InputError(spec_source + ": no runs");
  auto fail = [&](const std::string& what) { throw InputError(spec_source + ": " + what); };

  // One IMU: the same nominal triad in the IMU's axes and readings in the same unit.
  std::vector<Eigen::MatrixXd> mount(runs.size());
  std::vector<Prior> prior(runs.size());
  std::vector<Eigen::VectorXd> nominal_imu(runs.size());
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const JointRun& jr = runs[r];
    mount[r] = MountingMap(jr.run, layout);
    prior[r] = MakePrior(jr.run, layout);
    nominal_imu[r] = mount[r].transpose() * NominalTheta(jr.run, layout);
    for (std::size_t q = 0; q < r; ++q) {
      if (runs[q].name == jr.name) fail("two runs are named '" + jr.name + "'");
      const bool same_range = runs[q].run.time_range_s == jr.run.time_range_s;
      if (runs[q].run.data_path == jr.run.data_path && same_range) {
        fail("run '" + jr.name + "' (" + jr.source + ") is run '" + runs[q].name + "' (" +
             runs[q].source + ") again: the same data " + jr.run.data_path +
             (jr.run.time_range_s ? " over the same time_range_s" : "") +
             " (a run listed twice)");
      }
    }
    if (r == 0) continue;
    const Eigen::Vector3d k0 = nominal_imu[0].segment<3>(kKx), kr = nominal_imu[r].segment<3>(kKx);
    const Eigen::Vector3d b0 = nominal_imu[0].segment<3>(kW0x), br = nominal_imu[r].segment<3>(kW0x);
    const double tol = 1e-9 * std::max(1.0, k0.cwiseAbs().maxCoeff());
    if ((k0 - kr).cwiseAbs().maxCoeff() > tol || (b0 - br).cwiseAbs().maxCoeff() > tol) {
      fail("run '" + jr.name + "' (" + jr.run.yaml_path + ") declares another IMU: its triad " +
           "in the IMU's own axes (mounting undone) has scale_mV_per_g " +
           Vec3Text(kr) + " and bias_mV " + Vec3Text(br) + ", run '" + runs[0].name +
           "' has " + Vec3Text(k0) + " and " + Vec3Text(b0) +
           " (runs of one IMU declare the same nominal triad)");
    }
    if (ReadingsUnitOf(jr.run) != ReadingsUnitOf(runs[0].run)) {
      fail("run '" + jr.name + "' (" + jr.run.yaml_path + ") has readings in " +
           ReadingsUnitOf(jr.run) + ", run '" + runs[0].name + "' in " +
           ReadingsUnitOf(runs[0].run) + " (runs of one IMU read the same channels)");
    }
  }

  // A name the layout does not have: a catalogue effect's parameter whose
  // effect this command does not estimate, or no parameter at all.
  auto unknown = [&](const std::string& key, const std::string& name) {
    const std::size_t dot = name.find('.');
    for (const EffectSpec& e : EffectCatalogue()) {
      if (dot == std::string::npos || name.compare(0, dot, e.name) != 0) continue;
      for (const ParamSpec& p : e.params) {
        if (name.compare(dot + 1, std::string::npos, p.name) == 0) {
          fail(key + ": '" + name + "' is a parameter of the effect " + e.name +
               ", which this command does not estimate (add --effects " + e.name + ")");
        }
      }
    }
    fail(key + ": '" + name + "' is not a parameter (see `triadcal params`)");
  };
  // Which parameters are shared and which belong to each run.
  std::vector<bool> per_run(n, false);
  for (int i = 0; i < n; ++i) per_run[i] = !IsTriadParameter(layout, i);
  bool rotation = false;
  for (const std::string& name : spec.per_run) {
    if (name == "mounting") {
      rotation = true;
      continue;
    }
    const int i = layout.IndexOf(name);
    if (i < 0) unknown("per_run", name);
    if (!IsTriadParameter(layout, i)) {
      fail("per_run: '" + name + "' belongs to each run already (bench set-up and angle- or "
           "geometry-stage effects are per run unless listed under shared)");
    }
    per_run[i] = true;
  }
  for (const std::string& name : spec.shared) {
    const int i = layout.IndexOf(name);
    if (i < 0) unknown("shared", name);
    if (IsTriadParameter(layout, i)) {
      fail("shared: '" + name + "' is a triad parameter, shared already (list it under "
           "per_run to give each run its own)");
    }
    per_run[i] = false;
  }
  double span_C = 0.0;
  std::set<double> temperatures;
  for (const auto& [name, degree] : spec.temperature_degree) {
    const int i = layout.IndexOf(name);
    if (i < 0) fail("temperature.degree: '" + name + "' is not a parameter");
    if (per_run[i]) fail("temperature.degree: '" + name + "' is per run; a temperature model is "
                         "for a shared parameter");
    if (degree < 1 || degree > 3) {
      fail("temperature.degree: " + name + ": " + std::to_string(degree) +
           " is not a polynomial degree of 1 to 3");
    }
  }
  if (!spec.temperature_degree.empty()) {
    for (const JointRun& jr : runs) {
      if (!jr.has_temperature || !std::isfinite(jr.temperature_C)) {
        fail("run '" + jr.name + "' has no temperature for the temperature model (give "
             "temperature_C in the runs file or a temp_C column)");
      }
      temperatures.insert(jr.temperature_C);
      span_C = std::max(span_C, std::abs(jr.temperature_C - spec.temperature_ref_C));
    }
    for (const auto& [name, degree] : spec.temperature_degree) {
      if (static_cast<int>(temperatures.size()) <= degree) {
        fail("temperature.degree: " + name + ": a degree-" + std::to_string(degree) +
             " polynomial needs runs at " + std::to_string(degree + 1) +
             " temperatures or more, the runs have " + std::to_string(temperatures.size()));
      }
    }
  }

  // The unknowns: shared, their temperature coefficients, then each run's.
  auto prior_imu = [&](std::size_t r, int i, double* mean, double* sigma) {
    *mean = nominal_imu[r][i];
    *sigma = (mount[r].transpose().cwiseAbs() * prior[r].sigma)[i];
    if (!IsTriadParameter(layout, i)) {
      *mean = prior[r].mean[i];
      *sigma = prior[r].sigma[i];
    }
  };
  std::vector<int> shared_index(n, -1);
  for (int i = 0; i < n; ++i) {
    if (per_run[i]) continue;
    JointParam p;
    p.name = layout.info(i).name;
    p.unit = layout.info(i).unit;
    p.si_per_unit = layout.info(i).si_per_unit;
    p.base = i;
    prior_imu(0, i, &p.prior_mean, &p.prior_sigma);
    shared_index[i] = size();
    params_.push_back(p);
  }
  std::map<int, std::vector<int>> coefficient;  // layout index -> phi index of degree 1, 2, ...
  for (const auto& [name, degree] : spec.temperature_degree) {
    const int i = layout.IndexOf(name);
    for (int k = 1; k <= degree; ++k) {
      JointParam p = params_[shared_index[i]];
      p.name = name + ".t" + std::to_string(k);
      p.unit += k == 1 ? "/degC" : "/degC^" + std::to_string(k);
      p.si_per_unit = layout.info(i).si_per_unit;
      p.degree = k;
      p.prior_mean = 0.0;
      p.prior_sigma /= std::pow(std::max(span_C, 10.0), k);
      coefficient[i].push_back(size());
      params_.push_back(p);
    }
  }
  std::vector<std::vector<int>> own(runs.size(), std::vector<int>(n, -1));
  std::vector<int> rotation_index(runs.size(), -1);
  for (std::size_t r = 0; r < runs.size(); ++r) {
    for (int i = 0; i < n; ++i) {
      if (!per_run[i]) continue;
      JointParam p;
      p.name = layout.info(i).name + "@" + runs[r].name;
      p.unit = layout.info(i).unit;
      p.si_per_unit = layout.info(i).si_per_unit;
      p.run = static_cast<int>(r);
      p.base = i;
      prior_imu(r, i, &p.prior_mean, &p.prior_sigma);
      own[r][i] = size();
      params_.push_back(p);
    }
    if (rotation && r > 0) {
      rotation_index[r] = size();
      for (const char* axis : {"rx", "ry", "rz"}) {
        JointParam p;
        p.name = std::string("mounting.") + axis + "@" + runs[r].name;
        p.unit = "arcmin";
        p.si_per_unit = kArcminToRad;
        p.run = static_cast<int>(r);
        p.prior_mean = 0.0;
        p.prior_sigma = 180.0 * kArcminToRad;
        params_.push_back(p);
      }
    }
  }

  // theta_r = mount_r (IMU-side selection of phi) + rotation.
  const int m = size();
  for (std::size_t r = 0; r < runs.size(); ++r) {
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, m);
    for (int i = 0; i < n; ++i) {
      if (own[r][i] >= 0) {
        S(i, own[r][i]) = 1.0;
        continue;
      }
      S(i, shared_index[i]) = 1.0;
      const auto c = coefficient.find(i);
      if (c == coefficient.end()) continue;
      const double dT = runs[r].temperature_C - spec.temperature_ref_C;
      for (std::size_t k = 0; k < c->second.size(); ++k) {
        S(i, c->second[k]) = std::pow(dT, static_cast<double>(k + 1));
      }
    }
    Eigen::MatrixXd T = mount[r] * S;
    if (rotation_index[r] >= 0) {
      const int o = rotation_index[r];
      T(kGammaY, o) += 1.0;
      T(kGammaZ, o) += 1.0;
      T(kBetaX, o + 1) += 1.0;
      T(kBetaZ, o + 1) += 1.0;
      T(kAlphaX, o + 2) += 1.0;
      T(kAlphaY, o + 2) += 1.0;
    }
    map_.push_back(T);
    offset_.push_back(Eigen::VectorXd::Zero(n));
    run_names_.push_back(runs[r].name);
  }
}

int JointLayout::IndexOf(const std::string& name) const {
  for (int j = 0; j < size(); ++j) {
    if (params_[j].name == name) return j;
  }
  return -1;
}

Eigen::VectorXd JointLayout::Nominal() const {
  Eigen::VectorXd v(size());
  for (int j = 0; j < size(); ++j) v[j] = params_[j].prior_mean;
  return v;
}

Eigen::VectorXd JointLayout::PriorSigma() const {
  Eigen::VectorXd v(size());
  for (int j = 0; j < size(); ++j) v[j] = params_[j].prior_sigma;
  return v;
}

}  // namespace triadcal

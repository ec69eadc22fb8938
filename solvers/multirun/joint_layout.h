// Several runs of one IMU as one problem (docs/multi-run.md): which unknowns
// the runs share, which belong to one run, and how the shared ones reach each
// run's parameter vector.
//
// The joint unknowns phi are
//   shared    the triad's parameters in the IMU's own axes (the axes of the
//             readings columns before run.yaml's `mounting`; the platform's
//             axes for a run without one) and the sensor-stage effects, each
//             optionally a polynomial in temperature about reference_C:
//               p(T) = p + p.t1 (T - T_ref) + p.t2 (T - T_ref)^2 ...
//   per run   the bench set-up (dpsi, dtheta_c, dlambda2, dx2, dy2, dz2), the
//             angle- and geometry-stage effects, the triad parameters the user
//             lists in per_run (e.g. zero offsets that move between turn-ons),
//             and with per_run: [mounting] a small rotation of the IMU on the
//             platform for every run after the first (the first defines the
//             IMU's axes); named "NAME@RUN".
//
// Run r's parameter vector (platform axes, its ParameterLayout) is affine in
// phi: theta_r = offset_r + T_r phi. The mounting maps IMU axes to platform
// axes exactly (MountingMap, core/model/mounting.h).
// A small rotation rho (platform axes) adds to the misalignment matrix
// M_p + [[0, -rho_z, rho_y], [rho_z, 0, -rho_x], [-rho_y, rho_x, 0]]:
// alpha_x, alpha_y += rho_z; beta_x, beta_z += rho_y; gamma_y, gamma_z += rho_x.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/model/mounting.h"
#include "core/model/parameters.h"
#include "core/model/run_data.h"
#include "core/model/run_description.h"

namespace triadcal {

// One run of a joint problem.
struct JointRun {
  std::string name;        // unique: used in "NAME@RUN" and in messages
  std::string source;      // where it was listed (runs file line, or the command line)
  RunDescription run;
  RunData data;
  // The run's temperature [degC] for a temperature model: declared in the runs
  // file, else the mean of its temp_C column; NaN when neither.
  double temperature_C = 0.0;
  bool has_temperature = false;
};

// What the user says about the runs (runs file, docs/file-formats.md).
struct JointSpec {
  // Triad parameters (IMU axes) or `mounting` that belong to each run.
  std::vector<std::string> per_run;
  // Set-up or effect parameters that all runs share (e.g. the lever arm when
  // the IMU was never moved on the platform).
  std::vector<std::string> shared;
  // Temperature model: shared parameter -> polynomial degree (>= 1).
  std::map<std::string, int> temperature_degree;
  double temperature_ref_C = 20.0;
};

struct JointParam {
  std::string name;   // "Kx", "W0x.t1", "dpsi@slow", "mounting.rx@pitch"
  std::string unit;   // file unit ("mV/g", "mV/degC", "arcmin")
  double si_per_unit = 1.0;
  int run = -1;       // -1: shared
  int base = -1;      // index in the run layout of the parameter it belongs to (-1: rotation)
  int degree = 0;     // temperature degree (0: the value at T_ref)
  double prior_mean = 0.0, prior_sigma = 1.0;  // SI
};

class JointLayout {
 public:
  // Throws InputError (naming `spec_source`) for a per-run or shared name that
  // is not a parameter, a temperature model without run temperatures, runs of
  // different IMUs (nominal triads that differ in the IMU's axes, readings in
  // different units), or a run listed twice.
  JointLayout(const std::vector<JointRun>& runs, const ParameterLayout& layout,
              const JointSpec& spec, const std::string& spec_source);

  int size() const { return static_cast<int>(params_.size()); }
  int runs() const { return static_cast<int>(offset_.size()); }
  const JointParam& param(int j) const { return params_[j]; }
  const std::vector<JointParam>& params() const { return params_; }
  const ParameterLayout& layout() const { return layout_; }
  int IndexOf(const std::string& name) const;

  // theta_r = offset(r) + map(r) phi (all of run r's layout).
  const Eigen::VectorXd& offset(int r) const { return offset_[r]; }
  const Eigen::MatrixXd& map(int r) const { return map_[r]; }
  Eigen::VectorXd ThetaOfRun(int r, const Eigen::VectorXd& phi) const {
    return offset_[r] + map_[r] * phi;
  }
  // The nominal phi (prior means).
  Eigen::VectorXd Nominal() const;
  Eigen::VectorXd PriorSigma() const;

  const std::string& run_name(int r) const { return run_names_[r]; }

 private:
  ParameterLayout layout_;
  std::vector<JointParam> params_;
  std::vector<Eigen::VectorXd> offset_;
  std::vector<Eigen::MatrixXd> map_;
  std::vector<std::string> run_names_;
};

}  // namespace triadcal

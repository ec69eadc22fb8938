// Which parameters a run cannot separate, from the posterior covariance of an
// estimator and the prior it started from.
//
// In prior units (each parameter divided by its prior sigma) the posterior
// covariance is P~ = D^-1 P D^-1 and the information the data (and the
// constraints) added is I~ = P~^-1 - 1. An eigenvector of P~ with eigenvalue mu
// carries data information 1/mu - 1: a direction with little of it (below
// min_information, default 10: posterior sigma above ~0.3 of the prior along it)
// is one the run cannot determine, and its values are the prior's, not
// estimates. The parameters with weight >= 0.2 in it are named.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/model/parameters.h"

namespace triadcal {

struct WeakDirection {
  double data_information = 0.0;  // I~ along the direction (0: none)
  double sigma_ratio = 1.0;       // posterior / prior sigma along it
  std::vector<std::pair<std::string, double>> weights;  // normalised, largest first
  std::string description;        // in words
};

std::vector<WeakDirection> FindWeakDirections(const ParameterLayout& layout,
                                              const Eigen::MatrixXd& posterior_cov,
                                              const Eigen::VectorXd& prior_sigma,
                                              double min_information = 10.0);

// Names of the parameters that appear in any of the directions.
std::vector<std::string> ParametersIn(const std::vector<WeakDirection>& dirs);

// The sentence FindWeakDirections writes for a direction with these weights
// (also used by observability.h).
std::string DescribeDirection(const std::vector<std::pair<std::string, double>>& weights);

// A parameter the fit moved more than n_sigma of its prior sigma from the
// prior mean (the nominal value). Either the nominal value or the prior is
// wrong, or the model lacks an effect whose misfit this parameter absorbs
// along a direction the data determine only weakly: on the real slow roll
// run the 8.6-ms time offset, before `diagnose` finds it, tilts the shaft by
// dpsi = 76 deg (25 prior sigma) and takes Kx, Kz and W0y with it.
struct PriorExcursion {
  std::string name;
  double z = 0.0;  // (value - prior mean) / prior sigma
};
std::vector<PriorExcursion> BeyondPrior(const ParameterLayout& layout,
                                        const Eigen::VectorXd& theta,
                                        const Eigen::VectorXd& prior_mean,
                                        const Eigen::VectorXd& prior_sigma,
                                        double n_sigma = 3.0);
// "dpsi (+25.3) Kx (+9.5)": names with their z, largest |z| first.
std::string DescribeExcursions(const std::vector<PriorExcursion>& excursions);

}  // namespace triadcal

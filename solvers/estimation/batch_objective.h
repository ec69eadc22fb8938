// The batch problem of one or several runs as a function of the parameters
// alone: what the minimiser (batch_minimizer.h) minimises, and what every
// covariance, score test and consistency check is read from.
//
// The unknowns phi (m) reach each run r's parameter vector affinely,
// theta_r = offset_r + T_r phi (one run: phi = theta, T = I; several runs of
// one IMU: solvers/multirun/joint_layout.h). Each run keeps its own reading
// noise sigma_r (per channel, run_evaluation.h) and its trajectory, solved
// for at every evaluation. With the priors and the runs' constraints as rows
// over phi (whitened: r = A phi - b),
//
//   cost(phi) = sum_r cost_r(theta_r(phi); sigma_r) + 0.5 |A phi - b|^2
//   gradient  = sum_r T_r^T g_r + A^T (A phi - b)
//   H         = sum_r T_r^T I_r T_r + A^T A          (Gauss-Newton)
//
// An evaluation is one pass over every run's samples (run_evaluation.h); a
// new noise needs only the reductions again (Reweight).
#pragma once

#include <memory>
#include <vector>

#include <Eigen/Core>

#include "solvers/estimation/gyro_term.h"
#include "solvers/estimation/run_evaluation.h"
#include "solvers/estimation/run_problem.h"

namespace triadcal {

struct LinkedRun {
  const RunProblem* problem = nullptr;  // must outlive the objective; holds nothing
  Eigen::VectorXd offset;               // n_r; empty: zero
  Eigen::MatrixXd map;                  // n_r x m; empty: identity (n_r = m)
};

class BatchObjective {
 public:
  // rows: A (k x m) and b (k): the whitened priors and constraints over phi.
  // The noise weights' shape of every evaluation is the one at weights_phi
  // (the nominal values; run_evaluation.h): one pass without Jacobians here,
  // unless `weights` gives each run's (SharedRunWork::Weights).
  BatchObjective(std::vector<LinkedRun> runs, Eigen::MatrixXd A, Eigen::VectorXd b,
                 const Eigen::VectorXd& weights_phi, int threads,
                 std::vector<std::shared_ptr<const RunPass>> weights = {});

  struct Point {
    Eigen::VectorXd phi;
    // Per run; a pass never changes once evaluated, and the same point at
    // other noises (AtNoise) shares it.
    std::vector<std::shared_ptr<const RunPass>> passes;
    std::vector<RunReduction> reductions;   // per run, at its noise
    // Per run with a gyro triad (gyro_term.h; null entries for the others):
    // its pass, and its reduction at its noise's maximum there.
    std::vector<std::shared_ptr<const GyroPass>> gyro_passes;
    std::vector<GyroReduction> gyro;
    double cost = 0.0;                      // 0.5 chi^2: data, priors, constraints, + gyro_cost
    double data_cost = 0.0;                 // the runs' accelerometer part
    double gyro_cost = 0.0;                 // the gyros' -log L, their noise profiled
    Eigen::VectorXd gradient;               // m (empty without the Jacobian)
    Eigen::MatrixXd data_information;       // m x m, sum_r T_r^T I_r T_r
    // Its diagonal before the states' elimination (RunReduction::
    // information_scale, through the maps): what its rounding is relative to.
    Eigen::VectorXd data_information_scale;
    Eigen::MatrixXd information;            // m x m, with A^T A
    bool finite() const;
  };

  int size() const { return m_; }
  bool has_gyro(int r) const { return has_gyro_[r]; }
  // True when pt carries run r's gyro part.
  bool HasGyroPart(const Point& pt, int r) const;
  int runs() const { return static_cast<int>(runs_.size()); }
  const LinkedRun& run(int r) const { return runs_[r]; }
  const Eigen::MatrixXd& rows() const { return A_; }
  const Eigen::VectorXd& rhs() const { return b_; }
  Eigen::VectorXd ThetaOf(int r, const Eigen::VectorXd& phi) const;
  // T_r (identity when the run's map is empty).
  Eigen::MatrixXd MapOf(int r) const;

  // One pass over every run's samples at phi, each reduced at noise[r].
  // theta_part: what the reductions form (run_evaluation.h); the pass keeps
  // its Jacobian whatever it is, for a caller that moves the noise first and
  // reduces in full there (BatchMinimizer::MaximiseNoise). free: the theta
  // part by these unknowns only (the gradient and the runs' information
  // zero in the others, no blocks kept; the gyro's part is whole), or null
  // for all.
  Point Evaluate(const Eigen::VectorXd& phi, const std::vector<Eigen::Vector3d>& noise,
                 bool with_jacobian, ThetaPart theta_part = ThetaPart::kGradientAndInformation,
                 const std::vector<int>* free = nullptr) const;
  // The same point at other noises (no pass over the samples), its
  // reductions forming theta_part (without the information, pt has none;
  // without the gradient, neither).
  void Reweight(Point* pt, const std::vector<Eigen::Vector3d>& noise,
                ThetaPart theta_part = ThetaPart::kGradientAndInformation,
                const std::vector<int>* free = nullptr) const;
  // pt at other noises as a new point (its passes shared, its reductions
  // formed anew: pt's are not copied).
  Point AtNoise(const Point& pt, const std::vector<Eigen::Vector3d>& noise,
                ThetaPart theta_part = ThetaPart::kGradientAndInformation,
                const std::vector<int>* free = nullptr) const;
  // The same point with each gyro's part at the gyro noise of `other` (not
  // at its own maximum): what a change of the gradient at fixed noise needs.
  void ReweightGyro(Point* pt, const Point& other) const;

  // From now on each gyro's noise stays at its run's figure (RunProblem::
  // gyro_noise_rad_s: the declared one, or the readings' own) instead of its
  // maximum at every point: what the decision before the fit needs, as the
  // accelerometer's noise there is the declared one. At the nominal values a
  // profiled noise takes in the misfit (simulated paper run with a gyro
  // nonlinearity: its k2_y known 0.4 times its prior instead of 73 times).
  void HoldGyroNoise() { gyro_noise_held_ = true; }

  // Run r's reference pass of the noise weights (run_evaluation.h).
  const RunPass& weights(int r) const { return *weights_[r]; }

  // What the evaluations have cost so far, where a fit's time goes: the
  // passes over the samples (each Evaluate's, the gyros' with them) and the
  // reductions (each Reweight's, every run reduced again), with their wall
  // time; reduction_seconds holds the gyros' noise profiles and reductions
  // too (Evaluate, ReweightGyro).
  struct Work {
    int passes = 0;
    double pass_seconds = 0.0;
    int reductions = 0;
    double reduction_seconds = 0.0;
  };
  const Work& work() const { return work_; }

 private:
  void Assemble(Point* pt) const;
  // Run r's parameters that the unknowns `free` move.
  std::vector<int> ColumnsOf(int r, const std::vector<int>& free) const;

  std::vector<LinkedRun> runs_;
  std::vector<std::shared_ptr<const RunPass>> weights_;  // per run, at weights_phi
  std::vector<bool> has_gyro_;    // per run
  // The gyros' noise at the last evaluation: where the next one's profile
  // starts (the objective is evaluated by one minimiser at a time).
  mutable std::vector<Eigen::Vector3d> gyro_noise_hint_;
  bool gyro_noise_held_ = false;  // HoldGyroNoise
  mutable Work work_;             // work(): one minimiser at a time, as above
  Eigen::MatrixXd A_;
  Eigen::VectorXd b_;
  int m_ = 0;
  int threads_ = 1;
};

// The whitened rows of run p's priors (all n parameters) and of its
// constraints over the full theta, A theta - b: the rows of a one-run
// objective whose unknowns are its parameters.
void PriorAndConstraintRows(const RunProblem& p, Eigen::MatrixXd* A, Eigen::VectorXd* b);

}  // namespace triadcal

// One frame's least-squares problem (lm_solver.h): a parameter block per bone over theta,
// the cost terms, and the cost and loss functions they use. Internal to the solver.
#ifndef MOCAP_SRC_FRAME_PROBLEM_H_
#define MOCAP_SRC_FRAME_PROBLEM_H_

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <array>
#include <memory>
#include <vector>

#include "lm_solver.h"
#include "mocap/camera.h"
#include "mocap/initialisation.h"
#include "mocap/kinematics.h"
#include "mocap/observations.h"
#include "mocap/sites.h"

namespace mocap {

struct TermOptions;
class LinearPriorResidual;

enum Term {
  kOrientationTerm,
  kPositionTerm,
  kAccelerationTerm,
  kPcaProjectionTerm,
  kPcaDeviationTerm,
  kMotionTerm,  // E_M: E_A's cost against a constant-velocity model (motion_residual.h)
  kPointTerm    // not one of the paper's five: 3D targets (FitToPoints)
};

// The loss a term's options name (null for the trivial loss); the caller owns it.
ceres::LossFunction* MakeLoss(const TermOptions& term);

class FrameProblem {
 public:
  // theta must outlive the problem; Solve updates it in place.
  FrameProblem(const Skeleton& skeleton, double* theta);

  // E_P for each detection whose site is in front of its camera at theta; returns how
  // many were behind it (and left out).
  int AddPositionTerms(const Rig& rig, const KeypointLayout& layout,
                       const std::vector<Detection>& detections, const TermOptions& options);
  void AddOrientationTerm(const ImuSite& site, const Eigen::Matrix3d& measured_world,
                          const TermOptions& options);
  void AddAccelerationTerm(const ImuSite& site, const Eigen::Vector3d& x1,
                           const Eigen::Vector3d& x0, double h1, double h2,
                           const Eigen::Vector3d& measured_world, const TermOptions& options);
  // E_M for the point `site`: x1, v its position and filtered velocity at t1 (MotionState).
  void AddMotionTerm(const Site& site, const Eigen::Vector3d& x1, const Eigen::Vector3d& v,
                     double h1, double h2, const TermOptions& options);
  void AddPointTerm(const Site& site, const Eigen::Vector3d& target, const TermOptions& options);
  // A prior term over the joint blocks; `cost` is owned by the caller and reused.
  void AddPriorTerm(Term term, const LinearPriorResidual* cost, const TermOptions& options);

  int count(Term term) const { return static_cast<int>(blocks_[term].size()); }
  // Levenberg-Marquardt from theta.
  LmSummary Solve(const LmOptions& options);
  // E = sum of rho(|r|^2) of each term at the current theta.
  TermCosts Costs();
  const LmProblem& problem() const { return problem_; }

 private:
  ceres::LossFunction* Loss(Term term, const TermOptions& options);
  void Add(Term term, const ceres::CostFunction* cost, const TermOptions& options,
           const std::vector<int>& offsets, const Eigen::MatrixXd* gram = nullptr);

  const Skeleton& skeleton_;
  double* theta_;
  KinematicsCache fk_;
  LmProblem problem_;
  std::vector<std::vector<int>> chain_offsets_;  // per bone: its chain's blocks in theta
  std::vector<std::unique_ptr<ceres::CostFunction>> owned_;
  std::array<std::unique_ptr<ceres::LossFunction>, 7> losses_;
  std::array<std::vector<int>, 7> blocks_;  // residual blocks of each term
};

}  // namespace mocap

#endif  // MOCAP_SRC_FRAME_PROBLEM_H_

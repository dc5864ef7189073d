// One frame's least-squares problem (lm_solver.h): a parameter block per bone over theta,
// the cost terms, and the cost and loss functions they use. Internal to the solver.
#ifndef MOCAP_SRC_FRAME_PROBLEM_H_
#define MOCAP_SRC_FRAME_PROBLEM_H_

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "lm_solver.h"
#include "mocap/camera.h"
#include "mocap/initialisation.h"
#include "mocap/kinematics.h"
#include "mocap/observations.h"
#include "mocap/sites.h"
#include "mocap/solver_options.h"

namespace mocap {

class LinearPriorResidual;

enum Term {
  kOrientationTerm,
  kPositionTerm,
  kAccelerationTerm,
  kPcaProjectionTerm,
  kPcaDeviationTerm,
  kMotionTerm,  // E_M: E_A's cost against a constant-velocity model (motion_residual.h)
  kGroundTerm,  // E_G: the lowest foot contact point on the floor (ground_residual.h)
  kPointTerm,   // not one of the paper's five: 3D targets (FitToPoints)
  kShiftTerm,   // the prediction shift's prior (prediction_shift.h; not in TermCosts)
  kNumTerms
};

// The loss a term's options name (null for the trivial loss); the caller owns it.
ceres::LossFunction* MakeLoss(const TermOptions& term);

// E_G's inputs: the contact sites (null: none), the floor, the term's options.
struct GroundContact {
  const std::vector<Site>* contacts = nullptr;
  double floor = 0.0;
  TermOptions options;
};

// The information of a frame's keypoints (those in front of their cameras) and ground contact
// on the root's position at theta: sum of rho' J^T J of their residuals on it, robust weights
// at theta (the prediction shift's H, prediction_shift.h).
Eigen::Matrix3d RootPositionInformation(const Skeleton& skeleton, const double* theta,
                                        const Rig& rig, const KeypointLayout& layout,
                                        const std::vector<Detection>& detections,
                                        const TermOptions& position, const GroundContact& ground);

class FrameProblem {
 public:
  // theta must outlive the problem; Solve updates it. shift_prediction: the motion terms
  // (E_A, E_M) get the prediction shift delta, a parameter block after theta's, whose prior
  // AddPredictionShiftPrior adds (prediction_shift.h).
  FrameProblem(const Skeleton& skeleton, double* theta, bool shift_prediction = false);

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
  // E_G on the lowest of `contacts` (ground.h) at theta; none when `contacts` is empty.
  void AddGroundTerm(const std::vector<Site>& contacts, double floor, const TermOptions& options);
  void AddPointTerm(const Site& site, const Eigen::Vector3d& target, const TermOptions& options);
  // The prediction shift's prior (prediction_shift.h: H = root_information, kappa = slack,
  // r = observed_ratio, sigma_max = max_shift), W the motion terms' added so far; none unless
  // the problem shifts the prediction.
  void AddPredictionShiftPrior(const Eigen::Matrix3d& root_information, double slack,
                               double observed_ratio, double max_shift);
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
  // A motion term (E_A, E_M) on `bone`, its prediction shifted when the problem does so.
  void AddMotion(Term term, std::unique_ptr<ceres::CostFunction> cost, double position_scale,
                 int bone, const TermOptions& options);

  const Skeleton& skeleton_;
  double* theta_;      // the caller's pose
  Eigen::VectorXd x_;  // the parameters: the pose, then delta when the prediction shifts
  int shift_offset_;   // delta's offset in x_, -1 without it
  double motion_information_ = 0;  // the shifted motion terms' sum of position_scale^2
  KinematicsCache fk_;
  LmProblem problem_;
  std::vector<std::vector<int>> chain_offsets_;  // per bone: its chain's blocks in theta
  std::vector<std::unique_ptr<ceres::CostFunction>> owned_;
  std::array<std::unique_ptr<ceres::LossFunction>, kNumTerms> losses_;
  std::array<std::vector<int>, kNumTerms> blocks_;  // residual blocks of each term
};

}  // namespace mocap

#endif  // MOCAP_SRC_FRAME_PROBLEM_H_

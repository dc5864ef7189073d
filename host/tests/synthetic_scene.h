// Test support: a studio built in code (default skeleton, a ring of cameras, the
// 13-IMU set) that renders exact observations of any pose.
#ifndef MOCAP_TESTS_SYNTHETIC_SCENE_H_
#define MOCAP_TESTS_SYNTHETIC_SCENE_H_

#include <random>
#include <string>
#include <vector>

#include "mocap/solver.h"

namespace mocap::testing {

std::string DataPath(const std::string& relative);

struct Scene {
  Skeleton skeleton;
  Rig rig;
  KeypointLayout layout;
  std::vector<ImuSite> imus;
};

// Default skeleton, `cameras` 1920x1080 cameras on a 4.5 m ring at 1.5-2.2 m height
// aimed at the volume centre, the given layout, the 13-IMU set with non-trivial
// mounting and reference rotations.
Scene MakeScene(int cameras = 8, const std::string& layout = "blazepose33");

// A plausible random pose: root near the volume centre, joints within +-max_angle rad.
Eigen::VectorXd RandomPose(const Skeleton& skeleton, std::mt19937* rng, double max_angle = 0.5);

// Every joint rotated by `angle` radians about a random axis (root position moved by
// `shift` metres): the "10 degrees away" start.
Eigen::VectorXd Perturb(const Eigen::VectorXd& theta, double angle, double shift,
                        std::mt19937* rng);

// Exact observations of theta: keypoints in every camera (confidence 1), orientations of
// every IMU. Accelerations are left at zero; use SetAccelerations for a sequence.
FrameObservations Render(const Scene& scene, const Eigen::VectorXd& theta, double timestamp);

// Sets each IMU's measured acceleration at frame t1 so that it matches the second
// difference of the site over (t0, t1, t2) exactly (the solver's E_A at t2).
void SetAccelerations(const Scene& scene, const Eigen::VectorXd& theta0, double t0,
                      const Eigen::VectorXd& theta1, double t1, const Eigen::VectorXd& theta2,
                      double t2, const Eigen::Vector3d& accel_at_rest, FrameObservations* frame1);

// Largest joint position error (metres) and bone orientation error (radians).
double MaxJointError(const Skeleton& skeleton, const Eigen::VectorXd& a, const Eigen::VectorXd& b);
double MaxBoneAngleError(const Skeleton& skeleton, const Eigen::VectorXd& a,
                         const Eigen::VectorXd& b);

// Largest error of the layout's keypoint sites (metres): what the cameras observe.
double MaxSiteError(const Scene& scene, const Eigen::VectorXd& a, const Eigen::VectorXd& b);

// Options that solve noise-free frames to the last digit (tight tolerances, 50 iterations,
// no E_M: its constant-velocity model is millimetres off an accelerating motion).
SolverOptions ExactOptions();

// A solver of the scene's skeleton, rig, layout and IMUs (a test failure names what is wrong
// when it cannot be made).
std::unique_ptr<Solver> MakeSolver(const Scene& scene, std::optional<PosePrior> prior,
                                   SolverOptions options = ExactOptions());

// A noise-free prior for a test: zero cost at the last pose, whose non-root DOF are the
// mean, and (almost) zero at the others, whose directions it spans with sigma = 1e3.
// The data terms alone leave some DOF unobservable (spine twist split between two
// joints, clavicle and toe twist); the prior is what pins them, as in the paper.
PosePrior PriorThrough(const std::vector<Eigen::VectorXd>& poses, int rank, std::mt19937* rng);

// A prior with the given mean pose (root ignored) and a random orthonormal basis.
PosePrior RandomPrior(int dof, int rank, const Eigen::VectorXd& theta_mean, std::mt19937* rng);

}  // namespace mocap::testing

#endif  // MOCAP_TESTS_SYNTHETIC_SCENE_H_

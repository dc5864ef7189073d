// Ground contact: where the feet touch the floor, and the floor's height.
//
// A standing, walking or dancing performer has a foot on the floor nearly always; the ground
// term E_G (residuals/ground_residual.h) holds the body's lowest contact point at the floor.
// Contact sites (the one place they are defined): per foot, three points on its sole line,
// the line through the ball (the toes bone's origin) parallel to the foot's rest-pose ground
// plane (every bone frame is the world's in the rest pose, so that plane is the foot frame's
// x-y plane, the sole's direction the toes offset's horizontal part u, |u| = L):
//   heel      foot bone, ankle + (toes offset's z) e_z - kHeelBack L u/|u|
//   ball      toes bone, its origin
//   toe tip   toes bone, kToeAhead L u/|u|
// The ball's joint centre sits above the sole by a few centimetres, the same for all three
// sites when the foot is flat: the floor is defined through them (FloorHeight), so that
// thickness is absorbed by the definition instead of being a constant to know.
// Feet are the bones named foot_l / toes_l and foot_r / toes_r (the canonical skeleton's;
// mocap skeleton --from-bvh and retargeting keep them); a foot without them has no sites.
#ifndef MOCAP_GROUND_H_
#define MOCAP_GROUND_H_

#include <Eigen/Core>
#include <vector>

#include "mocap/kinematics.h"
#include "mocap/sites.h"
#include "mocap/skeleton.h"

namespace mocap {

// Heel behind the ankle and toe tip ahead of the ball, as fractions of the ankle-to-ball
// length L (an adult's: heel 4-5 cm behind the ankle, toes 6-7 cm beyond the ball, L 12-14 cm).
constexpr double kHeelBack = 0.4;
constexpr double kToeAhead = 0.5;

// Heel, ball and toe tip of each foot (empty when the skeleton has no feet with toes).
std::vector<Site> FootContactSites(const Skeleton& skeleton);

// The index of the lowest site (world z) at `pose`, -1 when `sites` is empty.
int LowestSite(const BodyPose& pose, const std::vector<Site>& sites);

// The floor under poses of `skeleton` (world z, metres): the median over the poses of each
// pose's lowest contact site. A foot is on the floor most of the time in a walk, a dance or
// a stand, so the median is the floor and a jump or a run's flight, under half the frames,
// does not move it. NaN when there are no contact sites, no finite poses, or a pose's
// size is not the skeleton's.
double FloorHeight(const Skeleton& skeleton, const std::vector<Eigen::VectorXd>& thetas);

}  // namespace mocap

#endif  // MOCAP_GROUND_H_

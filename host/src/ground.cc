#include "mocap/ground.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mocap {
namespace {

// The three sites of one foot; none when the foot or its toes are missing or the toes do not
// lie ahead of the ankle.
void AddFoot(const Skeleton& skeleton, const char* foot_name, const char* toes_name,
             std::vector<Site>* out) {
  const int foot = skeleton.BoneIndex(foot_name), toes = skeleton.BoneIndex(toes_name);
  if (foot < 0 || toes < 0 || skeleton.bone(toes).parent != foot) return;
  const Eigen::Vector3d ball = skeleton.bone(toes).offset;  // in the foot frame
  const Eigen::Vector3d ahead(ball.x(), ball.y(), 0.0);
  const double length = ahead.norm();
  if (!(length > 1e-3)) return;
  const Eigen::Vector3d forward = ahead / length;
  out->push_back({foot, Eigen::Vector3d(0, 0, ball.z()) - kHeelBack * length * forward});
  out->push_back({toes, Eigen::Vector3d::Zero()});
  out->push_back({toes, kToeAhead * length * forward});
}

double Height(const BodyPose& pose, const Site& s) {
  return (pose.position[s.bone] + pose.rotation[s.bone] * s.offset).z();
}

}  // namespace

std::vector<Site> FootContactSites(const Skeleton& skeleton) {
  std::vector<Site> sites;
  AddFoot(skeleton, "foot_l", "toes_l", &sites);
  AddFoot(skeleton, "foot_r", "toes_r", &sites);
  return sites;
}

int LowestSite(const BodyPose& pose, const std::vector<Site>& sites) {
  int lowest = -1;
  double z = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < sites.size(); ++i) {
    const double h = Height(pose, sites[i]);
    if (h < z) z = h, lowest = static_cast<int>(i);
  }
  return lowest;
}

double FloorHeight(const Skeleton& skeleton, const std::vector<Eigen::VectorXd>& thetas) {
  const double unknown = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Site> sites = FootContactSites(skeleton);
  if (sites.empty()) return unknown;
  std::vector<double> lowest;
  BodyPose pose;
  for (const Eigen::VectorXd& theta : thetas) {
    if (theta.size() != skeleton.pose_dim()) return unknown;
    if (!theta.allFinite()) continue;
    ForwardKinematics(skeleton, theta.data(), &pose);
    lowest.push_back(Height(pose, sites[LowestSite(pose, sites)]));
  }
  if (lowest.empty()) return unknown;
  const size_t half = lowest.size() / 2;
  std::nth_element(lowest.begin(), lowest.begin() + half, lowest.end());
  if (lowest.size() % 2 == 1) return lowest[half];
  const double above = lowest[half];
  return 0.5 * (above + *std::max_element(lowest.begin(), lowest.begin() + half));
}

}  // namespace mocap

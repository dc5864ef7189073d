#include "mocap/slip_monitor.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "mocap/so3.h"

namespace mocap {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// A frame is evidence on a sensor when its own keypoints were seen this many times (over all
// cameras): one or two views of a hand at the image's edge say little.
constexpr int kMinDetections = 3;

// Bone x is b or lies below it.
bool InSubtree(const Skeleton& skeleton, int x, int b) {
  for (; x >= 0; x = skeleton.bone(x).parent) {
    if (x == b) return true;
  }
  return false;
}

// The site moves when bone b turns.
bool MovesWith(const Skeleton& skeleton, const Site& site, int b) {
  return InSubtree(skeleton, site.bone, b) && (site.bone != b || site.offset.norm() > 1e-9);
}

}  // namespace

SlipMonitor::SlipMonitor(const Skeleton& skeleton, const KeypointLayout& layout,
                         const std::vector<ImuSite>& imus) {
  sensors_.resize(imus.size());
  for (size_t i = 0; i < imus.size(); ++i) {
    Sensor& s = sensors_[i];
    s.bone = imus[i].bone;
    s.mount = imus[i].mount;
    for (size_t j = 0; j < imus.size(); ++j) {
      if (imus[j].bone != s.bone && InSubtree(skeleton, imus[j].bone, s.bone))
        s.below.push_back(static_cast<int>(j));
    }
    for (int k = 0; k < layout.size(); ++k) {
      const Site& site = layout.sites[k];
      bool own = MovesWith(skeleton, site, s.bone);
      for (int j : s.below) own = own && !MovesWith(skeleton, site, imus[j].bone);
      if (own) s.keypoints.push_back(k);
    }
  }
  for (size_t i = 0; i < imus.size(); ++i) upstream_first_.push_back(static_cast<int>(i));
  std::stable_sort(upstream_first_.begin(), upstream_first_.end(),
                   [&](int a, int b) { return sensors_[a].bone < sensors_[b].bone; });
}

std::vector<double> SlipMonitor::OwnCosts(const SolverOptions& options, const Rig& rig,
                                          const KeypointLayout& layout, const BodyPose& pose,
                                          const std::vector<Detection>& detections) const {
  std::vector<double> per_keypoint(layout.size(), 0.0);
  std::vector<int> seen(layout.size(), 0);
  for (const Detection& d : detections) {
    const Site& site = layout.sites[d.keypoint];
    Eigen::Vector2d pixel;
    if (!rig.cameras[d.camera].Project(
            pose.position[site.bone] + pose.rotation[site.bone] * site.offset, &pixel))
      continue;
    per_keypoint[d.keypoint] +=
        std::log1p(options.position.weight * (pixel - d.pixel).squaredNorm());
    seen[d.keypoint]++;
  }
  std::vector<double> costs(sensors_.size(), kNaN);
  for (size_t i = 0; i < sensors_.size(); ++i) {
    double sum = 0;
    int n = 0;
    for (int k : sensors_[i].keypoints) sum += per_keypoint[k], n += seen[k];
    if (n >= kMinDetections) costs[i] = sum / n;
  }
  return costs;
}

double SlipMonitor::WindowMedian(const Sensor& s, double window_s) {
  if (s.costs.size() < 3 || s.costs.back().first - s.costs.front().first < 0.5 * window_s)
    return kNaN;
  std::vector<double> v;
  for (const auto& [t, c] : s.costs) v.push_back(c);
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

void SlipMonitor::Readmit(double timestamp, const SolverOptions& options, const BodyPose& pose,
                          const std::vector<std::optional<Eigen::Matrix3d>>& imu_world) {
  for (size_t i = 0; i < sensors_.size(); ++i) {
    Sensor& s = sensors_[i];
    if (!s.distrusted || !imu_world[i]) continue;
    const Eigen::Matrix3d solved = pose.rotation[s.bone] * s.mount;
    const double angle = Log(imu_world[i]->transpose() * solved).norm();
    if (angle > options.slip_readmit_deg * M_PI / 180) {
      s.agreeing_since.reset();
    } else if (!s.agreeing_since) {
      s.agreeing_since = timestamp;
    } else if (timestamp - *s.agreeing_since >= options.slip_readmit_s) {
      s.distrusted = false;
      s.agreeing_since.reset();
      s.costs.clear();
    }
  }
}

void SlipMonitor::Update(double timestamp, const SolverOptions& options, const Rig& rig,
                         const KeypointLayout& layout, const BodyPose& pose,
                         const std::vector<Detection>& detections,
                         const std::vector<std::optional<Eigen::Matrix3d>>& imu_world) {
  if (!(options.slip_keypoint_cost > 0)) return;
  Readmit(timestamp, options, pose, imu_world);
  const std::vector<double> costs = OwnCosts(options, rig, layout, pose, detections);
  for (size_t i = 0; i < sensors_.size(); ++i) {
    Sensor& s = sensors_[i];
    while (!s.costs.empty() && s.costs.front().first < timestamp - options.slip_window_s)
      s.costs.pop_front();
    // Evidence only from solves the sensor took part in.
    if (!s.distrusted && imu_world[i] && std::isfinite(costs[i]))
      s.costs.emplace_back(timestamp, costs[i]);
  }
  for (int i : upstream_first_) {
    Sensor& s = sensors_[i];
    if (s.distrusted || !(WindowMedian(s, options.slip_window_s) > options.slip_keypoint_cost))
      continue;
    s.distrusted = true;
    s.costs.clear();
    for (int j : s.below) sensors_[j].costs.clear();  // their keypoints moved with this bone
  }
}

}  // namespace mocap

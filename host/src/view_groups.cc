#include "mocap/view_groups.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

namespace mocap {
namespace {

double Median(std::vector<double> v) {
  const size_t n = v.size();
  std::nth_element(v.begin(), v.begin() + n / 2, v.end());
  const double upper = v[n / 2];
  if (n % 2) return upper;
  return 0.5 * (upper + *std::max_element(v.begin(), v.begin() + n / 2));
}

}  // namespace

double GroupError(const Rig& rig, const std::vector<ViewPerson>& people,
                  const std::vector<int>& members, const ViewGroupOptions& options) {
  std::set<int> cameras;
  std::map<int, std::vector<Detection>> by_keypoint;
  for (int m : members) {
    if (!cameras.insert(people[m].camera).second) return INFINITY;
    for (Detection d : people[m].keypoints) {
      d.camera = people[m].camera;
      by_keypoint[d.keypoint].push_back(d);
    }
  }
  std::map<int, std::vector<double>> errors;  // per camera
  for (const auto& [k, views] : by_keypoint) {
    Eigen::Vector3d x;
    if (views.size() < 2 || !TriangulatePoint(rig, views, &x)) continue;
    for (const Detection& d : views) {
      Eigen::Vector2d px;
      errors[d.camera].push_back(rig.cameras[d.camera].Project(x, &px) ? (px - d.pixel).norm()
                                                                       : INFINITY);
    }
  }
  double worst = 0;
  for (int c : cameras) {
    const auto it = errors.find(c);
    if (it == errors.end() || it->second.empty() ||
        static_cast<int>(it->second.size()) < options.min_shared)
      return INFINITY;
    worst = std::max(worst, Median(it->second));
  }
  return worst;
}

std::vector<std::vector<int>> GroupAcrossViews(const Rig& rig,
                                               const std::vector<ViewPerson>& people,
                                               const ViewGroupOptions& options) {
  const int n = static_cast<int>(people.size());
  std::vector<std::tuple<double, int, int>> pairs;
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      if (people[i].camera == people[j].camera) continue;
      const double e = GroupError(rig, people, {i, j}, options);
      if (e <= options.max_error_px) pairs.emplace_back(e, i, j);
    }
  std::sort(pairs.begin(), pairs.end());
  std::vector<int> group_of(n, -1);
  std::vector<std::vector<int>> groups;
  for (const auto& [e, i, j] : pairs) {
    if (group_of[i] >= 0 && group_of[i] == group_of[j]) continue;
    std::vector<int> merged;
    for (int p : {i, j}) {
      if (group_of[p] < 0) {
        merged.push_back(p);
      } else {
        merged.insert(merged.end(), groups[group_of[p]].begin(), groups[group_of[p]].end());
      }
    }
    std::sort(merged.begin(), merged.end());
    if (GroupError(rig, people, merged, options) > options.max_error_px) continue;
    const int into = group_of[i] >= 0   ? group_of[i]
                     : group_of[j] >= 0 ? group_of[j]
                                        : static_cast<int>(groups.size());
    if (into == static_cast<int>(groups.size())) groups.emplace_back();
    for (int p : merged) {
      if (group_of[p] >= 0 && group_of[p] != into) groups[group_of[p]].clear();
      group_of[p] = into;
    }
    groups[into] = merged;
  }
  std::vector<std::vector<int>> out;
  for (std::vector<int>& g : groups)
    if (g.size() >= 2) out.push_back(std::move(g));
  return out;
}

}  // namespace mocap

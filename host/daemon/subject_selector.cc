#include "subject_selector.h"

#include <algorithm>
#include <cmath>

#include "mocap/kinematics.h"

namespace mocap {
namespace {

// Boxes whose sizes differ by less than this fraction are one size (detector jitter).
constexpr double kSameSize = 0.01;

double Median(std::vector<double> v) {
  const size_t n = v.size();
  std::sort(v.begin(), v.end());
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Median pixel distance between the keypoints placed (finite) in both; infinite when none is.
double Distance(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  std::vector<double> d;
  for (size_t k = 0; k < a.size() && k < b.size(); ++k) {
    if (a[k].allFinite() && b[k].allFinite()) d.push_back((a[k] - b[k]).norm());
  }
  return d.empty() ? INFINITY : Median(std::move(d));
}

// The larger side of the box around the placed keypoints; 0 with fewer than two.
double BoxSize(const std::vector<Eigen::Vector2d>& placed) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(INFINITY), hi = -lo;
  int n = 0;
  for (const Eigen::Vector2d& p : placed) {
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p), n++;
  }
  return n > 1 ? (hi - lo).maxCoeff() : 0.0;
}

double Confidence(const v1::KeypointPerson& person) {
  double sum = 0;
  for (float c : person.confidence()) sum += c;
  return sum;
}

}  // namespace

std::vector<Eigen::Vector2d> ProjectSites(const Solver& solver, const Camera& camera) {
  BodyPose pose;
  ForwardKinematics(solver.skeleton(), solver.pose().data(), &pose);
  std::vector<Eigen::Vector2d> pixels;
  for (const Site& s : solver.layout().sites) {
    Eigen::Vector2d px(NAN, NAN);
    camera.Project(pose.position[s.bone] + pose.rotation[s.bone] * s.offset, &px);
    pixels.push_back(px);
  }
  return pixels;
}

SubjectSelector::SubjectSelector(int num_cameras, double min_confidence)
    : min_confidence_(min_confidence), previous_(num_cameras) {}

int SubjectSelector::Choose(const v1::KeypointFrame& frame, int camera,
                            const std::vector<Eigen::Vector2d>* predicted) {
  std::vector<Eigen::Vector2d>& previous = previous_[camera];
  if (!frame.detected()) return -1;
  if (frame.persons().empty()) {
    previous.clear();
    return -1;
  }
  int chosen = -1;
  if (frame.persons_size() > 1 && predicted) chosen = Nearest(frame, *predicted);
  if (chosen < 0 && frame.persons_size() > 1 && !previous.empty())
    chosen = Nearest(frame, previous);
  if (chosen < 0) chosen = Largest(frame);
  previous = Placed(frame.persons(chosen));
  return chosen;
}

std::vector<Eigen::Vector2d> SubjectSelector::Placed(const v1::KeypointPerson& person) const {
  std::vector<Eigen::Vector2d> placed(person.x_size(), Eigen::Vector2d(NAN, NAN));
  for (int k = 0; k < person.x_size(); ++k) {
    if (person.confidence(k) > min_confidence_) placed[k] = {person.x(k), person.y(k)};
  }
  return placed;
}

int SubjectSelector::Nearest(const v1::KeypointFrame& frame,
                             const std::vector<Eigen::Vector2d>& to) const {
  int best = -1;
  double best_distance = INFINITY;
  for (int p = 0; p < frame.persons_size(); ++p) {
    const double d = Distance(Placed(frame.persons(p)), to);
    if (d < best_distance) best_distance = d, best = p;
  }
  return best;
}

int SubjectSelector::Largest(const v1::KeypointFrame& frame) const {
  std::vector<double> size;
  for (const v1::KeypointPerson& p : frame.persons()) size.push_back(BoxSize(Placed(p)));
  const double largest = *std::max_element(size.begin(), size.end());
  int best = -1;
  double best_confidence = -INFINITY;
  for (int p = 0; p < frame.persons_size(); ++p) {
    const double c = Confidence(frame.persons(p));
    if (size[p] >= (1 - kSameSize) * largest && c > best_confidence) best_confidence = c, best = p;
  }
  return best;
}

}  // namespace mocap

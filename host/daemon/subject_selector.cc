#include "subject_selector.h"

#include <cmath>

#include "mocap/kinematics.h"
#include "stream_stats.h"

namespace mocap {
namespace {

double Confidence(const v1::KeypointPerson& person) {
  double sum = 0;
  for (float c : person.confidence()) sum += c;
  return sum;
}

// Median pixel distance of the person's confident keypoints to their predictions
// (infinite when none can be compared).
double Distance(const v1::KeypointPerson& person, const std::vector<Eigen::Vector2d>& predicted,
                double min_confidence) {
  std::vector<double> d;
  for (int k = 0; k < person.x_size() && k < static_cast<int>(predicted.size()); ++k) {
    if (person.confidence(k) > min_confidence && predicted[k].allFinite())
      d.push_back((Eigen::Vector2d(person.x(k), person.y(k)) - predicted[k]).norm());
  }
  return d.empty() ? INFINITY : Percentile(d, 0.5);
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

int ChooseSubject(const v1::KeypointFrame& frame, const std::vector<Eigen::Vector2d>& predicted,
                  double min_confidence) {
  int best = 0;
  double best_score = predicted.empty() ? -1 : INFINITY;
  for (int p = 0; p < frame.persons_size(); ++p) {
    if (predicted.empty()) {
      const double score = Confidence(frame.persons(p));
      if (score > best_score) best_score = score, best = p;
    } else {
      const double score = Distance(frame.persons(p), predicted, min_confidence);
      if (score < best_score) best_score = score, best = p;
    }
  }
  return best;
}

int ChooseSubject(const v1::KeypointFrame& frame, const Camera& camera, const Solver& solver) {
  const bool track = solver.initialised() && frame.persons_size() > 1;
  return ChooseSubject(frame, track ? ProjectSites(solver, camera) : std::vector<Eigen::Vector2d>(),
                       solver.options().min_confidence);
}

}  // namespace mocap

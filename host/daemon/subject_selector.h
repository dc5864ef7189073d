// Which of the persons a camera box detected is the subject, each camera remembering its
// previous choice. While a tracker (the solver) follows the subject, the person nearest the
// tracked pose's projection; before, the person nearest the camera's previous choice, so a
// bystander walking past is not taken for the subject; with neither, the largest person.
#ifndef MOCAP_DAEMON_SUBJECT_SELECTOR_H_
#define MOCAP_DAEMON_SUBJECT_SELECTOR_H_

#include <Eigen/Core>
#include <vector>

#include "mocap/solver.h"
#include "mocap/v1/keypoint_frame.pb.h"

namespace mocap {

// The pixels of the solver's keypoint sites in `camera` at its current pose; NaN where a
// site does not project (behind the camera).
std::vector<Eigen::Vector2d> ProjectSites(const Solver& solver, const Camera& camera);

class SubjectSelector {
 public:
  // Keypoints at or below min_confidence are not detected: they neither size nor place a
  // person.
  SubjectSelector(int num_cameras, double min_confidence);

  // The index of the subject among frame.persons() of `camera`, -1 for none. Among several
  // persons, in order:
  //  - nearest `predicted` (may be null: no tracker), the tracked pose's keypoint sites
  //    projected in this camera (NaN: not projected);
  //  - else nearest this camera's previous choice;
  //  - else the largest: the larger side of the box of its keypoints; boxes within 1% are
  //    one size, and then the most confident (sum of confidences) is taken.
  // Nearest: the median pixel distance over the keypoints placed in both; a rule that can
  // compare no person passes on to the next. A detected frame with nobody forgets the
  // camera's previous choice; a frame not detected (HS mode) keeps it.
  int Choose(const v1::KeypointFrame& frame, int camera,
             const std::vector<Eigen::Vector2d>* predicted);

 private:
  // The person's confident keypoints as pixels, NaN for the others.
  std::vector<Eigen::Vector2d> Placed(const v1::KeypointPerson& person) const;
  int Nearest(const v1::KeypointFrame& frame, const std::vector<Eigen::Vector2d>& to) const;
  int Largest(const v1::KeypointFrame& frame) const;

  double min_confidence_;
  std::vector<std::vector<Eigen::Vector2d>> previous_;  // per camera; empty: none
};

}  // namespace mocap

#endif  // MOCAP_DAEMON_SUBJECT_SELECTOR_H_

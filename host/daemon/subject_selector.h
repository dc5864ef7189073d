// Which of the persons a camera box detected is the subject. While the solver tracks, the
// person nearest the projection of the tracked pose (a bystander walking through is not
// taken for the subject); before, or with one person, the most confident.
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

// The index of the person whose keypoints above min_confidence lie nearest `predicted`
// (median pixel distance over the keypoints with a finite prediction); with `predicted`
// empty, the person with the largest sum of confidences. 0 for a frame without persons.
int ChooseSubject(const v1::KeypointFrame& frame, const std::vector<Eigen::Vector2d>& predicted,
                  double min_confidence);

// The subject of a frame of `camera`: nearest the solver's pose once it is initialised and
// the frame has several persons, else the most confident.
int ChooseSubject(const v1::KeypointFrame& frame, const Camera& camera, const Solver& solver);

}  // namespace mocap

#endif  // MOCAP_DAEMON_SUBJECT_SELECTOR_H_

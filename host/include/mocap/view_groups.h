// The people no tracked subject explains, grouped across the cameras: which detections in
// different views are one person, the first step of a new subject's birth. A group holds at
// most one person per camera, and its keypoints, triangulated from all its views, reproject
// close to every view's detections.
#ifndef MOCAP_VIEW_GROUPS_H_
#define MOCAP_VIEW_GROUPS_H_

#include <vector>

#include "mocap/camera.h"
#include "mocap/initialisation.h"

namespace mocap {

// One person detected by one camera: its confident keypoints (each Detection's camera is
// this person's camera).
struct ViewPerson {
  int camera = 0;
  std::vector<Detection> keypoints;
};

struct ViewGroupOptions {
  // A view belongs to a group when the median distance between its keypoints and their
  // triangulated points' projections is at most this.
  double max_error_px = 15.0;
  // Keypoints a view must share with the rest of its group (seen by two or more of its views).
  int min_shared = 6;
};

// The median reprojection error (pixels) of the worst view of `members` (indices into
// people) after triangulating every keypoint that two or more of them see; infinite when two
// members share a camera or a member has fewer than options.min_shared such keypoints.
double GroupError(const Rig& rig, const std::vector<ViewPerson>& people,
                  const std::vector<int>& members, const ViewGroupOptions& options);

// Groups (indices into people, ascending) of two or more views each whose GroupError is at
// most options.max_error_px; every person in at most one group. Greedy: pairs taken from the
// most consistent, a pair joining or merging groups only when the result stays consistent.
std::vector<std::vector<int>> GroupAcrossViews(const Rig& rig,
                                               const std::vector<ViewPerson>& people,
                                               const ViewGroupOptions& options = {});

}  // namespace mocap

#endif  // MOCAP_VIEW_GROUPS_H_

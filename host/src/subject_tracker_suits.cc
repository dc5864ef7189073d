// The suits' part of SubjectTracker: who wears which suit, and dressing a subject in it.
#include <algorithm>
#include <cmath>
#include <map>

#include "mocap/kinematics.h"
#include "mocap/subject_tracker.h"

namespace mocap {

std::vector<std::vector<int>> SubjectTracker::SuitBones(const std::vector<SuitCalibration>& suits) {
  std::vector<std::vector<int>> bones;
  for (const SuitCalibration& suit : suits) {
    bones.emplace_back();
    for (const ImuSite& site : suit.imus) bones.back().push_back(site.bone);
  }
  return bones;
}

void SubjectTracker::MatchSuits(double timestamp,
                                const std::vector<std::vector<ImuObservation>>& suits) {
  std::map<uint32_t, BodyPose> bodies;
  for (const auto& s : subjects_)
    if (s->solved) ForwardKinematics(s->solver->skeleton(), s->result.theta.data(), &bodies[s->id]);
  std::vector<std::vector<Eigen::Quaterniond>> readings(suits_.size());
  for (size_t k = 0; k < suits_.size(); ++k) {
    readings[k].assign(suits_[k].imus.size(), Eigen::Quaterniond(NAN, NAN, NAN, NAN));
    if (suits.empty()) continue;
    for (const ImuObservation& o : suits[k])
      if (o.has_orientation && o.imu >= 0 && o.imu < static_cast<int>(readings[k].size()))
        readings[k][o.imu] = o.orientation;
  }
  for (const auto& s : subjects_) {  // a suit whose readings the keypoints contradict
    const int suit = s->solved_with;
    if (suit < 0 || 2 * s->result.imus_distrusted.size() < suits_[suit].imus.size()) continue;
    matcher_.Forget(suit, s->id);
    counts_.suits_doubted++;
  }
  matcher_.Add(timestamp, bodies, readings);
  counts_.suit_changes = matcher_.changes();
  for (auto& s : subjects_) {
    const auto& wearers = matcher_.wearers();
    const auto it = std::find(wearers.begin(), wearers.end(), s->id);
    const int suit = it == wearers.end() ? -1 : static_cast<int>(it - wearers.begin());
    if (suit != s->suit) Dress(s.get(), suit);
  }
}

// The subject is solved with the suit's calibration from the next frame on (-1: the
// factory's, video only).
void SubjectTracker::Dress(Subject* subject, int suit) {
  std::string error;
  const bool ok = suit >= 0
                      ? subject->solver->SetCalibration(suits_[suit].skeleton, suits_[suit].layout,
                                                        suits_[suit].imus, &error)
                      : subject->solver->SetCalibration(reference_->skeleton(),
                                                        reference_->layout(), {}, &error);
  if (ok) subject->suit = suit;  // checked when the tracker was made: cannot fail
}

}  // namespace mocap

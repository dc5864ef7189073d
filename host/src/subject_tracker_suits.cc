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
  const auto& wearers = matcher_.wearers();
  const auto& leaders = matcher_.leaders();
  for (auto& s : subjects_) {
    const auto it = std::find(wearers.begin(), wearers.end(), s->id);
    const int suit = it == wearers.end() ? -1 : static_cast<int>(it - wearers.begin());
    int led = -1;  // an undecided suit it leads for
    for (size_t k = 0; k < leaders.size() && suit < 0 && led < 0; ++k)
      if (leaders[k] == s->id && !wearers[k]) led = static_cast<int>(k);
    // Without a leader (its history restarted when a frame did not solve it), the last one's
    // skeleton is kept while nobody else wears that suit.
    const int kept = s->skeleton >= 0 && !wearers[s->skeleton] ? s->skeleton : -1;
    const int skeleton = suit >= 0 ? suit : led >= 0 ? led : kept;
    if (suit != s->suit || skeleton != s->skeleton) Dress(s.get(), suit, skeleton);
  }
}

// The subject is solved from the next frame on with the suit's calibration and readings, or
// (suit -1) from video alone with the skeleton and layout of the suit `skeleton` (-1: the
// factory's).
void SubjectTracker::Dress(Subject* subject, int suit, int skeleton) {
  std::string error;
  const std::vector<ImuSite> none;
  const bool ok = skeleton >= 0 ? subject->solver->SetCalibration(
                                      suits_[skeleton].skeleton, suits_[skeleton].layout,
                                      suit >= 0 ? suits_[suit].imus : none, &error)
                                : subject->solver->SetCalibration(
                                      reference_->skeleton(), reference_->layout(), none, &error);
  // checked when the tracker was made: cannot fail
  if (ok) subject->suit = suit, subject->skeleton = skeleton;
}

}  // namespace mocap

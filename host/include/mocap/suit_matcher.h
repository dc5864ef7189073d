// Which tracked subject wears which suit of IMUs, from motion alone. A sensor turns with its
// bone: over any interval, the angle the sensor turned through equals the angle its bone
// turned through, whatever the sensor's mounting on the bone and its heading reference (both
// are rotations fixed over the interval, which conjugate the turn but keep its angle). Each
// frame, for every suit and subject, the suit's sensors' turn angles over the last
// `baseline_s` are compared with those of the subject's bones as solved from video; the
// median difference over the sensors, averaged over the frames of the last window_s in
// which the body moved, is the pair's disagreement. Suits are assigned to subjects by least
// disagreement (AssignRows, gated: within gate_rad, or time-locked: below lock_ratio times the
// pair's disagreement by chance, the same with the suit's turns shifted in time over the
// window; a wearer whose solve from video is poor disagrees beyond the gate, but far less than
// by chance, which an unrelated motion does not); a suit is worn by its subject once the window is
// full and the assignment beats, by `margin`, every alternative that gives the suit to another
// subject (swapping suits with that one's); it changes wearer only the same way.
#ifndef MOCAP_SUIT_MATCHER_H_
#define MOCAP_SUIT_MATCHER_H_

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <string>
#include <vector>

#include "mocap/kinematics.h"

namespace mocap {

struct SuitMatchOptions {
  double window_s = 2.0;       // the disagreement is averaged over this much of the take
  double baseline_s = 0.1;     // turn angles are taken over this interval
  double min_turn_rad = 0.05;  // frames where no bone or sensor turned this much say nothing
  double gate_rad = 0.15;      // a suit disagreeing more than this with every subject is on nobody
  double margin_rad = 0.03;    // the wearer's disagreement below every other subject's by this
  double lock_ratio = 0.75;    // beyond the gate, a pair below this fraction of chance is admitted
  bool IsValid(std::string* error) const;
};

class SuitMatcher {
 public:
  // suit_bones: per suit, the bone each of its sensors is on.
  SuitMatcher(std::vector<std::vector<int>> suit_bones, SuitMatchOptions options);

  // One frame. bodies: each tracked subject's solved pose, by id (a subject missing from a
  // frame has its history restarted). suits: per suit, per sensor, its orientation reading
  // (sensor -> its reference frame), or NaN coefficients when there is none this frame.
  void Add(double timestamp, const std::map<uint32_t, BodyPose>& bodies,
           const std::vector<std::vector<Eigen::Quaterniond>>& suits);

  // The suit is on nobody, and what was measured of it and of the subject `id` is forgotten:
  // both are decided again from the next window (the subject's pose was solved with the
  // suit's readings, so it agreed with them whoever wore it).
  void Forget(int suit, uint32_t id);

  // Per suit: the id of the subject wearing it, 0 while undecided or on nobody.
  const std::vector<uint32_t>& wearers() const { return wearers_; }
  // Per suit: the subject it is on by the least disagreement so far (its wearer once decided):
  // from kMinLeadingFrames moving frames, admissible or not, beating every alternative by
  // 0.01 rad (the current leader favoured by margin_rad); 0 for none. A guess, not a decision.
  const std::vector<uint32_t>& leaders() const { return leaders_; }
  // Per suit: its mean disagreement (rad) with each subject over the window, by id; only
  // pairs with at least min_frames moving frames (default: enough to decide on).
  std::map<uint32_t, double> Disagreements(int suit, int min_frames = kMinMovingFrames) const;
  static constexpr int kMinMovingFrames = 20;  // in the window, for a pair's disagreement to count
  static constexpr int kMinLeadingFrames = 4;  // for a leader: a guess
  // How many times a suit was decided for another subject than its last wearer while that
  // one was still tracked: a suit found on someone else than it was believed to be on.
  uint64_t changes() const { return changes_; }

 private:
  struct Timed {
    double time;
    std::vector<Eigen::Quaterniond> rotations;  // per sensor of the suit (a subject: its bones)
  };
  struct Turned {  // a moving frame of a pair: the suit's and the bones' turn angles
    double time;
    std::vector<double> sensors, bones;
    double median;  // of |sensor turn - bone turn| over the sensors (NaN: none measured)
  };
  struct Pair {
    std::deque<Turned> frames;  // the moving frames of the window
    double first = 0;           // when the pair's history (re)started
    double chance = NAN;        // its disagreement by chance, as last measured
    double chance_time = NAN;   // when (NaN: never)
    unsigned slot = 0;          // the pair's number, in order of birth
  };
  // The mean over the pair's frames of the median |sensor turn - bone turn|, the sensors' turns
  // taken `shift` frames later (circularly); shift 0: the disagreement.
  static double Disagreement(const Pair& pair, size_t shift);
  // The median over the sensors of |the suit's turn - the body's bone's turn|, NaN for none.
  static double MedianDifference(const Turned& suit, const Turned& body);
  // Whether the pair is admissible: within the gate, or time-locked (well below chance).
  bool Admissible(Pair& pair, double disagreement) const;
  // The turn angle of each sensor between the history's entry baseline_s ago and `now`
  // (NaN where either reading is missing); false when the history is too short.
  bool Turns(const std::deque<Timed>& history, const Timed& now, std::vector<double>* angles) const;
  void Decide(double timestamp);
  bool Clear(const Eigen::MatrixXd& cost, const std::vector<int>& to, int s, double margin) const;

  std::vector<std::vector<int>> suit_bones_;
  SuitMatchOptions options_;
  std::vector<std::deque<Timed>> suit_history_;
  std::map<uint32_t, std::vector<std::deque<Timed>>> subject_history_;  // per subject, per suit
  std::map<std::pair<int, uint32_t>, Pair> pairs_;                      // (suit, subject id)
  std::vector<uint32_t> wearers_;
  std::vector<uint32_t> leaders_;
  std::vector<uint32_t> decided_;  // per suit: the last wearer decided (0: none yet)
  uint64_t changes_ = 0;
  unsigned pairs_born_ = 0;
};

}  // namespace mocap

#endif  // MOCAP_SUIT_MATCHER_H_

// Several people on one stage. Each frame, every camera's detector lists the people it found in
// an order of its own; the tracker says which of them is which tracked subject and solves
// each subject with its own Solver:
//  1. Assignment, per camera: each tracked subject's pose (its last solve) is projected into
//     the view, and the view's people are assigned to subjects by the cost of the median
//     pixel distance between their keypoints and the projected sites, over the projected
//     body's size (AssignRows, gated).
//  2. Solves: each subject from the views assigned to it, the subjects in parallel.
//  3. Births: the people no subject explains are grouped across views (GroupAcrossViews); a
//     group whose centre recurs within birth_radius_m for birth_frames frames in a row is a
//     new subject, or a lost one found again when it stands where that one was last seen.
//  4. Losses: a subject no camera has assigned a person to for retire_s is retired; its id is
//     never used again.
//  5. Suits: which subject wears which suit of IMUs is found from motion (SuitMatcher); a
//     subject wearing one is solved with the suit's calibration (its skeleton, layout and
//     IMU sites) and readings from the next frame on, the others from video alone. Until a
//     suit is decided, the subject it agrees with best so far (its leader) is solved with its
//     skeleton and layout, not its readings: a performer's proportions from the start, at
//     worst another performer's instead of the session's default. A suit
//     whose readings the keypoints contradict (half its sensors distrusted by the solver's
//     slip monitor: a suit on another person than decided) is taken off and decided again.
#ifndef MOCAP_SUBJECT_TRACKER_H_
#define MOCAP_SUBJECT_TRACKER_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "mocap/solver.h"
#include "mocap/suit_matcher.h"
#include "mocap/view_groups.h"

namespace mocap {

struct TrackerOptions {
  // A person is assigned to a subject only when the median pixel distance between its
  // keypoints and the subject's projected sites is at most gate times the larger side of
  // the projected sites' box.
  double gate = 0.3;
  int birth_frames = 5;            // frames in a row a group of unexplained views must recur
  double birth_radius_m = 0.5;     // how far a recurring group's centre may move per frame
  double revive_radius_m = 1.0;    // a group this near a lost subject's last position is that one
  double retire_s = 2.0;           // unseen this long: retired
  int max_people_per_camera = 10;  // beyond: the least confident are counted and dropped
  int max_subjects = 8;            // births beyond are counted and refused
  int min_keypoints = 6;           // confident keypoints for a person to count at all
  double min_confidence = 0.0;     // keypoints at or below are not detected
  int threads = 2;                 // solves in parallel (1: one after the other)
  ViewGroupOptions grouping;
  SuitMatchOptions suits;
  bool IsValid(std::string* error) const;
};

struct SubjectFrame {
  uint32_t id = 0;  // 1, 2, ... in order of birth
  SolveResult result;
  std::vector<int> cameras;  // the views assigned to it this frame
  bool born = false;         // this frame is its first
  int suit = -1;             // the suit whose readings this frame's solve had, -1 for none
  int skeleton = -1;  // the suit whose calibration's skeleton and layout it had, -1: the session's
};

// A suit of IMUs and the calibration of its wearer: the skeleton, the keypoint layout on it,
// and the suit's IMU sites (mounting, position, heading reference) on that skeleton.
struct SuitCalibration {
  Skeleton skeleton;
  KeypointLayout layout;
  std::vector<ImuSite> imus;
};

struct TrackerCounts {
  uint64_t births = 0;
  uint64_t revivals = 0;  // lost subjects found again
  uint64_t retired = 0;
  uint64_t people_dropped = 0;     // over max_people_per_camera, or too few keypoints
  uint64_t births_refused = 0;     // people refused a birth over max_subjects, each once
  uint64_t views_unexplained = 0;  // people neither assigned nor in a group being born
  uint64_t suit_changes = 0;       // suits found on someone else than their last wearer
  // A suit taken off its wearer as the keypoints contradict half its sensors or more (the
  // solver's slip monitor): decided again from motion, the wearer solved from video meanwhile.
  uint64_t suits_doubted = 0;
};

class SubjectTracker {
 public:
  // A new solver for a subject being born (the session's skeleton, rig and layout).
  using SolverFactory = std::function<std::unique_ptr<Solver>()>;

  // suits: the suits that may be worn (none: video only); every calibration must fit the
  // factory's solvers (Solver::CheckCalibration), else std::invalid_argument.
  SubjectTracker(SolverFactory make_solver, TrackerOptions options,
                 std::vector<SuitCalibration> suits = {});
  ~SubjectTracker();

  // One frame: `people` holds every person every camera found (CameraObservation::camera
  // says which; a camera may appear any number of times, or not at all). Returns every
  // subject tracked after the frame, by id. *assigned (may be null): per entry of `people`,
  // the id of the subject it was assigned or born into, 0 for none.
  std::vector<SubjectFrame> Track(double timestamp, const std::vector<CameraObservation>& people,
                                  std::vector<uint32_t>* assigned = nullptr,
                                  const std::vector<std::vector<ImuObservation>>& suits = {});
  // Per suit: the id of the subject wearing it, 0 for none.
  const std::vector<uint32_t>& wearers() const { return matcher_.wearers(); }

  const TrackerCounts& counts() const { return counts_; }
  int tracked() const { return static_cast<int>(subjects_.size()); }
  const TrackerOptions& options() const { return options_; }

 private:
  struct Subject {
    uint32_t id = 0;
    std::unique_ptr<Solver> solver;
    double last_seen = 0;
    Eigen::Vector3d last_root{0, 0, 0};
    std::vector<int> views;  // indices into this frame's people
    SolveResult result;
    bool born = false;
    int suit = -1;             // the suit it is solved with
    int solved_with = -1;      // the suit this frame's solve had
    int skeleton = -1;         // the suit whose skeleton it is solved with (see Dress)
    int solved_skeleton = -1;  // this frame's
    bool solved = false;       // this frame
  };
  struct Candidate {
    Eigen::Vector3d centre;
    int frames = 0;
    bool refused = false;  // a birth refused over the cap (counted once)
  };
  static constexpr int kRefused = -2;  // Claim: over max_subjects

  std::vector<int> Admit(const std::vector<CameraObservation>& people);
  void Assign(const std::vector<CameraObservation>& people, const std::vector<int>& admitted,
              std::vector<int>* owner);
  void SolveAll(double timestamp, const std::vector<CameraObservation>& people,
                const std::vector<std::vector<ImuObservation>>& suits);
  void MatchSuits(double timestamp, const std::vector<std::vector<ImuObservation>>& suits);
  void Dress(Subject* subject, int suit, int skeleton);
  static std::vector<std::vector<int>> SuitBones(const std::vector<SuitCalibration>& suits);
  void Births(double timestamp, const std::vector<CameraObservation>& people,
              const std::vector<int>& admitted, std::vector<int>* owner);
  bool NearSeenSubject(const Eigen::Vector3d& centre, double timestamp) const;
  int Claim(const Eigen::Vector3d& centre, double timestamp,
            const std::vector<CameraObservation>& people, const std::vector<int>& members);
  void Retire(double timestamp);

  SolverFactory make_solver_;
  TrackerOptions options_;
  std::unique_ptr<Solver> reference_;  // the factory's first solver: the rig and layout
  std::vector<SuitCalibration> suits_;
  SuitMatcher matcher_;
  std::vector<std::unique_ptr<Subject>> subjects_;
  std::vector<Candidate> candidates_;
  uint32_t next_id_ = 1;
  TrackerCounts counts_;
};

}  // namespace mocap

#endif  // MOCAP_SUBJECT_TRACKER_H_

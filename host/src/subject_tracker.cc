#include "mocap/subject_tracker.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>
#include <thread>

#include "mocap/assignment.h"
#include "mocap/initialisation.h"
#include "mocap/kinematics.h"

namespace mocap {

namespace {

double Median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

bool Confident(const Keypoint2D& k, double min_confidence) {
  return k.confidence > min_confidence && std::isfinite(k.x) && std::isfinite(k.y);
}

int CountConfident(const CameraObservation& person, double min_confidence) {
  return static_cast<int>(
      std::count_if(person.keypoints.begin(), person.keypoints.end(),
                    [&](const Keypoint2D& k) { return Confident(k, min_confidence); }));
}

// Pixels of the subject's sites in `camera` (NaN where not projected), and the larger side of
// their box (0 when fewer than two project).
double Project(const BodyPose& body, const KeypointLayout& layout, const Camera& camera,
               std::vector<Eigen::Vector2d>* pixels) {
  pixels->assign(layout.sites.size(), Eigen::Vector2d(NAN, NAN));
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  int projected = 0;
  for (size_t k = 0; k < layout.sites.size(); ++k) {
    const Site& s = layout.sites[k];
    Eigen::Vector2d px;
    if (!camera.Project(body.position[s.bone] + body.rotation[s.bone] * s.offset, &px)) continue;
    (*pixels)[k] = px, lo = lo.cwiseMin(px), hi = hi.cwiseMax(px), projected++;
  }
  return projected < 2 ? 0.0 : (hi - lo).maxCoeff();
}

// The median distance between a person's keypoints and projected sites over `size`; infinite
// when fewer than min_keypoints are in both.
double Cost(const CameraObservation& person, const std::vector<Eigen::Vector2d>& pixels,
            double size, const TrackerOptions& options) {
  std::vector<double> d;
  for (size_t k = 0; k < person.keypoints.size() && k < pixels.size(); ++k) {
    const Keypoint2D& kp = person.keypoints[k];
    if (!Confident(kp, options.min_confidence) || !pixels[k].allFinite()) continue;
    d.push_back((Eigen::Vector2d(kp.x, kp.y) - pixels[k]).norm());
  }
  if (size <= 0 || static_cast<int>(d.size()) < options.min_keypoints) return INFINITY;
  return Median(d) / size;
}

ViewPerson ToViewPerson(const CameraObservation& person, double min_confidence) {
  ViewPerson view{person.camera, {}};
  for (size_t k = 0; k < person.keypoints.size(); ++k) {
    const Keypoint2D& kp = person.keypoints[k];
    if (Confident(kp, min_confidence))
      view.keypoints.push_back({person.camera, static_cast<int>(k), {kp.x, kp.y}, kp.confidence});
  }
  return view;
}

// The median of the group's triangulated keypoints (NaN when none triangulates).
Eigen::Vector3d GroupCentre(const Rig& rig, const std::vector<ViewPerson>& views,
                            const std::vector<int>& members) {
  std::map<int, std::vector<Detection>> by_keypoint;
  for (int m : members)
    for (const Detection& d : views[m].keypoints) by_keypoint[d.keypoint].push_back(d);
  std::vector<double> axes[3];
  for (const auto& [k, seen] : by_keypoint) {
    Eigen::Vector3d x;
    if (seen.size() < 2 || !TriangulatePoint(rig, seen, &x)) continue;
    for (int a = 0; a < 3; ++a) axes[a].push_back(x[a]);
  }
  if (axes[0].empty()) return Eigen::Vector3d::Constant(NAN);
  return {Median(axes[0]), Median(axes[1]), Median(axes[2])};
}

}  // namespace

bool TrackerOptions::IsValid(std::string* error) const {
  auto fail = [&](const char* what) {
    if (error) *error = what;
    return false;
  };
  if (!(gate >= 0) || !std::isfinite(gate)) return fail("gate must be finite and >= 0");
  if (birth_frames < 1) return fail("birth_frames must be >= 1");
  if (!(birth_radius_m > 0) || !(revive_radius_m >= 0))
    return fail("birth/revive radii must be > 0");
  if (!(retire_s > 0)) return fail("retire_s must be > 0");
  if (max_people_per_camera < 1 || max_subjects < 1)
    return fail("people and subject caps must be >= 1");
  if (min_keypoints < 2) return fail("min_keypoints must be >= 2");
  if (threads < 1) return fail("threads must be >= 1");
  return true;
}

SubjectTracker::SubjectTracker(SolverFactory make_solver, TrackerOptions options,
                               std::vector<SuitCalibration> suits)
    : make_solver_(std::move(make_solver)),
      options_(options),
      suits_(std::move(suits)),
      matcher_(SuitBones(suits_), options.suits) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("TrackerOptions: " + error);
  if (!make_solver_) throw std::invalid_argument("SubjectTracker needs a solver factory");
  reference_ = make_solver_();
  if (!reference_) throw std::invalid_argument("SubjectTracker: the solver factory made no solver");
  for (size_t k = 0; k < suits_.size(); ++k)
    if (!reference_->CheckCalibration(suits_[k].skeleton, suits_[k].layout, suits_[k].imus, &error))
      throw std::invalid_argument("suit " + std::to_string(k) + ": " + error);
}

SubjectTracker::~SubjectTracker() = default;

std::vector<SubjectFrame> SubjectTracker::Track(
    double timestamp, const std::vector<CameraObservation>& people, std::vector<uint32_t>* assigned,
    const std::vector<std::vector<ImuObservation>>& suits) {
  if (!suits.empty() && suits.size() != suits_.size())
    throw std::invalid_argument("SubjectTracker::Track: readings of " +
                                std::to_string(suits.size()) + " suits, not " +
                                std::to_string(suits_.size()));
  const std::vector<int> admitted = Admit(people);
  std::vector<int> owner(people.size(), -1);
  Assign(people, admitted, &owner);
  SolveAll(timestamp, people, suits);
  Births(timestamp, people, admitted, &owner);
  if (!suits_.empty()) MatchSuits(timestamp, suits);
  if (assigned) {  // before Retire, which renumbers the subjects (a retired one has no views)
    assigned->assign(people.size(), 0);
    for (size_t p = 0; p < people.size(); ++p)
      if (owner[p] >= 0) (*assigned)[p] = subjects_[owner[p]]->id;
  }
  Retire(timestamp);
  std::vector<SubjectFrame> out;
  for (const auto& s : subjects_) {
    std::vector<int> cameras;
    for (int p : s->views) cameras.push_back(people[p].camera);
    out.push_back({s->id, s->result, cameras, s->born, s->solved_with, s->solved_skeleton});
  }
  return out;
}

// Per entry of people: 1 when it takes part (a known camera, the layout's keypoint count,
// enough confident keypoints, within its camera's cap), else 0 (counted as dropped).
std::vector<int> SubjectTracker::Admit(const std::vector<CameraObservation>& people) {
  const Rig& rig = reference_->rig();
  const size_t keypoints = reference_->layout().sites.size();
  std::vector<int> admitted(people.size(), 0);
  std::map<int, std::vector<std::pair<double, int>>> by_camera;  // (-confidence sum, entry)
  for (size_t p = 0; p < people.size(); ++p) {
    const CameraObservation& person = people[p];
    if (person.camera < 0 || person.camera >= static_cast<int>(rig.cameras.size()) ||
        person.keypoints.size() != keypoints ||
        CountConfident(person, options_.min_confidence) < options_.min_keypoints) {
      counts_.people_dropped++;
      continue;
    }
    double sum = 0;
    for (const Keypoint2D& k : person.keypoints)
      if (Confident(k, options_.min_confidence)) sum += k.confidence;
    by_camera[person.camera].emplace_back(-sum, static_cast<int>(p));
  }
  for (auto& [camera, list] : by_camera) {
    std::sort(list.begin(), list.end());
    for (size_t i = 0; i < list.size(); ++i) {
      if (static_cast<int>(i) < options_.max_people_per_camera) {
        admitted[list[i].second] = 1;
      } else {
        counts_.people_dropped++;
      }
    }
  }
  return admitted;
}

void SubjectTracker::Assign(const std::vector<CameraObservation>& people,
                            const std::vector<int>& admitted, std::vector<int>* owner) {
  for (auto& s : subjects_) s->views.clear(), s->born = false;
  if (subjects_.empty()) return;
  const Rig& rig = reference_->rig();
  std::vector<BodyPose> bodies(subjects_.size());
  for (size_t s = 0; s < subjects_.size(); ++s)
    ForwardKinematics(subjects_[s]->solver->skeleton(), subjects_[s]->solver->pose().data(),
                      &bodies[s]);
  std::map<int, std::vector<int>> by_camera;
  for (size_t p = 0; p < people.size(); ++p)
    if (admitted[p]) by_camera[people[p].camera].push_back(static_cast<int>(p));
  std::vector<Eigen::Vector2d> pixels;
  for (const auto& [camera, entries] : by_camera) {
    Eigen::MatrixXd cost(entries.size(), subjects_.size());
    for (size_t s = 0; s < subjects_.size(); ++s) {
      const double size =
          Project(bodies[s], subjects_[s]->solver->layout(), rig.cameras[camera], &pixels);
      for (size_t i = 0; i < entries.size(); ++i)
        cost(i, s) = Cost(people[entries[i]], pixels, size, options_);
    }
    const std::vector<int> to = AssignRows(cost, options_.gate);
    for (size_t i = 0; i < entries.size(); ++i) {
      if (to[i] < 0) continue;
      (*owner)[entries[i]] = to[i];
      subjects_[to[i]]->views.push_back(entries[i]);
    }
  }
}

void SubjectTracker::SolveAll(double timestamp, const std::vector<CameraObservation>& people,
                              const std::vector<std::vector<ImuObservation>>& suits) {
  auto solve = [&](Subject& s) {
    const bool readings = s.suit >= 0 && !suits.empty() && !suits[s.suit].empty();
    s.solved = !s.views.empty() || readings;
    s.solved_with = readings ? s.suit : -1;
    s.solved_skeleton = s.skeleton;
    if (!s.solved) {  // nobody to solve from: the last pose is held
      s.result = SolveResult{};
      s.result.status = SolveStatus::kNoObservations;
      s.result.theta = s.solver->pose();
      s.result.timestamp = timestamp;
      s.result.message = "no camera's person was assigned to this subject";
      return;
    }
    FrameObservations frame;
    frame.timestamp = timestamp;
    for (int p : s.views) frame.cameras.push_back(people[p]);
    if (readings) frame.imus = suits[s.suit];
    s.result = s.solver->Solve(frame);
    if (s.views.empty()) return;  // seen by its suit only
    s.last_seen = timestamp;
    s.last_root = s.result.theta.head<3>();
  };
  const int workers = std::min<int>(options_.threads, static_cast<int>(subjects_.size()));
  std::vector<std::thread> threads;
  for (int w = 1; w < workers; ++w)
    threads.emplace_back([&, w] {
      for (size_t s = w; s < subjects_.size(); s += workers) solve(*subjects_[s]);
    });
  for (size_t s = 0; s < subjects_.size(); s += std::max(workers, 1)) solve(*subjects_[s]);
  for (std::thread& t : threads) t.join();
}

void SubjectTracker::Births(double timestamp, const std::vector<CameraObservation>& people,
                            const std::vector<int>& admitted, std::vector<int>* owner) {
  std::vector<ViewPerson> views;
  std::vector<int> entry;  // views[i] is people[entry[i]]
  for (size_t p = 0; p < people.size(); ++p) {
    if (!admitted[p] || (*owner)[p] >= 0) continue;
    views.push_back(ToViewPerson(people[p], options_.min_confidence));
    entry.push_back(static_cast<int>(p));
  }
  const Rig& rig = reference_->rig();
  std::vector<Candidate> recurring;
  std::vector<bool> used(candidates_.size(), false);
  int explained = 0;
  for (const std::vector<int>& group : GroupAcrossViews(rig, views, options_.grouping)) {
    const Eigen::Vector3d centre = GroupCentre(rig, views, group);
    if (!centre.allFinite() || NearSeenSubject(centre, timestamp)) continue;
    Candidate next{centre, 1};
    for (size_t c = 0; c < candidates_.size(); ++c)
      if (!used[c] && (candidates_[c].centre - centre).norm() <= options_.birth_radius_m) {
        next.frames = candidates_[c].frames + 1, next.refused = candidates_[c].refused;
        used[c] = true;
        break;
      }
    explained += static_cast<int>(group.size());
    if (next.frames < options_.birth_frames) {
      recurring.push_back(next);
      continue;
    }
    const int s = Claim(centre, timestamp, people, [&] {
      std::vector<int> members;
      for (int g : group) members.push_back(entry[g]);
      return members;
    }());
    if (s < 0) {  // not solvable yet, or over the cap: tried again next frame
      if (s == kRefused && !next.refused) counts_.births_refused++;  // a person once
      next.refused = next.refused || s == kRefused;
      recurring.push_back(next);
      continue;
    }
    for (int p : subjects_[s]->views) (*owner)[p] = s;
  }
  candidates_ = recurring;
  counts_.views_unexplained += views.size() - explained;
}

bool SubjectTracker::NearSeenSubject(const Eigen::Vector3d& centre, double timestamp) const {
  for (const auto& s : subjects_)
    if (s->last_seen == timestamp && (s->last_root - centre).norm() <= options_.birth_radius_m)
      return true;
  return false;
}

// The subject a recurring group of views (members, entries of people) is: a lost one last
// seen within revive_radius_m of its centre, else a new one; solved from those views. The
// subject's index, kRefused over the cap of subjects, or -1 when the solve failed.
int SubjectTracker::Claim(const Eigen::Vector3d& centre, double timestamp,
                          const std::vector<CameraObservation>& people,
                          const std::vector<int>& members) {
  FrameObservations frame;
  frame.timestamp = timestamp;
  for (int p : members) frame.cameras.push_back(people[p]);
  int lost = -1;
  double nearest = options_.revive_radius_m;
  for (size_t s = 0; s < subjects_.size(); ++s) {
    const double d = (subjects_[s]->last_root - centre).norm();
    if (subjects_[s]->last_seen < timestamp && d <= nearest)
      lost = static_cast<int>(s), nearest = d;
  }
  if (lost < 0 && tracked() >= options_.max_subjects) return kRefused;
  std::unique_ptr<Solver> solver = make_solver_();
  if (!solver) return -1;
  SolveResult result = solver->Solve(frame);
  if (result.status != SolveStatus::kInitialised && result.status != SolveStatus::kOk) return -1;
  if (lost >= 0) {
    counts_.revivals++;
  } else {
    counts_.births++;
    subjects_.push_back(std::make_unique<Subject>());
    subjects_.back()->id = next_id_++;
    subjects_.back()->born = true;
    lost = tracked() - 1;
  }
  Subject& s = *subjects_[lost];
  s.solver = std::move(solver), s.result = result, s.views = members, s.suit = -1,
  s.solved_with = -1, s.skeleton = -1, s.solved_skeleton = -1;
  s.solved = true;
  s.last_seen = timestamp, s.last_root = result.theta.head<3>();
  return lost;
}

void SubjectTracker::Retire(double timestamp) {
  const size_t before = subjects_.size();
  subjects_.erase(std::remove_if(subjects_.begin(), subjects_.end(),
                                 [&](const std::unique_ptr<Subject>& s) {
                                   return timestamp - s->last_seen > options_.retire_s;
                                 }),
                  subjects_.end());
  counts_.retired += before - subjects_.size();
}

}  // namespace mocap

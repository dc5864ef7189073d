#include "mocap/suit_matcher.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mocap/assignment.h"

namespace mocap {
namespace {

constexpr double kLeadMargin = 0.01;  // rad: a leader beats every alternative by this
constexpr int kChanceShifts = 8;  // chance: the suit's turns shifted by 1/8 ... 7/8 of the window
constexpr double kChanceEvery = 0.25;  // s: how often a pair's chance is measured again
constexpr int kChancePhases = 5;       // pairs measured again on as many different frames

double Median(std::vector<double>& v) {  // reorders v
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

template <typename T>
void DropBefore(double time, std::deque<T>* history) {
  while (!history->empty() && history->front().time < time) history->pop_front();
}

}  // namespace

bool SuitMatchOptions::IsValid(std::string* error) const {
  const bool ok = window_s > 0 && baseline_s > 0 && baseline_s < window_s && min_turn_rad >= 0 &&
                  gate_rad > 0 && margin_rad >= 0 && lock_ratio >= 0 && lock_ratio <= 1 &&
                  std::isfinite(window_s + gate_rad + margin_rad);
  if (!ok && error)
    *error =
        "window_s > baseline_s > 0, min_turn_rad >= 0, gate_rad > 0, margin_rad >= 0, "
        "0 <= lock_ratio <= 1, all finite";
  return ok;
}

SuitMatcher::SuitMatcher(std::vector<std::vector<int>> suit_bones, SuitMatchOptions options)
    : suit_bones_(std::move(suit_bones)),
      options_(options),
      suit_history_(suit_bones_.size()),
      wearers_(suit_bones_.size(), 0),
      leaders_(suit_bones_.size(), 0),
      decided_(suit_bones_.size(), 0) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument("SuitMatchOptions: " + error);
}

bool SuitMatcher::Turns(const std::deque<Timed>& history, const Timed& now,
                        std::vector<double>* angles) const {
  const Timed* then = nullptr;
  for (const Timed& t : history)
    if (t.time <= now.time - options_.baseline_s) then = &t;
  if (!then) return false;
  angles->assign(now.rotations.size(), NAN);
  for (size_t i = 0; i < now.rotations.size(); ++i) {
    const Eigen::Quaterniond &a = then->rotations[i], &b = now.rotations[i];
    if (a.coeffs().allFinite() && b.coeffs().allFinite()) (*angles)[i] = a.angularDistance(b);
  }
  return true;
}

void SuitMatcher::Add(double timestamp, const std::map<uint32_t, BodyPose>& bodies,
                      const std::vector<std::vector<Eigen::Quaterniond>>& suits) {
  if (suits.size() != suit_bones_.size())
    throw std::invalid_argument("SuitMatcher::Add: readings for " + std::to_string(suits.size()) +
                                " suits, not " + std::to_string(suit_bones_.size()));
  for (auto it = subject_history_.begin(); it != subject_history_.end();)  // subjects gone
    it = bodies.count(it->first) ? std::next(it) : subject_history_.erase(it);
  for (auto it = pairs_.begin(); it != pairs_.end();)
    it = bodies.count(it->first.second) ? std::next(it) : pairs_.erase(it);
  const double keep_from = timestamp - 2 * options_.baseline_s;
  for (size_t s = 0; s < suits.size(); ++s) {
    if (suits[s].size() != suit_bones_[s].size())
      throw std::invalid_argument("SuitMatcher::Add: suit " + std::to_string(s) + " has " +
                                  std::to_string(suit_bones_[s].size()) + " sensors");
    const Timed sensors{timestamp, suits[s]};
    std::vector<double> sensor_turns, bone_turns;
    const bool sensors_turned = Turns(suit_history_[s], sensors, &sensor_turns);
    suit_history_[s].push_back(sensors);
    DropBefore(keep_from, &suit_history_[s]);
    for (const auto& [id, body] : bodies) {
      Timed bones{timestamp, {}};
      for (int b : suit_bones_[s]) bones.rotations.emplace_back(body.rotation[b]);
      std::vector<std::deque<Timed>>& history = subject_history_[id];
      if (history.empty()) history.resize(suits.size());
      const auto [at, born] =
          pairs_.try_emplace({static_cast<int>(s), id}, Pair{{}, timestamp, NAN, NAN, pairs_born_});
      pairs_born_ += born;
      Pair& pair = at->second;
      const bool bones_turned = Turns(history[s], bones, &bone_turns);
      history[s].push_back(std::move(bones));
      DropBefore(keep_from, &history[s]);
      if (!sensors_turned || !bones_turned) continue;
      double most = 0;  // NaN never compares greater
      for (size_t i = 0; i < sensor_turns.size(); ++i)
        if (!std::isnan(sensor_turns[i] + bone_turns[i]))
          most = std::max({most, sensor_turns[i], bone_turns[i]});
      if (most >= options_.min_turn_rad) {
        pair.frames.push_back(Turned{timestamp, sensor_turns, bone_turns, NAN});
        pair.frames.back().median = MedianDifference(pair.frames.back(), pair.frames.back());
      }
      DropBefore(timestamp - options_.window_s, &pair.frames);
    }
  }
  Decide(timestamp);
}

void SuitMatcher::Forget(int suit, uint32_t id) {
  for (auto it = pairs_.begin(); it != pairs_.end();)
    it = it->first.first == suit || it->first.second == id ? pairs_.erase(it) : std::next(it);
  if (suit >= 0 && suit < static_cast<int>(wearers_.size())) wearers_[suit] = leaders_[suit] = 0;
}

double SuitMatcher::MedianDifference(const Turned& suit, const Turned& body) {
  thread_local std::vector<double> differences;
  differences.clear();
  for (size_t i = 0; i < body.bones.size(); ++i)
    if (!std::isnan(suit.sensors[i] + body.bones[i]))
      differences.push_back(std::abs(suit.sensors[i] - body.bones[i]));
  return differences.empty() ? NAN : Median(differences);
}

double SuitMatcher::Disagreement(const Pair& pair, size_t shift) {
  const size_t n = pair.frames.size();
  double sum = 0;
  int counted = 0;
  for (size_t f = 0; f < n; ++f) {
    const double d = shift == 0 ? pair.frames[f].median  // measured when the frame came
                                : MedianDifference(pair.frames[(f + shift) % n], pair.frames[f]);
    if (std::isnan(d)) continue;
    sum += d;
    counted++;
  }
  return counted ? sum / counted : NAN;
}

bool SuitMatcher::Admissible(Pair& pair, double disagreement) const {
  if (disagreement <= options_.gate_rad) return true;
  const double now = pair.frames.back().time;  // chance changes slowly: measured every kChanceEvery
  if (!(now - pair.chance_time < kChanceEvery)) {
    const size_t n = pair.frames.size();
    double sum = 0;
    for (int k = 1; k < kChanceShifts; ++k) sum += Disagreement(pair, k * n / kChanceShifts);
    // The pairs born on one frame are measured again on different frames (their phase within
    // kChanceEvery), not all on one.
    const double phase = static_cast<double>(pair.slot % kChancePhases) / kChancePhases;
    pair.chance = sum / (kChanceShifts - 1);
    pair.chance_time = std::isnan(pair.chance_time) ? now - phase * kChanceEvery : now;
  }
  return disagreement <= options_.lock_ratio * pair.chance;
}

std::map<uint32_t, double> SuitMatcher::Disagreements(int suit, int min_frames) const {
  std::map<uint32_t, double> out;
  for (const auto& [key, pair] : pairs_) {
    if (key.first != suit || static_cast<int>(pair.frames.size()) < min_frames) continue;
    const double d = Disagreement(pair, 0);
    if (std::isfinite(d)) out[key.second] = d;
  }
  return out;
}

// Whether suit s's subject in the assignment `to` is clear: giving the suit to any other
// subject instead (and that subject's suit, if any, to s's subject) costs at least the margin.
bool SuitMatcher::Clear(const Eigen::MatrixXd& cost, const std::vector<int>& to, int s,
                        double margin) const {
  const int j = to[s];
  for (int k = 0; k < cost.cols(); ++k) {
    if (k == j || !std::isfinite(cost(s, k))) continue;
    const auto other = std::find(to.begin(), to.end(), k);  // the suit k wears now
    double alternative = cost(s, k) - cost(s, j);
    if (other != to.end()) {
      const int t = static_cast<int>(other - to.begin());
      if (!std::isfinite(cost(t, j))) continue;  // that swap is not possible
      alternative += cost(t, j) - cost(t, k);
    }
    if (alternative < margin) return false;
  }
  return true;
}

void SuitMatcher::Decide(double timestamp) {
  std::vector<uint32_t> ids;
  for (const auto& [id, history] : subject_history_) ids.push_back(id);
  // The admissible pairs' disagreements; every admissible pair may be made (the gate above
  // them all), the cheapest total among the most pairs.
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(suit_bones_.size(), ids.size(), NAN);
  Eigen::MatrixXd early = cost;  // the same before the window is full: the leaders
  std::vector<std::map<uint32_t, double>> admissible(suit_bones_.size());
  double highest = options_.gate_rad, most = options_.gate_rad;
  std::vector<std::map<uint32_t, double>> measured(suit_bones_.size());
  for (size_t s = 0; s < suit_bones_.size(); ++s) {
    const std::map<uint32_t, double> glimpsed =
        Disagreements(static_cast<int>(s), kMinLeadingFrames);
    for (const auto& [id, d] : glimpsed)  // the pairs measured enough to decide on
      if (pairs_.at({static_cast<int>(s), id}).frames.size() >= kMinMovingFrames)
        measured[s][id] = d;
    for (const auto& [id, d] : measured[s])
      if (Admissible(pairs_.at({static_cast<int>(s), id}), d)) admissible[s][id] = d;
    for (size_t j = 0; j < ids.size(); ++j) {
      const auto it = glimpsed.find(ids[j]);
      if (it != glimpsed.end()) {  // the leader keeps its place unless beaten by the margin
        early(s, j) = it->second - (leaders_[s] == ids[j] ? options_.margin_rad : 0.0);
        most = std::max(most, it->second);
      }
      const auto ok = admissible[s].find(ids[j]);
      const Pair& pair = pairs_.at({static_cast<int>(s), ids[j]});
      if (ok == admissible[s].end() || timestamp - pair.first < options_.window_s) continue;
      cost(s, j) = ok->second;
      highest = std::max(highest, ok->second);
    }
  }
  const std::vector<int> to = AssignRows(cost, 2 * highest);
  const std::vector<int> led = AssignRows(early, 2 * most);  // every measured pair may lead
  for (size_t s = 0; s < suit_bones_.size(); ++s) {
    uint32_t& wearer = wearers_[s];
    if (wearer && !subject_history_.count(wearer)) wearer = 0;  // retired
    if (to[s] < 0) {  // its wearer's pair measured and no longer admissible: on nobody
      if (wearer && measured[s].count(wearer) && !admissible[s].count(wearer)) wearer = 0;
      continue;
    }
    if (!Clear(cost, to, static_cast<int>(s), options_.margin_rad) || wearer == ids[to[s]])
      continue;
    wearer = ids[to[s]];
    // on someone else than its last wearer, who is still here
    if (decided_[s] && decided_[s] != wearer && subject_history_.count(decided_[s])) changes_++;
    decided_[s] = wearer;
  }
  for (size_t s = 0; s < suit_bones_.size(); ++s)
    leaders_[s] = wearers_[s]                                                          ? wearers_[s]
                  : led[s] >= 0 && Clear(early, led, static_cast<int>(s), kLeadMargin) ? ids[led[s]]
                                                                                       : 0;
}

}  // namespace mocap

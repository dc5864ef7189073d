#include "calibration_queue.h"

#include <algorithm>

namespace mocap {

bool CalibrationQueue::Add(const v1::Calibration& c, const Solver& solver, std::string* error) {
  const auto seen = sequences_.find(c.source());
  if (seen != sequences_.end() && c.sequence() <= seen->second) {
    counts_.repeated++;
    return true;
  }
  PendingCalibration p;
  if (!Parse(c, solver, &p, error) ||
      !solver.CheckCalibration(p.skeleton, p.layout, p.imus, error)) {
    counts_.rejected++;
    return false;
  }
  const auto at =
      std::upper_bound(pending_.begin(), pending_.end(), p.valid_from_ns,
                       [](int64_t t, const PendingCalibration& q) { return t < q.valid_from_ns; });
  pending_.insert(at, std::move(p));
  sequences_[c.source()] = c.sequence();
  return true;
}

bool CalibrationQueue::Parse(const v1::Calibration& c, const Solver& solver, PendingCalibration* p,
                             std::string* error) const {
  p->valid_from_ns = c.valid_from_ns();
  if (!ParseSkeletonJson(c.skeleton_json(), &p->skeleton, error)) return false;
  KeypointLayout layout;
  if (!ParseKeypointLayoutJson(c.layout_json(), p->skeleton, &layout, error)) return false;
  const KeypointLayout& ours = solver.layout();
  if (layout.name != ours.name || layout.names != ours.names)
    return *error = "layout '" + layout.name + "' is not the session's " + ours.name, false;
  p->layout = layout.ScaledTo(p->skeleton);
  std::vector<ImuSite> sites;
  if (!ParseImuSitesJson(c.imus_json(), p->skeleton, &sites, error)) return false;
  p->imus = solver.imus();  // sensors the calibration leaves out keep their place, unused
  p->calibrated.assign(p->imus.size(), false);
  for (ImuSite& site : sites) {
    const auto it = std::find_if(p->imus.begin(), p->imus.end(),
                                 [&](const ImuSite& s) { return s.name == site.name; });
    if (it == p->imus.end())
      return *error = "sensor '" + site.name + "' is not in the IMU set", false;
    p->calibrated[it - p->imus.begin()] = true;
    *it = std::move(site);
  }
  return true;
}

std::vector<PendingCalibration> CalibrationQueue::TakeDue(int64_t time_ns) {
  const auto end =
      std::upper_bound(pending_.begin(), pending_.end(), time_ns,
                       [](int64_t t, const PendingCalibration& q) { return t < q.valid_from_ns; });
  std::vector<PendingCalibration> due(std::make_move_iterator(pending_.begin()),
                                      std::make_move_iterator(end));
  pending_.erase(pending_.begin(), end);
  return due;
}

}  // namespace mocap

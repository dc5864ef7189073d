#include "mocap/sites.h"

#include "json_util.h"
#include "mocap/so3.h"

namespace mocap {

KeypointLayout KeypointLayout::ScaledTo(const Skeleton& skeleton) const {
  KeypointLayout out = *this;
  const double height = skeleton.RestHeight();
  if (reference_height > 0.0 && height > 0.0) {
    for (Site& s : out.sites) s.offset *= height / reference_height;
    out.reference_height = height;
  }
  return out;
}

namespace {

bool ReadBone(const nlohmann::json& j, const Skeleton& skeleton, int* bone, std::string* error) {
  const std::string name =
      j.contains("bone") && j["bone"].is_string() ? j["bone"].get<std::string>() : "";
  *bone = skeleton.BoneIndex(name);
  if (*bone < 0) *error = "unknown bone '" + name + "'";
  return *bone >= 0;
}

bool ReadOptionalVector3(const nlohmann::json& j, const char* key, Eigen::Vector3d* v) {
  if (!j.contains(key)) return true;
  return internal::ReadVector3(j[key], v);
}

}  // namespace

static bool ParseKeypointLayoutJsonUnguarded(const std::string& text, const Skeleton& skeleton,
                                             KeypointLayout* out, std::string* error) {
  nlohmann::json j;
  if (!internal::ParseJson(text, &j, error)) return false;
  if (!j.is_object() || j.value("format", "") != "mocap.layout/1" || !j.contains("keypoints") ||
      !j["keypoints"].is_array()) {
    *error = "not a mocap.layout/1 file";
    return false;
  }
  KeypointLayout layout;
  layout.name = j.value("name", "");
  layout.reference_height = j.value("reference_height", 0.0);
  for (const auto& jk : j["keypoints"]) {
    Site site;
    if (!jk.is_object() || !jk.contains("name") || !jk["name"].is_string()) {
      *error = "keypoint without a name";
      return false;
    }
    const std::string name = jk["name"].get<std::string>();
    if (!ReadBone(jk, skeleton, &site.bone, error) ||
        !ReadOptionalVector3(jk, "offset", &site.offset)) {
      *error = "keypoint '" + name + "': " + (error->empty() ? "bad offset" : *error);
      return false;
    }
    layout.names.push_back(name);
    layout.sites.push_back(site);
  }
  *out = std::move(layout);
  return true;
}

bool ParseKeypointLayoutJson(const std::string& text, const Skeleton& skeleton, KeypointLayout* out,
                             std::string* error) {
  return internal::Guarded(
      error, [&] { return ParseKeypointLayoutJsonUnguarded(text, skeleton, out, error); });
}

bool LoadKeypointLayoutJson(const std::string& path, const Skeleton& skeleton, KeypointLayout* out,
                            std::string* error) {
  return internal::LoadFile(path, error, [&](const std::string& text) {
    return ParseKeypointLayoutJson(text, skeleton, out, error);
  });
}

static bool ParseImuSitesJsonUnguarded(const std::string& text, const Skeleton& skeleton,
                                       std::vector<ImuSite>* out, std::string* error) {
  nlohmann::json j;
  if (!internal::ParseJson(text, &j, error)) return false;
  if (!j.is_object() || j.value("format", "") != "mocap.imus/1" || !j.contains("imus") ||
      !j["imus"].is_array()) {
    *error = "not a mocap.imus/1 file";
    return false;
  }
  std::vector<ImuSite> sites;
  for (const auto& ji : j["imus"]) {
    ImuSite site;
    site.name = ji.is_object() ? ji.value("name", "") : "";
    Eigen::Vector3d mount(0, 0, 0), reference(0, 0, 0);
    if (site.name.empty() || !ReadBone(ji, skeleton, &site.bone, error) ||
        !ReadOptionalVector3(ji, "mount", &mount) ||
        !ReadOptionalVector3(ji, "offset", &site.offset) ||
        !ReadOptionalVector3(ji, "reference", &reference)) {
      *error = "imu '" + site.name + "': " + (error->empty() ? "bad name or vector" : *error);
      return false;
    }
    site.mount = Exp(mount);
    site.reference = Exp(reference);
    sites.push_back(site);
  }
  *out = std::move(sites);
  return true;
}

bool ParseImuSitesJson(const std::string& text, const Skeleton& skeleton, std::vector<ImuSite>* out,
                       std::string* error) {
  return internal::Guarded(error,
                           [&] { return ParseImuSitesJsonUnguarded(text, skeleton, out, error); });
}

bool LoadImuSitesJson(const std::string& path, const Skeleton& skeleton, std::vector<ImuSite>* out,
                      std::string* error) {
  return internal::LoadFile(path, error, [&](const std::string& text) {
    return ParseImuSitesJson(text, skeleton, out, error);
  });
}

namespace {

nlohmann::json Vector(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

std::string KeypointLayoutToJson(const Skeleton& skeleton, const KeypointLayout& layout) {
  nlohmann::json j;
  j["format"] = "mocap.layout/1";
  j["name"] = layout.name;
  j["reference_height"] = skeleton.RestHeight();
  j["keypoints"] = nlohmann::json::array();
  for (int k = 0; k < layout.size(); ++k) {
    j["keypoints"].push_back({{"name", layout.names[k]},
                              {"bone", skeleton.bone(layout.sites[k].bone).name},
                              {"offset", Vector(layout.sites[k].offset)}});
  }
  return j.dump(1);
}

std::string ImuSitesToJson(const Skeleton& skeleton, const std::vector<ImuSite>& imus) {
  nlohmann::json j;
  j["format"] = "mocap.imus/1";
  j["imus"] = nlohmann::json::array();
  for (const ImuSite& s : imus) {
    j["imus"].push_back({{"name", s.name},
                         {"bone", skeleton.bone(s.bone).name},
                         {"mount", Vector(Log(s.mount))},
                         {"offset", Vector(s.offset)},
                         {"reference", Vector(Log(s.reference))}});
  }
  return j.dump(1);
}

}  // namespace mocap

#include "mocap/skeleton.h"

#include <algorithm>
#include <limits>

#include "json_util.h"

namespace mocap {

const char* const kCanonicalBoneNames[21] = {
    "pelvis",      "spine_lower", "spine_upper", "neck",       "head",        "clavicle_l",
    "upper_arm_l", "forearm_l",   "hand_l",      "clavicle_r", "upper_arm_r", "forearm_r",
    "hand_r",      "thigh_l",     "shin_l",      "foot_l",     "toes_l",      "thigh_r",
    "shin_r",      "foot_r",      "toes_r"};

bool Skeleton::Create(std::vector<Bone> bones, Skeleton* out, std::string* error) {
  if (bones.empty()) {
    *error = "skeleton has no bones";
    return false;
  }
  for (int b = 0; b < static_cast<int>(bones.size()); ++b) {
    const int parent = bones[b].parent;
    if ((b == 0) != (parent < 0)) {
      *error = "bone '" + bones[b].name + "': only the first bone may (and must) be the root";
      return false;
    }
    if (parent >= b) {
      *error = "bone '" + bones[b].name + "': parent must come before the bone";
      return false;
    }
    if (!bones[b].offset.allFinite()) {
      *error = "bone '" + bones[b].name + "': offset is not finite";
      return false;
    }
    for (int o = 0; o < b; ++o) {
      if (bones[o].name == bones[b].name) {
        *error = "duplicate bone name '" + bones[b].name + "'";
        return false;
      }
    }
  }
  out->bones_ = std::move(bones);
  out->chains_.assign(out->bones_.size(), {});
  for (int b = 0; b < out->num_bones(); ++b) {
    for (int j = b; j >= 0; j = out->bones_[j].parent) out->chains_[b].push_back(j);
  }
  return true;
}

int Skeleton::BoneIndex(const std::string& name) const {
  for (int b = 0; b < num_bones(); ++b) {
    if (bones_[b].name == name) return b;
  }
  return -1;
}

double Skeleton::RestHeight() const {
  std::vector<Eigen::Vector3d> p(bones_.size());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int b = 0; b < num_bones(); ++b) {
    p[b] = b == 0 ? bones_[b].offset : p[bones_[b].parent] + bones_[b].offset;
    lo = std::min(lo, p[b].z());
    hi = std::max(hi, p[b].z());
  }
  return hi - lo;
}

static bool ParseSkeletonJsonUnguarded(const std::string& text, Skeleton* out, std::string* error) {
  nlohmann::json j;
  if (!internal::ParseJson(text, &j, error)) return false;
  if (!j.is_object() || j.value("format", "") != "mocap.skeleton/1") {
    *error = "not a mocap.skeleton/1 file";
    return false;
  }
  if (!j.contains("bones") || !j["bones"].is_array()) {
    *error = "skeleton file has no 'bones' array";
    return false;
  }
  std::vector<Skeleton::Bone> bones;
  for (const auto& jb : j["bones"]) {
    Skeleton::Bone bone;
    if (!jb.is_object() || !jb.contains("name") || !jb["name"].is_string()) {
      *error = "bone without a name";
      return false;
    }
    bone.name = jb["name"].get<std::string>();
    const auto& parent = jb.contains("parent") ? jb["parent"] : nlohmann::json();
    if (parent.is_string()) {
      const std::string pname = parent.get<std::string>();
      for (int o = 0; o < static_cast<int>(bones.size()); ++o) {
        if (bones[o].name == pname) bone.parent = o;
      }
      if (bone.parent < 0) {
        *error = "bone '" + bone.name + "': parent '" + pname + "' is not listed before it";
        return false;
      }
    } else if (!parent.is_null()) {
      *error = "bone '" + bone.name + "': parent must be a bone name or null";
      return false;
    }
    if (!jb.contains("offset") || !internal::ReadVector3(jb["offset"], &bone.offset)) {
      *error = "bone '" + bone.name + "': offset must be 3 finite numbers";
      return false;
    }
    bones.push_back(std::move(bone));
  }
  return Skeleton::Create(std::move(bones), out, error);
}

bool ParseSkeletonJson(const std::string& text, Skeleton* out, std::string* error) {
  return internal::Guarded(error, [&] { return ParseSkeletonJsonUnguarded(text, out, error); });
}

bool LoadSkeletonJson(const std::string& path, Skeleton* out, std::string* error) {
  return internal::LoadFile(
      path, error, [&](const std::string& text) { return ParseSkeletonJson(text, out, error); });
}

std::string SkeletonToJson(const Skeleton& skeleton) {
  nlohmann::json j;
  j["format"] = "mocap.skeleton/1";
  j["units"] = "m";
  j["bones"] = nlohmann::json::array();
  for (const auto& bone : skeleton.bones()) {
    nlohmann::json jb;
    jb["name"] = bone.name;
    jb["parent"] =
        bone.parent < 0 ? nlohmann::json() : nlohmann::json(skeleton.bone(bone.parent).name);
    jb["offset"] = {bone.offset.x(), bone.offset.y(), bone.offset.z()};
    j["bones"].push_back(jb);
  }
  return j.dump(2);
}

}  // namespace mocap

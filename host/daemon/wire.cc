#include "wire.h"

#include <cmath>
#include <initializer_list>

#include "mocap/v1/calibration.pb.h"
#include "mocap/v1/health.pb.h"
#include "mocap/v1/imu_batch.pb.h"
#include "mocap/v1/keypoint_frame.pb.h"
#include "mocap/v1/pose_frame.pb.h"
#include "protobuf_log.h"

namespace mocap::wire {
namespace {

template <typename Values>
bool AllFinite(const Values& values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

// Content checks of a parsed message; sets *detail and returns the reason on failure.
DropReason Check(const v1::KeypointFrame& m, std::string* detail) {
  if (m.camera_id().empty())
    return *detail = "KeypointFrame without camera_id", DropReason::kInvalid;
  if (m.persons_size() > kMaxPersons)
    return *detail = m.camera_id() + ": " + std::to_string(m.persons_size()) + " persons",
           DropReason::kInvalid;
  for (const auto& p : m.persons()) {
    if (p.x_size() > kMaxKeypoints) {
      *detail = m.camera_id() + ": " + std::to_string(p.x_size()) + " keypoints per person";
      return DropReason::kInvalid;
    }
    if (p.x_size() != p.y_size() || p.x_size() != p.confidence_size()) {
      *detail = m.camera_id() + ": x, y, confidence of different lengths";
      return DropReason::kInvalid;
    }
    if (!AllFinite(p.x()) || !AllFinite(p.y()) || !AllFinite(p.confidence())) {
      *detail = m.camera_id() + " frame " + std::to_string(m.frame_index()) + " holds NaN or inf";
      return DropReason::kNotFinite;
    }
  }
  return DropReason::kNone;
}

DropReason Check(const v1::ImuBatch& m, std::string* detail) {
  if (m.samples_size() > kMaxSamples)
    return *detail = m.hub_id() + ": " + std::to_string(m.samples_size()) + " samples",
           DropReason::kInvalid;
  for (const auto& s : m.samples()) {
    if (s.sensor_id().empty())
      return *detail = m.hub_id() + ": sample without sensor_id", DropReason::kInvalid;
    for (double v : {s.qw(), s.qx(), s.qy(), s.qz(), s.ax(), s.ay(), s.az()}) {
      if (!std::isfinite(v))
        return *detail = m.hub_id() + "/" + s.sensor_id() + " holds NaN or inf",
               DropReason::kNotFinite;
    }
  }
  return DropReason::kNone;
}

DropReason Check(const v1::PoseFrame& m, std::string* detail) {
  if (!AllFinite(m.theta()))
    return *detail = "PoseFrame theta holds NaN or inf", DropReason::kNotFinite;
  return DropReason::kNone;
}

DropReason Check(const v1::Health& m, std::string* detail) {
  if (m.streams_size() > kMaxStreams)
    return *detail = m.source() + ": " + std::to_string(m.streams_size()) + " streams",
           DropReason::kInvalid;
  return DropReason::kNone;
}

DropReason Check(const v1::Calibration& m, std::string* detail) {
  if (m.skeleton_json().empty() || m.imus_json().empty() || m.layout_json().empty()) {
    *detail = "Calibration from '" + m.source() + "' without its skeleton, IMU sites or layout";
    return DropReason::kInvalid;
  }
  return DropReason::kNone;
}

template <typename M>
Decoded Parse(std::string_view payload) {
  Decoded out;
  auto message = std::make_unique<M>();
  if (!message->ParseFromArray(payload.data(), static_cast<int>(payload.size()))) {
    out.reason = DropReason::kUndecodable;
    out.detail = M::descriptor()->full_name() + ": not a valid encoding";
    return out;
  }
  out.reason = Check(*message, &out.detail);
  if (out.reason == DropReason::kNone) out.message = std::move(message);
  return out;
}

}  // namespace

const char* ToString(DropReason reason) {
  switch (reason) {
    case DropReason::kNone:
      return "none";
    case DropReason::kUnknownType:
      return "unknown_type";
    case DropReason::kWrongVersion:
      return "wrong_version";
    case DropReason::kOversized:
      return "oversized";
    case DropReason::kUndecodable:
      return "undecodable";
    case DropReason::kNotFinite:
      return "not_finite";
    case DropReason::kInvalid:
      return "invalid";
  }
  return "?";
}

std::string TypeName(const google::protobuf::Message& message) {
  return message.GetDescriptor()->full_name();
}

Decoded DecodeMessage(std::string_view type, std::string_view payload) {
  LimitProtobufLog();
  Decoded out;
  if (payload.size() > kMaxPayload) {
    out.reason = DropReason::kOversized;
    out.detail = std::to_string(payload.size()) + " bytes";
    return out;
  }
  if (type == "mocap.v1.KeypointFrame") return Parse<v1::KeypointFrame>(payload);
  if (type == "mocap.v1.ImuBatch") return Parse<v1::ImuBatch>(payload);
  if (type == "mocap.v1.PoseFrame") return Parse<v1::PoseFrame>(payload);
  if (type == "mocap.v1.Health") return Parse<v1::Health>(payload);
  if (type == "mocap.v1.Calibration") return Parse<v1::Calibration>(payload);
  const std::string_view package =
      type.substr(0, type.rfind('.') == std::string_view::npos ? 0 : type.rfind('.'));
  const bool other_version = package.substr(0, 6) == "mocap." && package != kVersion;
  out.reason = other_version ? DropReason::kWrongVersion : DropReason::kUnknownType;
  out.detail = "message type '" + std::string(type.substr(0, 80)) + "'";
  return out;
}

}  // namespace mocap::wire

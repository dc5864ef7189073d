// The C++ side of the golden conformance vectors (tests/golden/), and the drop reasons.
#include "wire.h"

#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "mocap/v1/health.pb.h"
#include "mocap/v1/imu_batch.pb.h"
#include "mocap/v1/keypoint_frame.pb.h"
#include "protobuf_log.h"

namespace mocap::wire {
namespace {

std::string Read(const std::string& name) {
  std::ifstream in(std::string(MOCAP_GOLDEN_DIR) + "/" + name, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(Wire, GoldenVectorsDecodeToTheirExpectedMessagesAndReencodeToTheSameBytes) {
  const auto index = nlohmann::json::parse(Read("index.json"));
  int checked = 0;
  for (const auto& [name, entry] : index.items()) {
    SCOPED_TRACE(name);
    const std::string bytes = Read(name + ".bin");
    ASSERT_FALSE(bytes.empty());
    Decoded d = DecodeMessage(entry.at("type").get<std::string>(), bytes);
    if (entry.value("rejected", false)) {
      EXPECT_EQ(d.reason, DropReason::kUndecodable);
      continue;
    }
    ASSERT_TRUE(d.message) << d.detail;
    EXPECT_EQ(d.message->SerializeAsString(), bytes);  // unknown fields kept by a relay
    std::unique_ptr<google::protobuf::Message> expected(d.message->New());
    ASSERT_TRUE(
        google::protobuf::util::JsonStringToMessage(Read(name + ".json"), expected.get()).ok());
    d.message->DiscardUnknownFields();
    EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(*d.message, *expected))
        << d.message->DebugString() << "\nvs\n"
        << expected->DebugString();
    ++checked;
  }
  EXPECT_GE(checked, 6);
}

TEST(Wire, BadMessagesComeBackWithTheirReason) {
  v1::KeypointFrame frame;
  frame.set_camera_id("cam0");
  auto* p = frame.add_persons();
  p->add_x(1), p->add_y(2), p->add_confidence(NAN);
  EXPECT_EQ(DecodeMessage("mocap.v1.KeypointFrame", frame.SerializeAsString()).reason,
            DropReason::kNotFinite);
  p->set_confidence(0, 1.0);
  EXPECT_TRUE(DecodeMessage("mocap.v1.KeypointFrame", frame.SerializeAsString()).message);
  p->add_x(3);
  EXPECT_EQ(DecodeMessage("mocap.v1.KeypointFrame", frame.SerializeAsString()).reason,
            DropReason::kInvalid);
  EXPECT_EQ(DecodeMessage("mocap.v2.KeypointFrame", "").reason, DropReason::kWrongVersion);
  EXPECT_EQ(DecodeMessage("something.Else", "").reason, DropReason::kUnknownType);
  EXPECT_EQ(DecodeMessage("mocap.v1.KeypointFrame", std::string(kMaxPayload + 1, 'x')).reason,
            DropReason::kOversized);
  EXPECT_EQ(DecodeMessage("mocap.v1.KeypointFrame", "\xff\xff\xff").reason,
            DropReason::kUndecodable);
  v1::ImuBatch batch;
  batch.set_hub_id("hub0");
  auto* s = batch.add_samples();
  s->set_sensor_id("pelvis");
  s->set_ax(INFINITY);
  EXPECT_EQ(DecodeMessage("mocap.v1.ImuBatch", batch.SerializeAsString()).reason,
            DropReason::kNotFinite);
  s->set_ax(0);
  s->clear_sensor_id();
  EXPECT_EQ(DecodeMessage("mocap.v1.ImuBatch", batch.SerializeAsString()).reason,
            DropReason::kInvalid);
}

// The caps of wire.h: a message over one of them is dropped as invalid, one at it is taken.
TEST(Wire, MessagesOverTheCapsAreInvalid) {
  v1::KeypointFrame frame;
  frame.set_camera_id("cam0");
  for (int i = 0; i < kMaxPersons; ++i) frame.add_persons();
  EXPECT_TRUE(DecodeMessage("mocap.v1.KeypointFrame", frame.SerializeAsString()).message);
  frame.add_persons();
  EXPECT_EQ(DecodeMessage("mocap.v1.KeypointFrame", frame.SerializeAsString()).reason,
            DropReason::kInvalid);
  frame.clear_persons();
  auto* p = frame.add_persons();
  for (int k = 0; k <= kMaxKeypoints; ++k) p->add_x(1), p->add_y(1), p->add_confidence(1);
  EXPECT_EQ(DecodeMessage("mocap.v1.KeypointFrame", frame.SerializeAsString()).reason,
            DropReason::kInvalid);
  v1::ImuBatch batch;
  for (int i = 0; i <= kMaxSamples; ++i) batch.add_samples()->set_sensor_id("s");
  EXPECT_EQ(DecodeMessage("mocap.v1.ImuBatch", batch.SerializeAsString()).reason,
            DropReason::kInvalid);
  batch.mutable_samples()->RemoveLast();
  EXPECT_TRUE(DecodeMessage("mocap.v1.ImuBatch", batch.SerializeAsString()).message);
  v1::Health health;
  for (int i = 0; i <= kMaxStreams; ++i) health.add_streams();
  EXPECT_EQ(DecodeMessage("mocap.v1.Health", health.SerializeAsString()).reason,
            DropReason::kInvalid);
}

// protobuf logs a line per string field that is not UTF-8; the message is dropped (and
// counted) anyway, so a sender of such messages must not fill the host's log.
TEST(Wire, StringsThatAreNotUtf8AreDroppedWithoutFloodingTheLog) {
  v1::KeypointFrame frame;
  frame.set_camera_id("camX");
  std::string payload = frame.SerializeAsString();
  payload[payload.find('X')] = '\xff';
  const uint64_t held_before = ProtobufLogLinesHeldBack();
  testing::internal::CaptureStderr();
  for (int i = 0; i < 100; ++i)
    EXPECT_EQ(DecodeMessage("mocap.v1.KeypointFrame", payload).reason, DropReason::kUndecodable);
  const std::string log = testing::internal::GetCapturedStderr();
  int lines = 0;
  for (size_t at = log.find("UTF-8"); at != std::string::npos; at = log.find("UTF-8", at + 1))
    ++lines;
  EXPECT_LE(lines, 1) << log;
  EXPECT_GE(ProtobufLogLinesHeldBack() - held_before, 99u);
}

}  // namespace
}  // namespace mocap::wire

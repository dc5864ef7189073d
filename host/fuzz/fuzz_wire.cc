// libFuzzer target: what mocapd does with the messages it receives, from the wire check
// (wire.cc) through the input decoder, subject choice and synchroniser (input_decoder.cc,
// input_path.cc) to the edge Health and Calibration intake (pipeline.cc), for a sequence of
// messages of every type. Input: records [type selector][u16 length][payload][u8 ms to the
// next]; selector % 8 picks KeypointFrame, ImuBatch, PoseFrame, Health, Calibration, another
// version's type, an unknown type, or a type frame read from the input.
// Checks: nothing crashes or leaks, every message is taken or counted as dropped, and what
// is dropped as not decodable is not taken.
#include <cstdlib>

#include "fuzz_support.h"
#include "pipeline.h"
#include "wire.h"

namespace {

constexpr std::string_view kTypes[] = {
    "mocap.v1.KeypointFrame", "mocap.v1.ImuBatch",      "mocap.v1.PoseFrame", "mocap.v1.Health",
    "mocap.v1.Calibration",   "mocap.v2.KeypointFrame", "other.Thing"};

uint64_t Dropped(const mocap::HostPipeline& p) {
  uint64_t n = 0;
  for (const auto& [reason, count] : p.dropped()) n += count;
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string error;
  auto pipeline = mocap::HostPipeline::Create(mocap::fuzz::FixtureSession(), &error);
  if (!pipeline) std::abort();
  mocap::fuzz::Reader in(data, size);
  int64_t now_ns = 1'763'900'000'000'000'000;
  while (!in.empty()) {
    const uint8_t selector = in.Byte() % 8;
    const std::string_view type = selector < 7 ? kTypes[selector] : in.Take(in.Byte() % 48);
    const std::string_view payload = in.Piece();
    const uint64_t before = Dropped(*pipeline);
    const bool taken = pipeline->Feed(type, payload, now_ns);
    // A dropped message is counted (a batch may count several drops).
    if (!taken && Dropped(*pipeline) <= before) std::abort();
    const mocap::wire::Decoded d = mocap::wire::DecodeMessage(type, payload);
    if ((d.message == nullptr) == (d.reason == mocap::wire::DropReason::kNone)) std::abort();
    if (!d.message && taken) std::abort();
    now_ns += 1'000'000LL * in.Byte();
  }
  pipeline->Health(now_ns);
  return 0;
}

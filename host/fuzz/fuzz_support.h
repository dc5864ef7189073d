// What the host's libFuzzer targets share: the fixture session they decode against
// (host/fuzz/data/session.json: the shipped skeleton, IMU set, coco17 layout and prior, a
// two-camera rig) and a reader of the targets' record format.
#ifndef MOCAP_HOST_FUZZ_FUZZ_SUPPORT_H_
#define MOCAP_HOST_FUZZ_FUZZ_SUPPORT_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "session.h"

namespace mocap::fuzz {

// The fixture session, loaded once; aborts when it does not load (a broken fixture).
const Session& FixtureSession();
// The fixture's directory (MOCAP_FUZZ_DATA_DIR).
std::string FixtureDir();

// Reads the fuzz input front to back: bytes, little-endian integers and length-prefixed
// pieces; past the end everything reads as zero or empty.
class Reader {
 public:
  Reader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool empty() const { return pos_ >= size_; }
  uint8_t Byte() { return pos_ < size_ ? data_[pos_++] : 0; }
  uint16_t U16() { return static_cast<uint16_t>(Byte() | (Byte() << 8)); }
  // The next `n` bytes, fewer at the end of the input.
  std::string_view Take(size_t n);
  // A piece prefixed by its 16-bit length.
  std::string_view Piece() { return Take(U16()); }
  std::string_view Rest() { return Take(size_ - pos_); }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
};

}  // namespace mocap::fuzz

#endif  // MOCAP_HOST_FUZZ_FUZZ_SUPPORT_H_

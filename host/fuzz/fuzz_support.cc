#include "fuzz_support.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace mocap::fuzz {

std::string FixtureDir() { return MOCAP_FUZZ_DATA_DIR; }

const Session& FixtureSession() {
  static const Session* session = [] {
    auto* s = new Session;
    std::string error;
    if (!LoadSession(FixtureDir() + "/session.json", s, &error)) {
      std::fprintf(stderr, "fuzz fixture: %s\n", error.c_str());
      std::abort();
    }
    return s;
  }();
  return *session;
}

std::string_view Reader::Take(size_t n) {
  const size_t k = std::min(n, size_ - std::min(pos_, size_));
  const std::string_view out(reinterpret_cast<const char*>(data_) + pos_, k);
  pos_ += k;
  return out;
}

}  // namespace mocap::fuzz

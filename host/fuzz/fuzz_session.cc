// libFuzzer target: the session file reader (session.cc) and the files a session names
// (skeleton, rig, keypoint layout, IMU set, prior). Input: [selector][text]; selector % 6
// picks which of the fixture's files the text replaces (0: session.json itself), the
// others stay valid. Checks: LoadSession returns true or false with an error, never
// throws or crashes, and a session it loads is consistent.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "fuzz_support.h"

namespace {

namespace fs = std::filesystem;
constexpr const char* kFiles[] = {"session.json", "skeleton.json", "rig.json",
                                  "layout.json",  "imus.json",     "prior.json"};

std::string Read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void Write(const fs::path& path, std::string_view text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(text.data(), text.size());
}

// A private copy of the fixture (one per process: libFuzzer's -jobs run several), removed
// when the process exits.
struct RemovedAtExit {
  fs::path path;
  ~RemovedAtExit() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
};

const fs::path& WorkDir() {
  static const RemovedAtExit dir{[] {
    const fs::path base = fs::exists("/dev/shm") ? "/dev/shm" : fs::temp_directory_path();
    const fs::path d = base / ("mocap_fuzz_session_" + std::to_string(getpid()));
    fs::create_directories(d);
    for (const char* f : kFiles) Write(d / f, Read(fs::path(mocap::fuzz::FixtureDir()) / f));
    return d;
  }()};
  return dir.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  mocap::fuzz::Reader in(data, size);
  const char* file = kFiles[in.Byte() % 6];
  const fs::path& dir = WorkDir();
  const std::string original = Read(dir / file);
  Write(dir / file, in.Rest());
  mocap::Session session;
  std::string error;
  const bool ok = mocap::LoadSession((dir / "session.json").string(), &session, &error);
  Write(dir / file, original);
  if (!ok && error.empty()) std::abort();
  if (ok && (session.inputs.empty() || session.layout.size() <= 0)) std::abort();
  return 0;
}

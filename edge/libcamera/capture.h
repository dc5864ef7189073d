// A camera opened through libcamera's C++ API: the camera box's capture where picamera2 (a
// Raspberry Pi OS package) is absent. One stream, a packed 24-bit RGB format, a fixed frame
// duration; each frame copied out of libcamera's buffer (which goes back to the camera at
// once) with what the box needs to time it: the sensor timestamp, the exposure time and the
// frame's sequence number, whose gaps count the frames the camera dropped.
//
// libcamera's API changed between Debian 12's 0.0.3 and the releases Yocto and Raspberry Pi
// OS ship (0.3 and later): FrameBuffer::planes() became a Span (no at()), generateConfiguration
// takes a Span of roles (a std::vector converts), StreamRole became an enum class (qualified
// names serve both). The code is written in the subset both accept, so no <libcamera/version.h>
// branch is needed; LibcameraVersion() reports the version built against. Built and tested
// against 0.0.3; compiled against 0.7.2's headers (docs/devices.md, "The libcamera adapter").
#ifndef MOCAP_EDGE_LIBCAMERA_CAPTURE_H_
#define MOCAP_EDGE_LIBCAMERA_CAPTURE_H_

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace libcamera {
class Camera;
class CameraManager;
class FrameBufferAllocator;
class Request;
class Stream;
}  // namespace libcamera

namespace mocap::edge {

// Every failure of the device: the message names the camera and what to check.
class CaptureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CaptureConfig {
  std::string camera;  // an index ("0") or a libcamera id
  unsigned width = 1280, height = 720;
  double fps = 60.0;
  unsigned buffer_count = 4;
};

struct CapturedFrame {
  std::vector<uint8_t> rgb;  // height x width x 3, R, G, B
  unsigned width = 0, height = 0;
  uint32_t sequence = 0;                       // the camera's frame counter
  std::optional<int64_t> sensor_timestamp_ns;  // CLOCK_BOOTTIME per libcamera (see pi_camera.py)
  std::optional<int32_t> exposure_us;
};

// The ids of the cameras libcamera finds on this machine, in its order (the index order).
std::vector<std::string> ListCameras();

// libcamera's version as the headers this was built against give it ("0.0.3").
std::string LibcameraVersion();

class Capture {
 public:
  explicit Capture(const CaptureConfig& config);  // throws CaptureError
  ~Capture();
  Capture(const Capture&) = delete;
  Capture& operator=(const Capture&) = delete;

  // The next completed frame, waiting up to timeout_s; nullopt on timeout. A request that
  // completed without a frame (cancelled, a frame error) is counted in failed() and skipped.
  std::optional<CapturedFrame> Next(double timeout_s);
  void Close();

  const std::string& id() const { return id_; }
  unsigned width() const { return width_; }
  unsigned height() const { return height_; }
  const std::string& pixel_format() const { return pixel_format_; }
  uint64_t dropped() const { return dropped_; }  // sequence-number gaps
  uint64_t failed() const { return failed_; }    // requests completed without a frame

 private:
  void Configure(const CaptureConfig& config);
  void MapBuffers();
  void Start(double fps);
  void OnRequestCompleted(libcamera::Request* request);
  CapturedFrame CopyOut(libcamera::Request* request);

  std::shared_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  libcamera::Stream* stream_ = nullptr;
  std::vector<std::unique_ptr<libcamera::Request>> requests_;
  struct Mapping {
    uint8_t* base;
    size_t length, offset;  // of the whole mapping; the plane's start in it
  };
  std::map<const void*, Mapping> mapped_;  // by buffer
  std::string id_, pixel_format_;
  unsigned width_ = 0, height_ = 0, stride_ = 0;
  bool bgr_in_memory_ = false, acquired_ = false, started_ = false;
  std::mutex mutex_;
  std::condition_variable completed_cv_;
  std::deque<libcamera::Request*> completed_;
  std::optional<uint32_t> last_sequence_;
  uint64_t dropped_ = 0, failed_ = 0;
};

}  // namespace mocap::edge

#endif  // MOCAP_EDGE_LIBCAMERA_CAPTURE_H_

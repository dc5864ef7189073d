#include "capture.h"

#include <fcntl.h>
#include <libcamera/libcamera.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <utility>

namespace mocap::edge {
namespace {

using libcamera::CameraConfiguration;

// libcamera allows one CameraManager per process: every Capture and ListCameras share it,
// started on first use and stopped with the last user.
std::shared_ptr<libcamera::CameraManager> SharedManager() {
  static std::mutex mutex;
  static std::weak_ptr<libcamera::CameraManager> current;
  std::lock_guard<std::mutex> lock(mutex);
  if (auto manager = current.lock()) return manager;
  auto manager = std::shared_ptr<libcamera::CameraManager>(new libcamera::CameraManager(),
                                                           [](libcamera::CameraManager* m) {
                                                             m->stop();
                                                             delete m;
                                                           });
  if (const int error = manager->start(); error != 0)
    throw CaptureError("libcamera: the camera manager did not start (" +
                       std::string(std::strerror(-error)) + ")");
  current = manager;
  return manager;
}

std::string Names(const std::vector<std::string>& ids) {
  std::string out;
  for (const std::string& id : ids) out += (out.empty() ? "" : ", ") + id;
  return out.empty() ? "none" : out;
}

// The media devices another process holds: libcamera locks a camera's media device while a
// process uses it (lockf), and another process then does not list that camera at all.
std::string BusyMediaDevices() {
  std::string busy;
  for (int n = 0; n < 64; ++n) {
    const std::string path = "/dev/media" + std::to_string(n);
    const int fd = open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    if (lockf(fd, F_TEST, 0) != 0) busy += (busy.empty() ? "" : ", ") + path;
    close(fd);
  }
  return busy;
}

// The camera `wanted` names: an index into ListCameras' order, or an id.
std::shared_ptr<libcamera::Camera> Find(libcamera::CameraManager& manager,
                                        const std::string& wanted) {
  const auto cameras = manager.cameras();
  std::vector<std::string> ids;
  for (const auto& camera : cameras) ids.push_back(camera->id());
  const bool index = !wanted.empty() && std::all_of(wanted.begin(), wanted.end(), ::isdigit);
  if (index && wanted.size() < 4 && std::stoul(wanted) < cameras.size())
    return cameras[std::stoul(wanted)];
  if (!index)
    for (const auto& camera : cameras)
      if (camera->id() == wanted) return camera;
  const std::string busy = BusyMediaDevices();
  throw CaptureError("libcamera: no camera " + wanted + " (found " +
                     std::to_string(cameras.size()) + ": " + Names(ids) + ")" +
                     (busy.empty() ? "" : "; " + busy + " in use by another process") +
                     "; `cam -l` lists them, and a camera appears only once udev has run");
}

std::string Describe(const CaptureConfig& config) {
  char text[128];
  std::snprintf(text, sizeof text, "size %ux%u, %g fps, %u buffers", config.width, config.height,
                config.fps, config.buffer_count);
  return text;
}

}  // namespace

std::vector<std::string> ListCameras() {
  auto manager = SharedManager();
  std::vector<std::string> ids;
  for (const auto& camera : manager->cameras()) ids.push_back(camera->id());
  return ids;
}

std::string LibcameraVersion() {
  return std::to_string(LIBCAMERA_VERSION_MAJOR) + "." + std::to_string(LIBCAMERA_VERSION_MINOR) +
         "." + std::to_string(LIBCAMERA_VERSION_PATCH);
}

Capture::Capture(const CaptureConfig& config) {
  if (config.width == 0 || config.height == 0 || config.width > 8192 || config.height > 8192 ||
      !(config.fps > 0 && config.fps <= 1000) || config.buffer_count < 2 ||
      config.buffer_count > 32)
    throw CaptureError("libcamera:" + config.camera + ": " + Describe(config) +
                       ": out of range (1-8192 px, 0-1000 fps, 2-32 buffers)");
  manager_ = SharedManager();
  camera_ = Find(*manager_, config.camera);
  id_ = camera_->id();
  if (camera_->acquire() != 0)
    throw CaptureError("libcamera: camera " + id_ + " is in use by another process");
  acquired_ = true;
  try {
    Configure(config);
    MapBuffers();
    Start(config.fps);
  } catch (...) {
    Close();
    throw;
  }
}

Capture::~Capture() { Close(); }

void Capture::Configure(const CaptureConfig& config) {
  const std::vector<libcamera::StreamRole> roles{libcamera::StreamRole::VideoRecording};
  std::unique_ptr<CameraConfiguration> configuration = camera_->generateConfiguration(roles);
  if (!configuration || configuration->empty())
    throw CaptureError("libcamera: camera " + id_ + " offers no video stream");
  libcamera::StreamConfiguration& stream = configuration->at(0);
  stream.size = libcamera::Size(config.width, config.height);
  stream.pixelFormat = libcamera::formats::BGR888;  // R, G, B in memory (DRM fourcc order)
  stream.bufferCount = config.buffer_count;
  if (configuration->validate() == CameraConfiguration::Invalid)
    throw CaptureError("libcamera: camera " + id_ + " refuses " + stream.toString());
  // The camera may adjust the request: another size is taken (the box reports it), a format
  // other than packed 24-bit RGB cannot be converted here.
  if (stream.pixelFormat != libcamera::formats::BGR888 &&
      stream.pixelFormat != libcamera::formats::RGB888)
    throw CaptureError("libcamera: camera " + id_ + " gives " + stream.pixelFormat.toString() +
                       ", not 24-bit RGB (BGR888 or RGB888)");
  if (camera_->configure(configuration.get()) != 0)
    throw CaptureError("libcamera: camera " + id_ + " could not be configured as " +
                       stream.toString());
  stream_ = stream.stream();
  width_ = stream.size.width;
  height_ = stream.size.height;
  stride_ = stream.stride;
  pixel_format_ = stream.pixelFormat.toString();
  bgr_in_memory_ = stream.pixelFormat == libcamera::formats::RGB888;
}

void Capture::MapBuffers() {
  allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
  if (allocator_->allocate(stream_) < 0)
    throw CaptureError("libcamera: camera " + id_ + ": buffers could not be allocated");
  for (const std::unique_ptr<libcamera::FrameBuffer>& buffer : allocator_->buffers(stream_)) {
    if (buffer->planes().empty())
      throw CaptureError("libcamera: camera " + id_ + ": a buffer without a plane");
    // planes() is a std::vector up to 0.0.x and a Span (no at()) since: [] serves both
    const libcamera::FrameBuffer::Plane& plane = buffer->planes()[0];
    const size_t length = plane.offset + plane.length;
    void* memory = mmap(nullptr, length, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
    if (memory == MAP_FAILED)
      throw CaptureError("libcamera: camera " + id_ + ": a buffer could not be mapped (" +
                         std::strerror(errno) + ")");
    mapped_[buffer.get()] = {static_cast<uint8_t*>(memory), length, plane.offset};
    std::unique_ptr<libcamera::Request> request = camera_->createRequest();
    if (!request || request->addBuffer(stream_, buffer.get()) != 0)
      throw CaptureError("libcamera: camera " + id_ + ": a request could not be made");
    requests_.push_back(std::move(request));
  }
}

void Capture::Start(double fps) {
  camera_->requestCompleted.connect(this, &Capture::OnRequestCompleted);
  libcamera::ControlList controls(camera_->controls());
  const int64_t frame_us = static_cast<int64_t>(1e6 / fps + 0.5);
  if (camera_->controls().count(&libcamera::controls::FrameDurationLimits))
    controls.set(libcamera::controls::FrameDurationLimits,
                 libcamera::Span<const int64_t, 2>({frame_us, frame_us}));
  if (camera_->start(&controls) != 0)
    throw CaptureError("libcamera: camera " + id_ + " did not start");
  started_ = true;
  for (const std::unique_ptr<libcamera::Request>& request : requests_)
    if (camera_->queueRequest(request.get()) != 0)
      throw CaptureError("libcamera: camera " + id_ + ": a request was refused");
}

void Capture::OnRequestCompleted(libcamera::Request* request) {  // libcamera's thread
  {
    std::lock_guard<std::mutex> lock(mutex_);
    completed_.push_back(request);
  }
  completed_cv_.notify_one();
}

std::optional<CapturedFrame> Capture::Next(double timeout_s) {
  if (!started_) throw CaptureError("libcamera: camera " + id_ + " is closed");
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::microseconds(static_cast<int64_t>(timeout_s * 1e6));
  for (;;) {
    libcamera::Request* request = nullptr;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!completed_cv_.wait_until(lock, deadline, [&] { return !completed_.empty(); }))
        return std::nullopt;
      request = completed_.front();
      completed_.pop_front();
    }
    std::optional<CapturedFrame> frame;
    if (request->status() == libcamera::Request::RequestComplete)
      frame = CopyOut(request);
    else
      failed_++;
    request->reuse(libcamera::Request::ReuseBuffers);  // back to the camera at once
    if (camera_->queueRequest(request) != 0) failed_++;
    if (frame) return frame;
  }
}

CapturedFrame Capture::CopyOut(libcamera::Request* request) {
  libcamera::FrameBuffer* buffer = request->buffers().begin()->second;
  const libcamera::FrameMetadata& metadata = buffer->metadata();
  CapturedFrame frame;
  frame.width = width_;
  frame.height = height_;
  frame.sequence = metadata.sequence;
  if (last_sequence_ && metadata.sequence > *last_sequence_ + 1)
    dropped_ += metadata.sequence - *last_sequence_ - 1;
  last_sequence_ = metadata.sequence;
  frame.sensor_timestamp_ns = request->metadata().get(libcamera::controls::SensorTimestamp);
  frame.exposure_us = request->metadata().get(libcamera::controls::ExposureTime);
  const Mapping& mapping = mapped_.at(buffer);
  const uint8_t* source = mapping.base + mapping.offset;
  frame.rgb.resize(static_cast<size_t>(width_) * height_ * 3);
  for (unsigned y = 0; y < height_; ++y) {
    const uint8_t* row = source + static_cast<size_t>(y) * stride_;
    uint8_t* out = frame.rgb.data() + static_cast<size_t>(y) * width_ * 3;
    if (!bgr_in_memory_) {
      std::memcpy(out, row, static_cast<size_t>(width_) * 3);
      continue;
    }
    for (unsigned x = 0; x < width_; ++x) {
      out[3 * x] = row[3 * x + 2];
      out[3 * x + 1] = row[3 * x + 1];
      out[3 * x + 2] = row[3 * x];
    }
  }
  return frame;
}

void Capture::Close() {
  if (started_) {
    camera_->stop();  // completes every queued request (cancelled)
    started_ = false;
    camera_->requestCompleted.disconnect(this, &Capture::OnRequestCompleted);
  }
  completed_.clear();
  requests_.clear();
  for (auto& [buffer, mapping] : mapped_) munmap(mapping.base, mapping.length);
  mapped_.clear();
  if (allocator_ && stream_) allocator_->free(stream_);
  allocator_.reset();
  if (acquired_) camera_->release();
  acquired_ = false;
  camera_.reset();
}

}  // namespace mocap::edge

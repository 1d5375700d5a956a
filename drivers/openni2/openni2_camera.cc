#include "drivers/openni2/openni2_camera.h"

#include <OpenNI.h>

#include <cmath>
#include <cstring>
#include <mutex>
#include <vector>

namespace selfcal::openni2 {
namespace {

std::string LastError() { return openni::OpenNI::getExtendedError(); }

Status Initialize() {
  static std::once_flag once;
  static openni::Status status = openni::STATUS_OK;
  std::call_once(once, [] { status = openni::OpenNI::initialize(); });
  if (status != openni::STATUS_OK) return Error{"OpenNI2 initialize failed: " + LastError()};
  return OkStatus();
}

double UnitOf(openni::PixelFormat format) {
  return format == openni::PIXEL_FORMAT_DEPTH_100_UM ? 0.0001 : 0.001;
}

}  // namespace

struct OpenNi2Camera::Impl {
  openni::Device device;
  openni::VideoStream stream;
  openni::Recorder recorder;
  openni::VideoFrameRef frame;
  double depth_unit_m = 0.001;
};

OpenNi2Camera::OpenNi2Camera() : impl_(std::make_unique<Impl>()) {}

OpenNi2Camera::~OpenNi2Camera() {
  if (impl_->recorder.isValid()) {
    impl_->recorder.stop();
    impl_->recorder.destroy();
  }
  impl_->frame.release();
  impl_->stream.stop();
  impl_->stream.destroy();
  impl_->device.close();
}

Expected<std::unique_ptr<OpenNi2Camera>> OpenNi2Camera::Open(const CameraOptions& options) {
  if (auto status = Initialize(); !status) return status.error();
  std::unique_ptr<OpenNi2Camera> self(new OpenNi2Camera());
  self->options_ = options;
  Impl& impl = *self->impl_;
  const bool playback = !options.oni_path.empty();
  const std::string what = playback
                               ? "recording '" + options.oni_path + "'"
                               : (options.uri.empty() ? std::string("any OpenNI2 device")
                                                      : "OpenNI2 device '" + options.uri + "'");
  const char* uri = playback ? options.oni_path.c_str()
                             : (options.uri.empty() ? openni::ANY_DEVICE : options.uri.c_str());
  if (impl.device.open(uri) != openni::STATUS_OK)
    return Error{"cannot open " + what + ": " + LastError()};
  if (playback) {
    // Manual speed: every readFrame returns the next recorded frame, none is skipped.
    impl.device.getPlaybackControl()->setSpeed(-1);
    impl.device.getPlaybackControl()->setRepeatEnabled(false);
  }
  if (!impl.device.hasSensor(openni::SENSOR_DEPTH)) return Error{what + " has no depth sensor"};
  if (impl.stream.create(impl.device, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
    return Error{"cannot create the depth stream of " + what + ": " + LastError()};
  }
  if (!playback && (options.width > 0 || options.height > 0 || options.fps > 0)) {
    const auto& modes = impl.stream.getSensorInfo().getSupportedVideoModes();
    bool found = false;
    for (int i = 0; i < modes.getSize() && !found; ++i) {
      const auto& mode = modes[i];
      const bool depth = mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM ||
                         mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM;
      if (depth && (options.width == 0 || mode.getResolutionX() == options.width) &&
          (options.height == 0 || mode.getResolutionY() == options.height) &&
          (options.fps == 0 || mode.getFps() == options.fps)) {
        if (impl.stream.setVideoMode(mode) != openni::STATUS_OK) {
          return Error{"cannot set the depth mode of " + what + ": " + LastError()};
        }
        found = true;
      }
    }
    if (!found) {
      return Error{what + " offers no 16-bit depth mode " + std::to_string(options.width) + "x" +
                   std::to_string(options.height) + " at " + std::to_string(options.fps) + " fps"};
    }
  }
  const openni::VideoMode mode = impl.stream.getVideoMode();
  if (mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_1_MM &&
      mode.getPixelFormat() != openni::PIXEL_FORMAT_DEPTH_100_UM) {
    return Error{what + ": depth stream pixel format " + std::to_string(mode.getPixelFormat()) +
                 " is not 16-bit depth (DEPTH_1_MM or DEPTH_100_UM)"};
  }
  impl.depth_unit_m = UnitOf(mode.getPixelFormat());
  self->width_ = mode.getResolutionX();
  self->height_ = mode.getResolutionY();
  if (options.intrinsics.fx > 0) {
    self->intrinsics_ = options.intrinsics;
  } else {
    const float hfov = impl.stream.getHorizontalFieldOfView();
    const float vfov = impl.stream.getVerticalFieldOfView();
    if (!(hfov > 0.0f && hfov < 3.1f && vfov > 0.0f && vfov < 3.1f)) {
      return Error{what + " reports no usable field of view (" + std::to_string(hfov) + ", " +
                   std::to_string(vfov) + " rad): give the intrinsics in the configuration"};
    }
    self->intrinsics_ = PinholeIntrinsics::FromFieldOfView(self->width_, self->height_, hfov, vfov);
  }
  if (playback)
    self->frames_in_recording_ = impl.device.getPlaybackControl()->getNumberOfFrames(impl.stream);
  if (!options.record_path.empty()) {
    if (impl.recorder.create(options.record_path.c_str()) != openni::STATUS_OK ||
        impl.recorder.attach(impl.stream) != openni::STATUS_OK) {
      return Error{"cannot record to '" + options.record_path + "': " + LastError()};
    }
  }
  if (impl.stream.start() != openni::STATUS_OK) {
    return Error{"cannot start the depth stream of " + what + ": " + LastError()};
  }
  if (impl.recorder.isValid() && impl.recorder.start() != openni::STATUS_OK) {
    return Error{"cannot start recording to '" + options.record_path + "': " + LastError()};
  }
  const openni::DeviceInfo& info = impl.device.getDeviceInfo();
  self->description_ =
      std::string(info.getVendor()) + " " + info.getName() + " (" + info.getUri() + ")";
  return self;
}

Expected<bool> OpenNi2Camera::NextFrame(std::chrono::milliseconds timeout,
                                        std::vector<std::int16_t>& depth, DepthFrame& frame) {
  Impl& impl = *impl_;
  if (playback()) {
    if (frames_read_ >= frames_in_recording_) {
      at_end_ = true;
      return false;
    }
  } else {
    openni::VideoStream* streams[] = {&impl.stream};
    int ready = -1;
    const openni::Status status =
        openni::OpenNI::waitForAnyStream(streams, 1, &ready, static_cast<int>(timeout.count()));
    if (status == openni::STATUS_TIME_OUT) return false;
    if (status != openni::STATUS_OK)
      return Error{"waiting for a depth frame failed: " + LastError()};
  }
  if (impl.stream.readFrame(&impl.frame) != openni::STATUS_OK) {
    return Error{"reading a depth frame failed: " + LastError()};
  }
  ++frames_read_;
  const openni::VideoFrameRef& f = impl.frame;
  const int width = f.getWidth(), height = f.getHeight();
  const int stride = f.getStrideInBytes();
  if (width <= 0 || height <= 0 || stride < width * 2 ||
      f.getDataSize() < stride * (height - 1) + width * 2) {
    return Error{"depth frame " + std::to_string(f.getFrameIndex()) +
                 " has an inconsistent layout: " + std::to_string(width) + "x" +
                 std::to_string(height) + ", stride " + std::to_string(stride) + ", " +
                 std::to_string(f.getDataSize()) + " bytes"};
  }
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (depth.size() != count) depth.resize(count);
  const auto* bytes = static_cast<const std::uint8_t*>(f.getData());
  for (int row = 0; row < height; ++row) {
    std::memcpy(depth.data() + static_cast<std::size_t>(row) * static_cast<std::size_t>(width),
                bytes + static_cast<std::size_t>(row) * static_cast<std::size_t>(stride),
                static_cast<std::size_t>(width) * 2);
  }
  frame.device_timestamp_us = f.getTimestamp();
  frame.frame_index = f.getFrameIndex();
  frame.width = width;
  frame.height = height;
  frame.depth_unit_m = impl.depth_unit_m;
  return true;
}

}  // namespace selfcal::openni2

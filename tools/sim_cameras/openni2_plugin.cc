// An OpenNI2 driver plugin of ours: a simulated depth camera (Kinect-like) serving the analytic
// depth scene through the real libOpenNI2, loaded from a private driver folder in tests
// (test-peers.md). URI: "selfcal-sim://depth?width=320&height=288&fps=30&hfov_deg=75&vfov_deg=65".
// Device timestamps run from the device's own start, as a real camera's do.
#define XN_NEW(type, ...) new type(__VA_ARGS__)
#define XN_DELETE(p) delete (p)
#include <openni2/Driver/OniDriverAPI.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "tools/sim_cameras/depth_scene.h"

namespace {

using selfcal::PinholeIntrinsics;
using selfcal::sim_cameras::AnalyticDepthScene;

constexpr const char* kScheme = "selfcal-sim://";
constexpr double kDegree = 3.14159265358979323846 / 180.0;

struct SimConfig {
  int width = 320, height = 288, fps = 30;
  double hfov_deg = 75.0, vfov_deg = 65.0;
  double noise_sigma_m = 0.0025;
};

double QueryValue(const std::string& uri, const std::string& key, double fallback) {
  const auto at = uri.find(key + "=");
  if (at == std::string::npos) return fallback;
  return std::atof(uri.c_str() + at + key.size() + 1);
}

SimConfig ParseUri(const std::string& uri) {
  SimConfig c;
  c.width = static_cast<int>(QueryValue(uri, "width", c.width));
  c.height = static_cast<int>(QueryValue(uri, "height", c.height));
  c.fps = static_cast<int>(QueryValue(uri, "fps", c.fps));
  c.hfov_deg = QueryValue(uri, "hfov_deg", c.hfov_deg);
  c.vfov_deg = QueryValue(uri, "vfov_deg", c.vfov_deg);
  c.noise_sigma_m = QueryValue(uri, "noise_m", c.noise_sigma_m);
  return c;
}

PinholeIntrinsics FromFov(const SimConfig& c) {
  return PinholeIntrinsics::FromFieldOfView(c.width, c.height, c.hfov_deg * kDegree,
                                            c.vfov_deg * kDegree);
}

AnalyticDepthScene KinectScene() {
  AnalyticDepthScene scene;
  scene.wall_distance_m = 1.6;
  scene.wall_slope = 0.5;
  scene.ball_x_m = 0.1;
  scene.ball_y_m = -0.05;
  scene.ball_z_m = 1.1;
  scene.ball_radius_m = 0.2;
  scene.closest_m = 0.5;
  scene.farthest_m = 2.0;
  return scene;
}

class SimStream : public oni::driver::StreamBase {
 public:
  SimStream(const SimConfig& config, std::chrono::steady_clock::time_point device_start)
      : config_(config), device_start_(device_start) {
    mode_.pixelFormat = ONI_PIXEL_FORMAT_DEPTH_1_MM;
    mode_.resolutionX = config.width;
    mode_.resolutionY = config.height;
    mode_.fps = config.fps;
  }
  ~SimStream() override { stop(); }

  OniStatus start() override {
    running_ = true;
    thread_ = std::thread([this] { Produce(); });
    return ONI_STATUS_OK;
  }
  void stop() override {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }

  OniBool isPropertySupported(int id) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
      case ONI_STREAM_PROPERTY_STRIDE:
      case ONI_STREAM_PROPERTY_CROPPING:
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      case ONI_STREAM_PROPERTY_MAX_VALUE:
      case ONI_STREAM_PROPERTY_MIN_VALUE:
      case ONI_STREAM_PROPERTY_MIRRORING:
        return TRUE;
      default:
        return FALSE;
    }
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    const auto put = [&](const auto& value) {
      if (*size < static_cast<int>(sizeof(value))) return ONI_STATUS_BAD_PARAMETER;
      std::memcpy(data, &value, sizeof(value));
      *size = sizeof(value);
      return ONI_STATUS_OK;
    };
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
        return put(mode_);
      case ONI_STREAM_PROPERTY_STRIDE:
        return put(static_cast<int>(mode_.resolutionX * sizeof(OniDepthPixel)));
      case ONI_STREAM_PROPERTY_CROPPING: {
        OniCropping cropping{};
        cropping.enabled = FALSE;
        return put(cropping);
      }
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
        return put(static_cast<float>(config_.hfov_deg * kDegree));
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
        return put(static_cast<float>(config_.vfov_deg * kDegree));
      case ONI_STREAM_PROPERTY_MAX_VALUE:
        return put(10000);
      case ONI_STREAM_PROPERTY_MIN_VALUE:
        return put(0);
      case ONI_STREAM_PROPERTY_MIRRORING:
        return put(OniBool(FALSE));
      default:
        return ONI_STATUS_NOT_SUPPORTED;
    }
  }

  OniStatus setProperty(int id, const void* data, int size) override {
    if (id == ONI_STREAM_PROPERTY_VIDEO_MODE && size == sizeof(OniVideoMode)) {
      OniVideoMode mode;
      std::memcpy(&mode, data, sizeof(mode));
      // One mode only, as the sensor info says.
      if (mode.pixelFormat != ONI_PIXEL_FORMAT_DEPTH_1_MM || mode.resolutionX != config_.width ||
          mode.resolutionY != config_.height || mode.fps != config_.fps) {
        return ONI_STATUS_NOT_SUPPORTED;
      }
      return ONI_STATUS_OK;
    }
    if (id == ONI_STREAM_PROPERTY_MIRRORING) return ONI_STATUS_OK;
    if (id == ONI_STREAM_PROPERTY_CROPPING && size == sizeof(OniCropping)) {
      OniCropping cropping;
      std::memcpy(&cropping, data, sizeof(cropping));
      return cropping.enabled ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_OK;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

 private:
  void Produce() {
    const PinholeIntrinsics k = FromFov(config_);
    const AnalyticDepthScene scene = KinectScene();
    // Truth once, noise from a table: a frame costs a copy, not a ray cast per pixel.
    std::vector<double> truth(static_cast<std::size_t>(config_.width * config_.height));
    for (int v = 0; v < config_.height; ++v) {
      for (int u = 0; u < config_.width; ++u)
        truth[static_cast<std::size_t>(v * config_.width + u)] = scene.DepthAt(u, v, k);
    }
    std::vector<double> noise(1 << 16);
    for (std::size_t i = 0; i < noise.size(); ++i)
      noise[i] = selfcal::sim_cameras::GaussianNoise(0x0111, i);
    const auto period = std::chrono::microseconds(1'000'000 / config_.fps);
    auto next = std::chrono::steady_clock::now();
    while (running_) {
      std::this_thread::sleep_until(next);
      next += period;
      OniFrame* frame = getServices().acquireFrame();
      if (frame == nullptr) continue;
      auto* depth = static_cast<OniDepthPixel*>(frame->data);
      const std::uint64_t index = ++frame_index_;
      for (int v = 0; v < config_.height; ++v) {
        for (int u = 0; u < config_.width; ++u) {
          const std::size_t i = static_cast<std::size_t>(v * config_.width + u);
          const double z = truth[i];
          const double noisy =
              z > 0 ? z + config_.noise_sigma_m * noise[(index * 7919 + i) & (noise.size() - 1)]
                    : 0;
          depth[i] = static_cast<OniDepthPixel>(z > 0 ? std::lround(noisy * 1000.0) : 0);
        }
      }
      frame->dataSize = config_.width * config_.height * static_cast<int>(sizeof(OniDepthPixel));
      frame->sensorType = ONI_SENSOR_DEPTH;
      frame->timestamp =
          static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::microseconds>(
                                    std::chrono::steady_clock::now() - device_start_)
                                    .count());
      frame->frameIndex = static_cast<int>(index);
      frame->width = config_.width;
      frame->height = config_.height;
      frame->videoMode = mode_;
      frame->croppingEnabled = FALSE;
      frame->cropOriginX = frame->cropOriginY = 0;
      frame->stride = config_.width * static_cast<int>(sizeof(OniDepthPixel));
      raiseNewFrame(frame);
      getServices().releaseFrame(frame);
    }
  }

  SimConfig config_;
  std::chrono::steady_clock::time_point device_start_;
  OniVideoMode mode_{};
  std::atomic<bool> running_{false};
  std::thread thread_;
  std::uint64_t frame_index_ = 0;
};

class SimDevice : public oni::driver::DeviceBase {
 public:
  explicit SimDevice(const SimConfig& config) : config_(config) {
    mode_.pixelFormat = ONI_PIXEL_FORMAT_DEPTH_1_MM;
    mode_.resolutionX = config.width;
    mode_.resolutionY = config.height;
    mode_.fps = config.fps;
    sensor_.sensorType = ONI_SENSOR_DEPTH;
    sensor_.numSupportedVideoModes = 1;
    sensor_.pSupportedVideoModes = &mode_;
  }
  OniStatus getSensorInfoList(OniSensorInfo** infos, int* count) override {
    *infos = &sensor_;
    *count = 1;
    return ONI_STATUS_OK;
  }
  oni::driver::StreamBase* createStream(OniSensorType type) override {
    if (type != ONI_SENSOR_DEPTH) return nullptr;
    return new SimStream(config_, start_);
  }
  void destroyStream(oni::driver::StreamBase* stream) override { delete stream; }

 private:
  SimConfig config_;
  OniVideoMode mode_{};
  OniSensorInfo sensor_{};
  std::chrono::steady_clock::time_point start_ =
      std::chrono::steady_clock::now() - std::chrono::seconds(3600);
};

class SimDriver : public oni::driver::DriverBase {
 public:
  explicit SimDriver(OniDriverServices* services) : DriverBase(services) {}
  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback changed, void* cookie) override {
    DriverBase::initialize(connected, disconnected, changed, cookie);
    Announce("selfcal-sim://depth");
    return ONI_STATUS_OK;
  }
  OniStatus tryDevice(const char* uri) override {
    if (std::strncmp(uri, kScheme, std::strlen(kScheme)) != 0) return ONI_STATUS_ERROR;
    Announce(uri);
    return ONI_STATUS_OK;
  }
  oni::driver::DeviceBase* deviceOpen(const char* uri, const char*) override {
    if (std::strncmp(uri, kScheme, std::strlen(kScheme)) != 0) return nullptr;
    return new SimDevice(ParseUri(uri));
  }
  void deviceClose(oni::driver::DeviceBase* device) override { delete device; }
  void shutdown() override {}

 private:
  void Announce(const char* uri) {
    OniDeviceInfo info{};
    std::strncpy(info.uri, uri, sizeof(info.uri) - 1);
    std::strncpy(info.vendor, "selfcal", sizeof(info.vendor) - 1);
    std::strncpy(info.name, "simulated depth camera", sizeof(info.name) - 1);
    deviceConnected(&info);
  }
};

}  // namespace

ONI_EXPORT_DRIVER(SimDriver);

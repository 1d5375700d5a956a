// An OpenNI2 driver plugin of ours: a simulated depth camera (Kinect-like) serving the analytic
// depth scene through the real libOpenNI2, loaded from a private driver folder in tests
// (test-peers.md). URI: "selfcal-sim://depth?width=320&height=288&fps=30&hfov_deg=75&vfov_deg=65".
// With "scenario=PATH&view=N" it serves a simulation scenario instead (scenario_camera.h): the
// camera on the true arm at the start of scan N, with the resolution and field of view of the
// scenario's sensor file, and the scenario's field effects if it has any (then the noise is the
// sensor file's, not noise_m). Device timestamps run from the device's own start, as a real
// camera's do; the warm-up drift of a range bias runs on that clock.
#define XN_NEW(type, ...) new type(__VA_ARGS__)
#define XN_DELETE(p) delete (p)
#include <openni2/Driver/OniDriverAPI.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "tools/sim_cameras/depth_scene.h"
#include "tools/sim_cameras/scenario_camera.h"

namespace {

using selfcal::PinholeIntrinsics;
using selfcal::sim_cameras::AnalyticDepthScene;
using selfcal::sim_cameras::ScenarioCamera;

constexpr const char* kScheme = "selfcal-sim://";
constexpr double kDegree = 3.14159265358979323846 / 180.0;

struct SimConfig {
  int width = 320, height = 288, fps = 30;
  double hfov_deg = 75.0, vfov_deg = 65.0;
  double noise_sigma_m = 0.0025;
  std::string scenario;  // empty: the analytic scene
  int view = 0;
};

double QueryValue(const std::string& uri, const std::string& key, double fallback) {
  const auto at = uri.find(key + "=");
  if (at == std::string::npos) return fallback;
  return std::atof(uri.c_str() + at + key.size() + 1);
}

std::string QueryText(const std::string& uri, const std::string& key) {
  const auto at = uri.find(key + "=");
  if (at == std::string::npos) return {};
  const auto begin = at + key.size() + 1;
  return uri.substr(begin, uri.find('&', begin) - begin);
}

SimConfig ParseUri(const std::string& uri) {
  SimConfig c;
  c.scenario = QueryText(uri, "scenario");
  c.view = static_cast<int>(QueryValue(uri, "view", c.view));
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
  SimStream(const SimConfig& config, std::chrono::steady_clock::time_point device_start,
            std::shared_ptr<ScenarioCamera> scenario)
      : config_(config), device_start_(device_start), scenario_(std::move(scenario)) {
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
  // Depth z [m] per pixel without noise, once: the scene (or the scenario's, cast once).
  std::vector<double> Truth(const PinholeIntrinsics& k) const {
    std::vector<double> truth(static_cast<std::size_t>(config_.width * config_.height));
    if (scenario_) {
      const std::vector<float> depth = scenario_->IdealDepth(
          static_cast<std::uint32_t>(config_.width), static_cast<std::uint32_t>(config_.height), k);
      std::copy(depth.begin(), depth.end(), truth.begin());
      return truth;
    }
    const AnalyticDepthScene scene = KinectScene();
    for (int v = 0; v < config_.height; ++v) {
      for (int u = 0; u < config_.width; ++u)
        truth[static_cast<std::size_t>(v * config_.width + u)] = scene.DepthAt(u, v, k);
    }
    return truth;
  }

  // A scenario with field effects: the frame of core/sim/device_frame.h at the device time.
  void FieldFrame(const PinholeIntrinsics& k, std::uint64_t index, double device_time,
                  OniDepthPixel* depth) {
    scenario_->FieldDepth(index, device_time, static_cast<std::uint32_t>(config_.width),
                          static_cast<std::uint32_t>(config_.height), k, field_depth_);
    for (std::size_t i = 0; i < field_depth_.size(); ++i) {
      depth[i] = static_cast<OniDepthPixel>(std::lround(field_depth_[i] * 1000.0));
    }
  }

  void Produce() {
    const PinholeIntrinsics k = FromFov(config_);
    const bool field = scenario_ && scenario_->field();
    // Truth once, noise from a table: a frame costs a copy, not a ray cast per pixel.
    const std::vector<double> truth = field ? std::vector<double>() : Truth(k);
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
      const auto device_time = std::chrono::steady_clock::now() - device_start_;
      if (field) {
        FieldFrame(k, index, std::chrono::duration<double>(device_time).count(), depth);
      }
      for (int v = 0; v < config_.height && !field; ++v) {
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
      frame->timestamp = static_cast<uint64_t>(
          std::chrono::duration_cast<std::chrono::microseconds>(device_time).count());
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
  std::shared_ptr<ScenarioCamera> scenario_;  // null: the analytic scene
  std::vector<float> field_depth_;
};

class SimDevice : public oni::driver::DeviceBase {
 public:
  SimDevice(const SimConfig& config, std::shared_ptr<ScenarioCamera> scenario)
      : config_(config), scenario_(std::move(scenario)) {
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
    return new SimStream(config_, start_, scenario_);
  }
  void destroyStream(oni::driver::StreamBase* stream) override { delete stream; }

 private:
  SimConfig config_;
  OniVideoMode mode_{};
  OniSensorInfo sensor_{};
  std::shared_ptr<ScenarioCamera> scenario_;
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
    SimConfig config = ParseUri(uri);
    if (config.scenario.empty()) return new SimDevice(config, nullptr);
    auto camera = ScenarioCamera::Create(config.scenario, config.view);
    if (!camera) {
      std::fprintf(stderr, "selfcal-sim-openni2: %s\n", camera.error().message.c_str());
      return nullptr;
    }
    // The scenario's sensor file sets the resolution and the field of view.
    const auto& sensor = (*camera)->sensor();
    config.width = sensor.width;
    config.height = sensor.height;
    config.hfov_deg = 2 * std::atan(sensor.width / 2.0 / sensor.intrinsics.fx) / kDegree;
    config.vfov_deg = 2 * std::atan(sensor.height / 2.0 / sensor.intrinsics.fy) / kDegree;
    return new SimDevice(config, std::move(*camera));
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

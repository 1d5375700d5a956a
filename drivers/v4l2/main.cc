// selfcal-v4l2: UVC depth cameras with Z16 frames (RealSense and the like, Kinect v1 through
// gspca) over V4L2 mmap streaming; publishes selfcal.depth_image_t. See docs/cameras.md.
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>

#include "drivers/v4l2/v4l2_driver.h"
#include "protocols/model_file/sensor_config.h"

namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  using namespace selfcal::v4l2;
  DriverOptions options;
  std::string lcm_url;
  std::string sensor_config;
  std::string trigger = "none";
  CLI::App app{"selfcal-v4l2: UVC Z16 depth camera (V4L2) -> selfcal.depth_image_t"};
  app.add_option("--device", options.camera.device, "V4L2 device")->capture_default_str();
  app.add_option("--width", options.camera.width, "width [px] (0: device's)");
  app.add_option("--height", options.camera.height, "height [px] (0: device's)");
  app.add_option("--fps", options.camera.fps, "frame rate (0: device's)");
  app.add_option("--buffers", options.camera.buffers, "mmap buffers")
      ->capture_default_str()
      ->check(CLI::Range(2, 32));
  auto* config = app.add_option("--sensor-config", sensor_config,
                                "sensor file with the intrinsics (config/sensors/*.yaml)")
                     ->check(CLI::ExistingFile);
  auto* fx = app.add_option("--fx", options.intrinsics.fx, "focal length x [px]");
  app.add_option("--fy", options.intrinsics.fy, "focal length y [px]");
  app.add_option("--cx", options.intrinsics.cx, "principal point x [px]");
  app.add_option("--cy", options.intrinsics.cy, "principal point y [px]");
  fx->excludes(config);
  app.add_option("--depth-unit", options.depth_unit_m, "metres per Z16 count")
      ->capture_default_str();
  app.add_option("--lcm-url", lcm_url, "LCM URL (empty: LCM_DEFAULT_URL or udpm default)");
  app.add_option("--channel", options.channel, "channel of the depth images")
      ->capture_default_str();
  app.add_option("--trigger", trigger,
                 "none (every frame) or request (one frame per scan_marker_t BEGIN)")
      ->check(CLI::IsMember({"none", "request"}))
      ->capture_default_str();
  app.add_option("--trigger-channel", options.trigger_channel,
                 "scan_marker_t channel of the requests")
      ->capture_default_str();
  app.add_option("--max-frames", options.max_frames,
                 "exit after publishing this many frames (0: never)");
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-v4l2"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (!sensor_config.empty()) {
    auto sensor = selfcal::ReadSensorConfig(sensor_config);
    if (!sensor) {
      std::fprintf(stderr, "error: %s\n", sensor.error().message.c_str());
      return 2;
    }
    options.intrinsics = sensor->camera.intrinsics;
  }
  const auto& k = options.intrinsics;
  if (!(k.fx > 0 && k.fy > 0 && k.cx > 0 && k.cy > 0)) {
    std::fprintf(
        stderr,
        "error: UVC reports no intrinsics: give --sensor-config or all of --fx --fy --cx --cy\n");
    return 2;
  }
  if (!(options.depth_unit_m > 0)) {
    std::fprintf(stderr, "error: --depth-unit must be positive\n");
    return 2;
  }
  options.request_mode = trigger == "request";
  spdlog::info(
      "device={} width={} height={} fps={} buffers={} fx={} fy={} cx={} cy={} depth_unit={} "
      "lcm_url={} "
      "channel={} trigger={} trigger_channel={} max_frames={}",
      options.camera.device, options.camera.width, options.camera.height, options.camera.fps,
      options.camera.buffers, k.fx, k.fy, k.cx, k.cy, options.depth_unit_m, lcm_url,
      options.channel, trigger, options.trigger_channel, options.max_frames);
  auto bus = selfcal::OpenLcmBus(lcm_url);
  if (!bus) {
    std::fprintf(stderr, "error: %s\n", bus.error().message.c_str());
    return 1;
  }
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  auto io = MakeSystemV4l2Io();
  V4l2Driver driver(options, *io, **bus, [](int level, const std::string& message) {
    if (level == 0) {
      spdlog::info("{}", message);
    } else {
      spdlog::warn("{}", message);
    }
  });
  auto status = driver.Run(g_stop);
  const auto& c = driver.counters();
  spdlog::info("published={} requests={} dropped={} sequence_gaps={} reopens={}", c.published,
               c.requests, c.dropped, c.sequence_gaps, c.reopens);
  if (!status) {
    std::fprintf(stderr, "error: %s\n", status.error().message.c_str());
    return 1;
  }
  return 0;
}

// selfcal-openni2: Kinect and other OpenNI2 depth cameras, or .oni recordings; publishes
// selfcal.depth_image_t. See docs/cameras.md.
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>

#include "drivers/openni2/openni2_driver.h"

namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  using namespace selfcal::openni2;
  DriverOptions options;
  std::string lcm_url;
  std::string trigger = "none";
  CLI::App app{"selfcal-openni2: OpenNI2 depth camera or .oni recording -> selfcal.depth_image_t"};
  auto* uri = app.add_option("--uri", options.camera.uri, "device URI (default: any device)");
  auto* oni = app.add_option("--oni", options.camera.oni_path,
                             "play this .oni recording instead of a device")
                  ->check(CLI::ExistingFile);
  uri->excludes(oni);
  app.add_option("--record", options.camera.record_path,
                 "record the depth stream to this .oni file")
      ->excludes(oni);
  app.add_option("--width", options.camera.width, "depth width [px] (0: device's mode)");
  app.add_option("--height", options.camera.height, "depth height [px] (0: device's mode)");
  app.add_option("--fps", options.camera.fps, "frame rate (0: device's mode)");
  app.add_option("--fx", options.camera.intrinsics.fx,
                 "focal length x [px] (default: from the field of view)");
  app.add_option("--fy", options.camera.intrinsics.fy, "focal length y [px]");
  app.add_option("--cx", options.camera.intrinsics.cx, "principal point x [px]");
  app.add_option("--cy", options.camera.intrinsics.cy, "principal point y [px]");
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
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-openni2"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  const auto& k = options.camera.intrinsics;
  if ((k.fx > 0 || k.fy > 0 || k.cx > 0 || k.cy > 0) &&
      !(k.fx > 0 && k.fy > 0 && k.cx > 0 && k.cy > 0)) {
    std::fprintf(stderr, "error: give all of --fx --fy --cx --cy, or none\n");
    return 2;
  }
  options.request_mode = trigger == "request";
  spdlog::info(
      "uri={} oni={} record={} width={} height={} fps={} fx={} fy={} cx={} cy={} lcm_url={} "
      "channel={} trigger={} trigger_channel={} max_frames={}",
      options.camera.uri, options.camera.oni_path, options.camera.record_path, options.camera.width,
      options.camera.height, options.camera.fps, k.fx, k.fy, k.cx, k.cy, lcm_url, options.channel,
      trigger, options.trigger_channel, options.max_frames);
  auto bus = selfcal::OpenLcmBus(lcm_url);
  if (!bus) {
    std::fprintf(stderr, "error: %s\n", bus.error().message.c_str());
    return 1;
  }
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  OpenNi2Driver driver(options, **bus, [](int level, const std::string& message) {
    if (level == 0) {
      spdlog::info("{}", message);
    } else {
      spdlog::warn("{}", message);
    }
  });
  auto status = driver.Run(g_stop);
  const auto& c = driver.counters();
  spdlog::info("published={} frames={} requests={} reconnects={}", c.published, c.frames,
               c.requests, c.reconnects);
  if (!status) {
    std::fprintf(stderr, "error: %s\n", status.error().message.c_str());
    return 1;
  }
  return 0;
}

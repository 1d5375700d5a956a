// selfcal-aravis: PhotoNeo MotionCam-3D / PhoXi and other GenICam 3D cameras over GigE Vision;
// publishes selfcal.organized_cloud_t. See docs/cameras.md.
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <cstdio>

#include "drivers/aravis/aravis_driver.h"

namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop.store(true); }
}  // namespace

int main(int argc, char** argv) {
  using namespace selfcal::aravis;
  DriverOptions options;
  std::string lcm_url;
  std::string range_format = "abc";
  std::string trigger = "software";
  int frame_timeout_ms = 2000;
  // Pacing of cloud messages on udpm:// (docs/cameras.md, "Large messages over LCM").
  int publish_burst_kb = 1024;
  int publish_gap_us = 1000;
  CLI::App app{
      "selfcal-aravis: GenICam 3D camera (PhotoNeo) over GigE Vision -> selfcal.organized_cloud_t"};
  auto* address =
      app.add_option("--address", options.camera.address, "camera IPv4 address (opens directly)");
  auto* serial =
      app.add_option("--serial", options.camera.serial,
                     "camera serial number (GigE Vision discovery: broadcasts on every interface)");
  address->excludes(serial);
  app.add_option("--lcm-url", lcm_url, "LCM URL (empty: LCM_DEFAULT_URL or udpm default)");
  app.add_option("--channel", options.cloud_channel, "channel of the clouds")
      ->capture_default_str();
  app.add_option("--trigger-channel", options.trigger_channel,
                 "scan_marker_t channel whose BEGIN events request one frame each")
      ->capture_default_str();
  app.add_option("--trigger", trigger, "software (one frame per request) or free-run")
      ->check(CLI::IsMember({"software", "free-run"}))
      ->capture_default_str();
  app.add_option("--range-format", range_format,
                 "abc (Coord3D_ABC32f) or c (Coord3D_C32f + Scan3d intrinsics)")
      ->check(CLI::IsMember({"abc", "c"}))
      ->capture_default_str();
  app.add_flag("--intensity", options.camera.intensity, "enable the Intensity component");
  app.add_flag("--confidence", options.camera.confidence,
               "enable the Confidence component (invalid points NaN)");
  app.add_flag("--coordinate-maps", options.camera.coordinate_maps,
               "enable CoordinateMapA/B (with --range-format c)");
  app.add_option("--min-confidence", options.camera.decode.min_confidence,
                 "confidence below this is invalid")
      ->capture_default_str();
  app.add_option("--frame-rate", options.camera.frame_rate_hz,
                 "free-run frame rate [Hz] (0: camera's)")
      ->capture_default_str();
  app.add_option("--width", options.camera.width, "frame width [px] (0: camera's)");
  app.add_option("--height", options.camera.height, "frame height [px] (0: camera's)");
  app.add_option("--packet-size", options.camera.packet_size,
                 "GevSCPSPacketSize [bytes] (0: camera's)");
  app.add_flag("--ptp", options.camera.ptp, "PtpEnable: timestamps in PTP time");
  app.add_option("--buffers", options.camera.buffers, "stream buffers")
      ->capture_default_str()
      ->check(CLI::Range(2, 64));
  app.add_option("--frame-timeout-ms", frame_timeout_ms,
                 "reconnect when a triggered frame is this late")
      ->capture_default_str()
      ->check(CLI::Range(50, 600000));
  app.add_option("--retriggers", options.retriggers,
                 "re-triggers of a request whose frame was dropped")
      ->capture_default_str();
  app.add_option(
         "--publish-burst-kb", publish_burst_kb,
         "udpm://: send clouds in bursts of at most this many KiB (0: liblcm's single burst)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1 << 20));
  app.add_option("--publish-gap-us", publish_gap_us, "udpm://: pause between two bursts [us]")
      ->capture_default_str()
      ->check(CLI::Range(0, 1000000));
  app.add_option("--max-frames", options.max_frames,
                 "exit after publishing this many frames (0: never)");
  // Logs go to stderr, as for every selfcal program.
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-aravis"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (options.camera.address.empty() && options.camera.serial.empty()) {
    std::fprintf(stderr, "error: give --address or --serial\n");
    return 2;
  }
  options.camera.range_format =
      range_format == "c" ? RangeFormat::kCoord3dC32f : RangeFormat::kCoord3dAbc32f;
  options.camera.trigger = trigger == "free-run" ? TriggerMode::kFreeRun : TriggerMode::kSoftware;
  options.frame_timeout = std::chrono::milliseconds(frame_timeout_ms);
  if (options.camera.coordinate_maps && options.camera.range_format != RangeFormat::kCoord3dC32f) {
    std::fprintf(stderr, "error: --coordinate-maps needs --range-format c\n");
    return 2;
  }
  spdlog::info(
      "address={} serial={} lcm_url={} channel={} trigger={} trigger_channel={} range_format={} "
      "intensity={} confidence={} coordinate_maps={} min_confidence={} frame_rate={} width={} "
      "height={} packet_size={} ptp={} buffers={} frame_timeout_ms={} retriggers={} max_frames={} "
      "publish_burst_kb={} publish_gap_us={}",
      options.camera.address, options.camera.serial, lcm_url, options.cloud_channel, trigger,
      options.trigger_channel, range_format, options.camera.intensity, options.camera.confidence,
      options.camera.coordinate_maps, options.camera.decode.min_confidence,
      options.camera.frame_rate_hz, options.camera.width, options.camera.height,
      options.camera.packet_size, options.camera.ptp, options.camera.buffers, frame_timeout_ms,
      options.retriggers, options.max_frames, publish_burst_kb, publish_gap_us);
  selfcal::PublishPacing pacing;
  pacing.burst_bytes = static_cast<std::size_t>(publish_burst_kb) * 1024;
  pacing.gap = std::chrono::microseconds(publish_gap_us);
  auto bus = selfcal::OpenLcmBus(lcm_url, pacing);
  if (!bus) {
    std::fprintf(stderr, "error: %s\n", bus.error().message.c_str());
    return 1;
  }
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  AravisDriver driver(options, **bus, [](int level, const std::string& message) {
    if (level == 0) {
      spdlog::info("{}", message);
    } else {
      spdlog::warn("{}", message);
    }
  });
  auto status = driver.Run(g_stop);
  const auto& c = driver.counters();
  spdlog::info("published={} requests={} failed_requests={} dropped={} stray={} reconnects={}",
               c.published, c.requests, c.failed_requests, c.dropped, c.stray, c.reconnects);
  if (!status) {
    std::fprintf(stderr, "error: %s\n", status.error().message.c_str());
    return 1;
  }
  return 0;
}

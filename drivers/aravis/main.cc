// selfcal-aravis: PhotoNeo MotionCam-3D / PhoXi and other GenICam 3D cameras over GigE Vision;
// publishes selfcal.organized_cloud_t. See docs/cameras.md.
#include <spdlog/spdlog.h>

#include "drivers/aravis/aravis_driver.h"
#include "protocols/program/program.h"

namespace {

namespace program = selfcal::program;
using namespace selfcal::aravis;

constexpr program::About kAbout{
    "selfcal-aravis",
    "selfcal-aravis: GenICam 3D camera (PhotoNeo) over GigE Vision -> selfcal.organized_cloud_t"};

struct Settings {
  DriverOptions driver;
  std::string lcm_url;
  int frame_timeout_ms = 2000;
  // Pacing of cloud messages on udpm:// (docs/cameras.md, "Large messages over LCM").
  int publish_burst_kb = 1024;
  int publish_gap_us = 1000;
};

void DescribeOptions(program::Program& p, Settings& s) {
  CameraOptions& c = s.driver.camera;
  auto* address = p.Option("--address", c.address, "camera IPv4 address (opens directly)");
  p.Option("--serial", c.serial,
           "camera serial number (GigE Vision discovery: broadcasts on every interface)")
      ->excludes(address);
  p.LcmUrlOption(s.lcm_url);
  p.Option("--channel", s.driver.stream.channel, "channel of the clouds");
  p.Option("--trigger-channel", s.driver.stream.trigger_channel,
           "scan_marker_t channel whose BEGIN events request one frame each");
  p.Choice("--trigger", c.trigger,
           {{"software", TriggerMode::kSoftware}, {"free-run", TriggerMode::kFreeRun}},
           "software (one frame per request) or free-run");
  p.Choice("--range-format", c.range_format,
           {{"abc", RangeFormat::kCoord3dAbc32f}, {"c", RangeFormat::kCoord3dC32f}},
           "abc (Coord3D_ABC32f) or c (Coord3D_C32f + Scan3d intrinsics)");
  p.Flag("--intensity", c.intensity, "enable the Intensity component");
  p.Flag("--confidence", c.confidence, "enable the Confidence component (invalid points NaN)");
  p.Flag("--coordinate-maps", c.coordinate_maps, "enable CoordinateMapA/B (with --range-format c)");
  p.Option("--min-confidence", c.decode.min_confidence, "confidence below this is invalid");
  p.Option("--frame-rate", c.frame_rate_hz, "free-run frame rate [Hz] (0: camera's)");
  p.Option("--width", c.width, "frame width [px] (0: camera's)");
  p.Option("--height", c.height, "frame height [px] (0: camera's)");
  p.Option("--packet-size", c.packet_size, "GevSCPSPacketSize [bytes] (0: camera's)");
  p.Flag("--ptp", c.ptp, "PtpEnable: timestamps in PTP time");
  p.Option("--buffers", c.buffers, "stream buffers")->check(CLI::Range(2, 64));
  p.Choice("--stream-socket", c.stream_socket,
           {{"packet", StreamSocket::kPacket}, {"standard", StreamSocket::kStandard}},
           "how the stream is received: packet (Aravis' packet socket ring, needs CAP_NET_RAW; "
           "Aravis falls back without it) or standard (a UDP socket)");
  p.Option("--frame-timeout-ms", s.frame_timeout_ms,
           "reconnect when a triggered frame is this late")
      ->check(CLI::Range(50, 600000));
  p.Option("--retriggers", s.driver.retriggers, "re-triggers of a request whose frame was dropped");
  p.Option("--publish-burst-kb", s.publish_burst_kb,
           "udpm://: send clouds in bursts of at most this many KiB (0: liblcm's single burst)")
      ->check(CLI::Range(0, 1 << 20));
  p.Option("--publish-gap-us", s.publish_gap_us, "udpm://: pause between two bursts [us]")
      ->check(CLI::Range(0, 1000000));
  p.Option("--max-frames", s.driver.stream.max_frames,
           "exit after publishing this many frames (0: never)");
}

// Everything after the command line: check, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  const CameraOptions& camera = s.driver.camera;
  if (camera.address.empty() && camera.serial.empty()) {
    return program::Fail("give --address or --serial", program::kExitUsage);
  }
  if (camera.coordinate_maps && camera.range_format != RangeFormat::kCoord3dC32f) {
    return program::Fail("--coordinate-maps needs --range-format c", program::kExitUsage);
  }
  s.driver.stream.frame_timeout = std::chrono::milliseconds(s.frame_timeout_ms);
  program.LogConfiguration();
  selfcal::PublishPacing pacing;
  pacing.burst_bytes = static_cast<std::size_t>(s.publish_burst_kb) * 1024;
  pacing.gap = std::chrono::microseconds(s.publish_gap_us);
  auto bus = program.OpenBus(s.lcm_url, pacing);
  if (!bus) return program::Fail(bus.error().message);
  AravisDriver driver(s.driver, **bus, program::Logger());
  auto status = driver.Run(program::StopOnSignals());
  const auto& c = driver.counters();
  spdlog::info("published={} requests={} failed_requests={} dropped={} stray={} reconnects={}",
               c.published, c.requests, c.failed_requests, c.dropped, c.stray, c.reconnects);
  return program::ExitCode(status);
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}

// selfcal-v4l2: UVC depth cameras with Z16 frames (RealSense and the like, Kinect v1 through
// gspca) over V4L2 mmap streaming; publishes selfcal.depth_image_t. See docs/cameras.md.
#include <spdlog/spdlog.h>

#include "drivers/v4l2/v4l2_driver.h"
#include "protocols/camera/stream_options.h"
#include "protocols/model_file/sensor_config.h"
#include "protocols/program/program.h"

namespace {

namespace program = selfcal::program;
using namespace selfcal::v4l2;

constexpr program::About kAbout{
    "selfcal-v4l2", "selfcal-v4l2: UVC Z16 depth camera (V4L2) -> selfcal.depth_image_t"};

struct Settings {
  DriverOptions driver;
  std::string lcm_url;
  std::string sensor_config;
  std::string trigger = "none";
};

void DescribeOptions(program::Program& p, Settings& s) {
  CameraOptions& c = s.driver.camera;
  p.Option("--device", c.device, "V4L2 device");
  p.Option("--width", c.width, "width [px] (0: device's)");
  p.Option("--height", c.height, "height [px] (0: device's)");
  p.Option("--fps", c.fps, "frame rate (0: device's)");
  p.Option("--buffers", c.buffers, "mmap buffers")->check(CLI::Range(2, 32));
  auto* config = p.Option("--sensor-config", s.sensor_config,
                          "sensor file with the intrinsics (config/sensors/*.yaml)")
                     ->check(CLI::ExistingFile);
  auto& k = s.driver.intrinsics;
  p.Option("--fx", k.fx, "focal length x [px]")->excludes(config);
  p.Option("--fy", k.fy, "focal length y [px]");
  p.Option("--cx", k.cx, "principal point x [px]");
  p.Option("--cy", k.cy, "principal point y [px]");
  p.Option("--depth-unit", s.driver.depth_unit_m, "metres per Z16 count")
      ->check(program::kPositive);
  selfcal::camera::DescribeRequestStreamOptions(p, s.lcm_url, s.trigger, s.driver.stream);
}

// The intrinsics from --sensor-config or the flags; nothing when usable, else the exit code.
std::optional<int> ResolveIntrinsics(Settings& s) {
  auto& k = s.driver.intrinsics;
  if (!s.sensor_config.empty()) {
    auto sensor = selfcal::ReadSensorConfig(s.sensor_config);
    if (!sensor) return program::Fail(sensor.error().message, program::kExitUsage);
    k = sensor->camera.intrinsics;
  }
  if (!(k.fx > 0 && k.fy > 0 && k.cx > 0 && k.cy > 0)) {
    return program::Fail(
        "UVC reports no intrinsics: give --sensor-config or all of --fx --fy --cx --cy",
        program::kExitUsage);
  }
  return std::nullopt;
}

// Everything after the command line: check, open the bus and the device, echo, run.
int Start(program::Program& program, Settings& s) {
  if (auto exit = ResolveIntrinsics(s)) return *exit;
  s.driver.request_mode = s.trigger == "request";
  program.LogConfiguration();
  auto bus = program.OpenBus(s.lcm_url);
  if (!bus) return program::Fail(bus.error().message);
  auto io = MakeSystemV4l2Io();
  V4l2Driver driver(s.driver, *io, **bus, program::Logger());
  auto status = driver.Run(program::StopOnSignals());
  const auto& c = driver.counters();
  spdlog::info("published={} requests={} dropped={} sequence_gaps={} reopens={}", c.published,
               c.requests, c.dropped, c.sequence_gaps, c.reopens);
  return program::ExitCode(status);
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}

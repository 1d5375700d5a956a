// selfcal-openni2: Kinect and other OpenNI2 depth cameras, or .oni recordings; publishes
// selfcal.depth_image_t. See docs/cameras.md.
#include <spdlog/spdlog.h>

#include "drivers/openni2/openni2_driver.h"
#include "protocols/camera/stream_options.h"
#include "protocols/program/program.h"

namespace {

namespace program = selfcal::program;
using namespace selfcal::openni2;

constexpr program::About kAbout{
    "selfcal-openni2",
    "selfcal-openni2: OpenNI2 depth camera or .oni recording -> selfcal.depth_image_t"};

struct Settings {
  DriverOptions driver;
  std::string lcm_url;
  std::string trigger = "none";
};

void DescribeOptions(program::Program& p, Settings& s) {
  CameraOptions& c = s.driver.camera;
  auto* uri = p.Option("--uri", c.uri, "device URI (default: any device)");
  auto* oni = p.Option("--oni", c.oni_path, "play this .oni recording instead of a device")
                  ->check(CLI::ExistingFile)
                  ->excludes(uri);
  p.Option("--record", c.record_path, "record the depth stream to this .oni file")->excludes(oni);
  p.Option("--width", c.width, "depth width [px] (0: device's mode)");
  p.Option("--height", c.height, "depth height [px] (0: device's mode)");
  p.Option("--fps", c.fps, "frame rate (0: device's mode)");
  p.Option("--fx", c.intrinsics.fx, "focal length x [px] (default: from the field of view)");
  p.Option("--fy", c.intrinsics.fy, "focal length y [px]");
  p.Option("--cx", c.intrinsics.cx, "principal point x [px]");
  p.Option("--cy", c.intrinsics.cy, "principal point y [px]");
  selfcal::camera::DescribeRequestStreamOptions(p, s.lcm_url, s.trigger, s.driver.stream);
}

// Everything after the command line: check, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  const auto& k = s.driver.camera.intrinsics;
  if ((k.fx > 0 || k.fy > 0 || k.cx > 0 || k.cy > 0) &&
      !(k.fx > 0 && k.fy > 0 && k.cx > 0 && k.cy > 0)) {
    return program::Fail("give all of --fx --fy --cx --cy, or none", program::kExitUsage);
  }
  s.driver.request_mode = s.trigger == "request";
  program.LogConfiguration();
  auto bus = program.OpenBus(s.lcm_url);
  if (!bus) return program::Fail(bus.error().message);
  OpenNi2Driver driver(s.driver, **bus, program::Logger());
  auto status = driver.Run(program::StopOnSignals());
  const auto& c = driver.counters();
  spdlog::info("published={} frames={} requests={} reopens={}", c.published, c.frames, c.requests,
               c.reopens);
  return program::ExitCode(status);
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}

// selfcal-fake-gev-camera: serves a PhotoNeo-like GigE Vision camera (libaravis' fake camera with
// our GenICam features) until SIGINT/SIGTERM. Run it inside a network namespace (tests/netns-run):
// GigE Vision clients discover cameras by broadcast.
#include <glib.h>
#include <spdlog/spdlog.h>

#include <cstdio>

#include "protocols/program/program.h"
#include "tools/sim_cameras/fake_gev_camera.h"
#include "tools/sim_cameras/raycast_depth.h"
#include "tools/sim_cameras/scenario_camera.h"

namespace {

namespace program = selfcal::program;

constexpr program::About kAbout{
    "selfcal-fake-gev-camera",
    "Serves a PhotoNeo-like GigE Vision fake camera (libaravis) with an analytic depth scene or "
    "a core/sim scene or a simulation scenario"};

struct Settings {
  selfcal::sim_cameras::FakeGevCameraOptions camera;
  bool print_xml = false;
  std::string scene = "analytic";
  double camera_distance_m = 0.7;
  std::string scenario;
  int view = 0;
};

void DescribeOptions(program::Program& p, Settings& s) {
  auto& c = s.camera;
  p.Option("--address", c.address, "IPv4 address to serve GVCP/GVSP on");
  p.Option("--serial", c.serial, "serial number (DeviceID)");
  p.Option("--width", c.width, "frame width [px]")->check(CLI::Range(1, 2048));
  p.Option("--height", c.height, "frame height [px]")->check(CLI::Range(1, 2048));
  p.Option("--fx", c.intrinsics.fx, "focal length x [px]");
  p.Option("--fy", c.intrinsics.fy, "focal length y [px]");
  p.Option("--cx", c.intrinsics.cx, "principal point x [px]");
  p.Option("--cy", c.intrinsics.cy, "principal point y [px]");
  p.Option("--noise-sigma", c.noise_sigma_m, "depth noise sigma [m]")->check(program::kNonNegative);
  p.Option("--frame-rate", c.frame_rate_hz, "free-run frame rate [Hz]")
      ->check(CLI::Range(0.2, 1000.0));
  p.Option("--loss-ratio", c.packet_loss_ratio, "fraction of GVSP packets dropped")
      ->check(CLI::Range(0.0, 1.0));
  p.Option("--scene", s.scene,
           "analytic (wall and ball) or a core/sim scene ray cast with Embree: tabletop-teapot, "
           "office, lab, corner")
      ->check(CLI::IsMember({"analytic", "tabletop-teapot", "office", "lab", "corner"}));
  p.Option("--camera-distance", s.camera_distance_m,
           "core/sim scenes: camera distance from the focus [m]")
      ->check(CLI::Range(0.05, 20.0));
  p.Option("--scenario", s.scenario,
           "a simulation scenario (config/scenarios/): the camera on its true arm at the start of "
           "scan --view, with the resolution, intrinsics and view range of its sensor file; its "
           "effects section, if any, served as selfcal-sim-scip serves it (replaces --scene)");
  p.Option("--view", s.view, "--scenario: the scan of the scenario's plan to stand at")
      ->check(CLI::NonNegativeNumber);
  p.Flag(
      "--multipart", c.multipart,
      "send frames as GigE Vision 2 multipart payloads (Intensity, Range, Confidence as enabled)");
  p.app().add_flag("--print-xml", s.print_xml, "print the GenICam XML and exit");
}

int PrintXml(bool multipart) {
  auto xml = selfcal::sim_cameras::BuildFakeGevGenicamXml(multipart);
  if (!xml) return program::Fail(xml.error().message);
  std::fwrite(xml->data(), 1, xml->size(), stdout);
  return program::kExitOk;
}

// A core/sim scene instead of the analytic one: depth maps ray cast from the camera's view.
std::optional<int> UseSimScene(Settings& s) {
  auto view = selfcal::sim_cameras::MakeSimSceneView(s.scene, s.camera_distance_m);
  if (!view) return program::Fail(view.error().message);
  auto shared = std::make_shared<selfcal::sim_cameras::SimSceneView>(std::move(*view));
  const auto intrinsics = s.camera.intrinsics;
  const double closest = s.camera.scene.closest_m, farthest = s.camera.scene.farthest_m;
  s.camera.depth_map = [shared, intrinsics, closest, farthest](std::uint32_t width,
                                                               std::uint32_t height) {
    return selfcal::sim_cameras::RayCastDepthMap(*shared->caster, shared->T_scene_camera, width,
                                                 height, intrinsics, closest, farthest);
  };
  return std::nullopt;
}

// A scenario's camera: ideal ray casts plus the fake's noise, or the field frames.
std::optional<int> UseScenario(Settings& s) {
  auto created = selfcal::sim_cameras::ScenarioCamera::Create(s.scenario, s.view);
  if (!created) return program::Fail(created.error().message);
  std::shared_ptr<selfcal::sim_cameras::ScenarioCamera> camera = std::move(*created);
  const auto& sensor = camera->sensor();
  s.camera.width = static_cast<std::uint32_t>(sensor.width);
  s.camera.height = static_cast<std::uint32_t>(sensor.height);
  s.camera.intrinsics = sensor.intrinsics;
  s.camera.scene.closest_m = sensor.range_min;
  s.camera.scene.farthest_m = sensor.range_max;
  const auto intrinsics = s.camera.intrinsics;
  spdlog::info("scenario camera: {} x {}, fx {}, view {}, field effects {}", sensor.width,
               sensor.height, intrinsics.fx, s.view, camera->field() ? "on" : "off");
  if (camera->field()) {
    s.camera.frame_depth = [camera, intrinsics](std::uint64_t frame, double device_time,
                                                std::uint32_t width, std::uint32_t height,
                                                std::vector<float>& depth) {
      camera->FieldDepth(frame, device_time, width, height, intrinsics, depth);
    };
  } else {
    s.camera.depth_map = [camera, intrinsics](std::uint32_t width, std::uint32_t height) {
      return camera->IdealDepth(width, height, intrinsics);
    };
  }
  return std::nullopt;
}

// Everything after the command line: read files, open the bus, echo, run.
int Start(program::Program& program, Settings& s) {
  if (s.print_xml) return PrintXml(s.camera.multipart);
  program.LogConfiguration();
  if (!s.scenario.empty()) {
    if (auto exit = UseScenario(s)) return *exit;
  } else if (s.scene != "analytic") {
    if (auto exit = UseSimScene(s)) return *exit;
  }
  auto camera = selfcal::sim_cameras::FakeGevCamera::Start(s.camera);
  if (!camera) return program::Fail(camera.error().message);
  // The camera runs on glib's main loop; it ends when the stop flag is set.
  GMainLoop* loop = g_main_loop_new(nullptr, FALSE);
  program::StopOnSignals();
  g_timeout_add(
      50,
      [](gpointer data) -> gboolean {
        if (!program::StopFlag().load()) return G_SOURCE_CONTINUE;
        g_main_loop_quit(static_cast<GMainLoop*>(data));
        return G_SOURCE_REMOVE;
      },
      loop);
  spdlog::info("serving; stop with SIGINT or SIGTERM");
  g_main_loop_run(loop);
  g_main_loop_unref(loop);
  spdlog::info("stopped after {} frames", (*camera)->frames_served());
  return program::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return program::Main<Settings>(argc, argv, kAbout, DescribeOptions, Start);
}

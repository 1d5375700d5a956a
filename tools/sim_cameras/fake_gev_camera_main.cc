// selfcal-fake-gev-camera: serves a PhotoNeo-like GigE Vision camera (libaravis' fake camera with
// our GenICam features) until SIGINT/SIGTERM. Run it inside a network namespace (tests/netns-run):
// GigE Vision clients discover cameras by broadcast.
#include <glib-unix.h>
#include <glib.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>

#include "tools/sim_cameras/fake_gev_camera.h"
#include "tools/sim_cameras/raycast_depth.h"

int main(int argc, char** argv) {
  selfcal::sim_cameras::FakeGevCameraOptions options;
  bool print_xml = false;
  std::string scene = "analytic";
  double camera_distance_m = 0.7;
  CLI::App app{
      "Serves a PhotoNeo-like GigE Vision fake camera (libaravis) with an analytic depth scene or "
      "a "
      "core/sim scene"};
  app.add_option("--address", options.address, "IPv4 address to serve GVCP/GVSP on")
      ->capture_default_str();
  app.add_option("--serial", options.serial, "serial number (DeviceID)")->capture_default_str();
  app.add_option("--width", options.width, "frame width [px]")
      ->capture_default_str()
      ->check(CLI::Range(1, 2048));
  app.add_option("--height", options.height, "frame height [px]")
      ->capture_default_str()
      ->check(CLI::Range(1, 2048));
  app.add_option("--fx", options.intrinsics.fx, "focal length x [px]")->capture_default_str();
  app.add_option("--fy", options.intrinsics.fy, "focal length y [px]")->capture_default_str();
  app.add_option("--cx", options.intrinsics.cx, "principal point x [px]")->capture_default_str();
  app.add_option("--cy", options.intrinsics.cy, "principal point y [px]")->capture_default_str();
  app.add_option("--noise-sigma", options.noise_sigma_m, "depth noise sigma [m]")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--frame-rate", options.frame_rate_hz, "free-run frame rate [Hz]")
      ->capture_default_str()
      ->check(CLI::Range(0.2, 1000.0));
  app.add_option("--loss-ratio", options.packet_loss_ratio, "fraction of GVSP packets dropped")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--scene", scene,
                 "analytic (wall and ball) or a core/sim scene ray cast with Embree: "
                 "tabletop-teapot, office, "
                 "lab, corner")
      ->capture_default_str()
      ->check(CLI::IsMember({"analytic", "tabletop-teapot", "office", "lab", "corner"}));
  app.add_option("--camera-distance", camera_distance_m,
                 "core/sim scenes: camera distance from the focus [m]")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 20.0));
  app.add_flag(
      "--multipart", options.multipart,
      "send frames as GigE Vision 2 multipart payloads (Intensity, Range, Confidence as enabled)");
  app.add_flag("--print-xml", print_xml, "print the GenICam XML and exit");
  // Logs go to stderr, as for every selfcal program.
  spdlog::set_default_logger(spdlog::stderr_color_mt("selfcal-fake-gev-camera"));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (print_xml) {
    auto xml = selfcal::sim_cameras::BuildFakeGevGenicamXml(options.multipart);
    if (!xml) {
      std::fprintf(stderr, "error: %s\n", xml.error().message.c_str());
      return 1;
    }
    std::fwrite(xml->data(), 1, xml->size(), stdout);
    return 0;
  }
  spdlog::info(
      "address={} serial={} width={} height={} fx={} fy={} cx={} cy={} noise_sigma={} "
      "frame_rate={} loss_ratio={} scene={} camera_distance={} multipart={}",
      options.address, options.serial, options.width, options.height, options.intrinsics.fx,
      options.intrinsics.fy, options.intrinsics.cx, options.intrinsics.cy, options.noise_sigma_m,
      options.frame_rate_hz, options.packet_loss_ratio, scene, camera_distance_m,
      options.multipart);
  if (scene != "analytic") {
    auto view = selfcal::sim_cameras::MakeSimSceneView(scene, camera_distance_m);
    if (!view) {
      std::fprintf(stderr, "error: %s\n", view.error().message.c_str());
      return 1;
    }
    auto shared = std::make_shared<selfcal::sim_cameras::SimSceneView>(std::move(*view));
    const auto intrinsics = options.intrinsics;
    const double closest = options.scene.closest_m, farthest = options.scene.farthest_m;
    options.depth_map = [shared, intrinsics, closest, farthest](std::uint32_t width,
                                                                std::uint32_t height) {
      return selfcal::sim_cameras::RayCastDepthMap(*shared->caster, shared->T_scene_camera, width,
                                                   height, intrinsics, closest, farthest);
    };
  }
  auto camera = selfcal::sim_cameras::FakeGevCamera::Start(options);
  if (!camera) {
    std::fprintf(stderr, "error: %s\n", camera.error().message.c_str());
    return 1;
  }
  GMainLoop* loop = g_main_loop_new(nullptr, FALSE);
  const auto quit = [](gpointer data) -> gboolean {
    g_main_loop_quit(static_cast<GMainLoop*>(data));
    return G_SOURCE_REMOVE;
  };
  g_unix_signal_add(SIGINT, quit, loop);
  g_unix_signal_add(SIGTERM, quit, loop);
  spdlog::info("serving; stop with SIGINT or SIGTERM");
  g_main_loop_run(loop);
  g_main_loop_unref(loop);
  spdlog::info("stopped after {} frames", (*camera)->frames_served());
  return 0;
}

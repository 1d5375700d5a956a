// A PhotoNeo-like GigE Vision camera for tests and benchmarks: libaravis' own GigE Vision fake
// camera (real GVCP/GVSP on a UDP socket), with a GenICam description of ours that adds
// Coord3D_ABC32f / Coord3D_C32f / Confidence8 pixel formats, ComponentSelector / ComponentEnable /
// ComponentIDValue and the Scan3d intrinsics, serving frames of an analytic depth scene or of a
// core/sim scene (depth_map).
// Run it only on 127.0.0.1 inside a network namespace the test created (test-peers.md).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/util/expected.h"
#include "tools/sim_cameras/depth_scene.h"

namespace selfcal::sim_cameras {

// Register map of our additions (free scratch registers of the fake camera, 0x1000..0xFFFF).
namespace fake_gev {
inline constexpr std::uint32_t kComponentSelector = 0x1000;
inline constexpr std::uint32_t kComponentEnable = 0x1010;  // + 4 * selector
inline constexpr std::uint32_t kComponentId = 0x1030;      // + 4 * selector
inline constexpr std::uint32_t kScan3dOutputMode = 0x1050;
inline constexpr std::uint32_t kScan3dFocalLength = 0x1100;  // float64, big-endian
inline constexpr std::uint32_t kScan3dPrincipalPointU = 0x1108;
inline constexpr std::uint32_t kScan3dPrincipalPointV = 0x1110;
inline constexpr std::uint32_t kScan3dAspectRatio = 0x1118;
// Selector values and the component ids our fake reports for them.
inline constexpr std::uint32_t kIntensity = 0, kRange = 1, kConfidence = 2;
inline constexpr std::uint32_t kIntensityId = 1, kRangeId = 2, kConfidenceId = 6;
}  // namespace fake_gev

struct FakeGevCameraOptions {
  std::string address = "127.0.0.1";
  std::string serial = "SELFCAL-FAKE-1";
  std::uint32_t width = 1120, height = 800;
  PinholeIntrinsics intrinsics{1200.0, 1200.0, 559.5, 399.5};  // of the full width x height frame
  AnalyticDepthScene scene;
  // Depth z [m] per pixel, row-major, 0 = invalid, for a frame of the given size; when set it
  // replaces `scene` (e.g. RayCastDepthMap of a core/sim scene, raycast_depth.h).
  std::function<std::vector<float>(std::uint32_t width, std::uint32_t height)> depth_map;
  // Depth z [m] per pixel (0 = invalid) of frame `frame_id`, taken `device_time_s` after the
  // camera started, noise included; when set it replaces `scene`, `depth_map` and the noise
  // below (a scenario's field effects: scenario_camera.h).
  std::function<void(std::uint64_t frame_id, double device_time_s, std::uint32_t width,
                     std::uint32_t height, std::vector<float>& depth)>
      frame_depth;
  double noise_sigma_m = 0.00018;  // on z (Table I, PhotoNeo)
  double frame_rate_hz = 20.0;
  double packet_loss_ratio = 0.0;    // GVSP packets the fake drops, 0..1
  std::uint32_t packet_size = 8192;  // GevSCPSPacketSize default (loopback takes jumbo packets)
  // Send every frame as a GigE Vision 2 multipart payload of the enabled components (Intensity
  // Mono16, Range, Confidence8, in increasing component id order, as PhotoNeo does). libaravis'
  // fake cannot: in this mode all of its own GVSP packets are dropped (gvsp-lost-ratio 1) and we
  // send the frame ourselves, built with protocols/camera/gvsp.h, to the stream address the client
  // configured, with the fake's frame ids and timestamps. GVCP stays libaravis'.
  bool multipart = false;
};

// The GenICam XML our fake serves: libaravis' fake camera description plus our features. With
// `multipart`, PayloadSize counts every enabled component (Range + Mono16 Intensity + Confidence8).
Expected<std::string> BuildFakeGevGenicamXml(bool multipart = false);

class FakeGevCamera {
 public:
  static Expected<std::unique_ptr<FakeGevCamera>> Start(const FakeGevCameraOptions& options);
  ~FakeGevCamera();
  FakeGevCamera(const FakeGevCamera&) = delete;
  FakeGevCamera& operator=(const FakeGevCamera&) = delete;

  std::uint64_t frames_served() const { return frames_served_.load(); }
  const FakeGevCameraOptions& options() const { return options_; }

 private:
  explicit FakeGevCamera(const FakeGevCameraOptions& options);
  static void Fill(void* buffer, void* self, std::uint32_t exposure_us, std::uint32_t gain,
                   std::uint32_t pixel_format);
  void UpdateTruth(std::uint32_t width, std::uint32_t height);
  void SendMultipart(std::uint64_t frame_id, std::uint64_t timestamp_ns, std::uint32_t range_format,
                     const std::uint8_t* range, std::uint32_t width, std::uint32_t height);

  FakeGevCameraOptions options_;
  std::string xml_path_;
  void* gv_camera_ = nullptr;         // ArvGvFakeCamera*
  std::vector<float> truth_depth_m_;  // per pixel of the current width x height
  std::vector<float> noise_;          // a table of unit Gaussian samples
  std::vector<float> frame_depth_m_;  // the current frame's, with frame_depth
  std::chrono::steady_clock::time_point started_ = std::chrono::steady_clock::now();
  std::uint32_t truth_width_ = 0, truth_height_ = 0;
  std::atomic<std::uint64_t> frames_served_{0};
  int multipart_fd_ = -1;                             // our GVSP socket in multipart mode
  std::vector<std::uint8_t> intensity_, confidence_;  // multipart parts, reused
};

}  // namespace selfcal::sim_cameras

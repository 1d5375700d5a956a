// A GenICam 3D camera (PhotoNeo MotionCam-3D / PhoXi and the like) over GigE Vision through
// Aravis: open by address or serial, component selection, software trigger or free run, buffers
// decoded to organized clouds in metres. Returns selfcal types; knows nothing of LCM.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/util/expected.h"
#include "protocols/camera/cloud_decode.h"

namespace selfcal::aravis {

enum class RangeFormat { kCoord3dAbc32f, kCoord3dC32f };
enum class TriggerMode { kSoftware, kFreeRun };
// How Aravis receives the GVSP stream: a packet socket (an AF_PACKET ring, needs CAP_NET_RAW or
// root; Aravis falls back to a socket without them) or a plain UDP socket.
enum class StreamSocket { kPacket, kStandard };

struct CameraOptions {
  // Exactly one of address (IPv4, no discovery) or serial (GigE Vision discovery: broadcasts on
  // every interface, so never in tests outside a network namespace).
  std::string address;
  std::string serial;
  RangeFormat range_format = RangeFormat::kCoord3dAbc32f;
  bool intensity = false;
  bool confidence = false;
  bool coordinate_maps = false;  // CoordinateMapA/B with Coord3D_C32f
  TriggerMode trigger = TriggerMode::kSoftware;
  double frame_rate_hz = 0.0;           // free run; 0 keeps the camera's rate
  std::uint32_t width = 0, height = 0;  // 0 keeps the camera's size
  std::uint32_t packet_size = 0;        // GevSCPSPacketSize; 0 keeps the camera's
  bool ptp = false;                     // PtpEnable: buffer timestamps in PTP time
  int buffers = 6;
  StreamSocket stream_socket = StreamSocket::kPacket;
  camera::DecodeOptions decode;
};

struct CameraCounters {
  std::uint64_t decoded = 0;
  std::uint64_t incomplete = 0;  // Aravis reported missing packets, timeout, size mismatch...
  std::uint64_t corrupted = 0;   // complete but undecodable (wrong layout, sizes)
};

struct FrameInfo {
  std::uint64_t device_timestamp_ns = 0;  // the buffer's timestamp (device or PTP clock)
  std::uint64_t system_timestamp_ns = 0;  // host CLOCK_REALTIME when the buffer arrived
  std::uint64_t frame_id = 0;             // GVSP block id
  std::uint32_t width = 0, height = 0;
  camera::DecodeSummary summary;
};

// Storage the caller owns (allocated once): x, y, z and intensity, resized on size changes only.
struct CloudStorage {
  std::vector<float> x, y, z, intensity;
};

class AravisCamera {
 public:
  static Expected<std::unique_ptr<AravisCamera>> Open(const CameraOptions& options);
  ~AravisCamera();
  AravisCamera(const AravisCamera&) = delete;
  AravisCamera& operator=(const AravisCamera&) = delete;

  // Sends TriggerSoftware: the camera exposes one frame.
  Status Trigger();
  // Waits up to `timeout` for a buffer. Returns true with a decoded cloud in `storage`; false on
  // timeout or when the buffer was incomplete or corrupted (counted, never returned).
  Expected<bool> NextCloud(std::chrono::milliseconds timeout, CloudStorage& storage,
                           FrameInfo& info);

  // Set by the heartbeat thread when the camera stopped answering (Aravis' control-lost signal).
  bool control_lost() const { return control_lost_->load(); }
  const CameraCounters& counters() const { return counters_; }
  const std::string& description() const { return description_; }
  std::uint32_t width() const { return width_; }
  std::uint32_t height() const { return height_; }
  std::string last_drop_reason() const { return last_drop_reason_; }

 private:
  AravisCamera() = default;
  Status Configure();

  CameraOptions options_;
  void* camera_ = nullptr;  // ArvCamera*
  void* stream_ = nullptr;  // ArvStream*
  std::shared_ptr<std::atomic<bool>> control_lost_ = std::make_shared<std::atomic<bool>>(false);
  std::vector<std::pair<std::uint32_t, camera::ComponentRole>> roles_by_id_;
  camera::Scan3dParameters scan3d_;
  std::vector<camera::ImagePart> parts_;
  CameraCounters counters_;
  std::string description_;
  std::string last_drop_reason_;
  std::uint32_t width_ = 0, height_ = 0;
};

}  // namespace selfcal::aravis

#include "drivers/aravis/aravis_camera.h"

#include <arv.h>

#include <algorithm>

#include "protocols/camera/pixel_format.h"

namespace selfcal::aravis {
namespace {

using camera::ComponentRole;

ArvCamera* Cam(void* p) { return static_cast<ArvCamera*>(p); }
ArvStream* Stream(void* p) { return static_cast<ArvStream*>(p); }

// Takes the GError (if any) and returns it as our error with `what` in front.
Status Check(GError* error, const std::string& what) {
  if (error == nullptr) return OkStatus();
  std::string message = what + ": " + error->message;
  g_error_free(error);
  return Error{message};
}

bool HasFeature(ArvCamera* camera, const char* name) {
  return arv_camera_is_feature_available(camera, name, nullptr);
}

bool HasEnumEntry(ArvCamera* camera, const char* feature, const char* entry) {
  return HasFeature(camera, feature) &&
         arv_camera_is_enumeration_entry_available(camera, feature, entry, nullptr);
}

struct ComponentChoice {
  ComponentRole role;  // selected by its name, ComponentRoleName
  bool wanted;
};

const char* BufferStatusName(ArvBufferStatus status) {
  switch (status) {
    case ARV_BUFFER_STATUS_SUCCESS:
      return "success";
    case ARV_BUFFER_STATUS_CLEARED:
      return "cleared";
    case ARV_BUFFER_STATUS_TIMEOUT:
      return "timeout before all packets arrived";
    case ARV_BUFFER_STATUS_MISSING_PACKETS:
      return "missing packets";
    case ARV_BUFFER_STATUS_WRONG_PACKET_ID:
      return "wrong packet id";
    case ARV_BUFFER_STATUS_SIZE_MISMATCH:
      return "size mismatch";
    case ARV_BUFFER_STATUS_FILLING:
      return "still filling";
    case ARV_BUFFER_STATUS_ABORTED:
      return "aborted";
    default:
      return "unknown status";
  }
}

void OnControlLost(ArvDevice*, gpointer flag) {
  static_cast<std::atomic<bool>*>(flag)->store(true);
}

}  // namespace

Expected<std::unique_ptr<AravisCamera>> AravisCamera::Open(const CameraOptions& options) {
  if (options.address.empty() == options.serial.empty()) {
    return Error{"give exactly one of address and serial"};
  }
  std::unique_ptr<AravisCamera> self(new AravisCamera());
  self->options_ = options;
  const std::string& id = options.address.empty() ? options.serial : options.address;
  GError* error = nullptr;
  // An IPv4 address opens the camera directly over GVCP; a serial goes through discovery.
  ArvCamera* camera = arv_camera_new(id.c_str(), &error);
  if (camera == nullptr) return Check(error, "cannot open GigE Vision camera '" + id + "'").error();
  self->camera_ = camera;
  g_signal_connect(arv_camera_get_device(camera), "control-lost", G_CALLBACK(OnControlLost),
                   self->control_lost_.get());
  if (auto status = self->Configure(); !status) return status.error();
  return self;
}

AravisCamera::~AravisCamera() {
  if (camera_ != nullptr) {
    arv_camera_stop_acquisition(Cam(camera_), nullptr);
    g_signal_handlers_disconnect_by_data(arv_camera_get_device(Cam(camera_)), control_lost_.get());
  }
  if (stream_ != nullptr) g_object_unref(Stream(stream_));
  if (camera_ != nullptr) g_object_unref(Cam(camera_));
}

Status AravisCamera::Configure() {
  ArvCamera* camera = Cam(camera_);
  GError* error = nullptr;
  const char* vendor = arv_camera_get_vendor_name(camera, nullptr);
  const char* model = arv_camera_get_model_name(camera, nullptr);
  const char* serial = arv_camera_get_device_serial_number(camera, nullptr);
  description_ = std::string(vendor ? vendor : "?") + " " + (model ? model : "?") + " serial " +
                 (serial ? serial : "?");
  if (!arv_camera_is_gv_device(camera)) return Error{description_ + " is not a GigE Vision camera"};

  if (options_.width > 0 || options_.height > 0) {
    gint x = 0, y = 0, w = 0, h = 0;
    arv_camera_get_region(camera, &x, &y, &w, &h, nullptr);
    arv_camera_set_region(camera, 0, 0, options_.width > 0 ? static_cast<gint>(options_.width) : w,
                          options_.height > 0 ? static_cast<gint>(options_.height) : h, &error);
    if (auto s = Check(error, "set the frame size"); !s) return s;
  }

  const bool projected = options_.range_format == RangeFormat::kCoord3dC32f;
  if (options_.coordinate_maps && !projected) {
    return Error{"coordinate maps go with Range as Coord3D_C32f, not Coord3D_ABC32f"};
  }
  // Components (PhotoNeo: ComponentSelector + ComponentEnable; ComponentIDValue names the part).
  const ComponentChoice choices[] = {
      {ComponentRole::kRange, true},
      {ComponentRole::kIntensity, options_.intensity},
      {ComponentRole::kConfidence, options_.confidence},
      {ComponentRole::kCoordinateMapA, options_.coordinate_maps},
      {ComponentRole::kCoordinateMapB, options_.coordinate_maps},
  };
  int enabled = 0;
  roles_by_id_.clear();
  const bool has_components = HasFeature(camera, "ComponentSelector");
  for (const auto& choice : choices) {
    const char* name = ComponentRoleName(choice.role);
    if (!has_components) {
      if (choice.wanted && choice.role != ComponentRole::kRange) {
        return Error{description_ + " has no ComponentSelector: cannot enable " + name};
      }
      continue;
    }
    if (!HasEnumEntry(camera, "ComponentSelector", name)) {
      if (choice.wanted) return Error{description_ + " has no component " + name};
      continue;
    }
    arv_camera_set_string(camera, "ComponentSelector", name, &error);
    if (auto s = Check(error, std::string("ComponentSelector=") + name); !s) return s;
    arv_camera_set_boolean(camera, "ComponentEnable", choice.wanted, &error);
    if (auto s = Check(error, std::string("ComponentEnable for ") + name); !s) return s;
    if (!choice.wanted) continue;
    ++enabled;
    if (HasFeature(camera, "ComponentIDValue")) {
      const gint64 component_id = arv_camera_get_integer(camera, "ComponentIDValue", &error);
      if (auto s = Check(error, std::string("ComponentIDValue of ") + name); !s) return s;
      roles_by_id_.emplace_back(static_cast<std::uint32_t>(component_id), choice.role);
    }
  }
  // The Range format (selected component Range, when the camera has components).
  if (has_components) {
    arv_camera_set_string(camera, "ComponentSelector", "Range", &error);
    if (auto s = Check(error, "ComponentSelector=Range"); !s) return s;
  }
  const char* format = projected ? "Coord3D_C32f" : "Coord3D_ABC32f";
  if (!HasEnumEntry(camera, "PixelFormat", format)) {
    return Error{description_ + " offers no PixelFormat " + format};
  }
  arv_camera_set_string(camera, "PixelFormat", format, &error);
  if (auto s = Check(error, std::string("PixelFormat=") + format); !s) return s;
  const char* output_mode = projected ? "ProjectedC" : "CalibratedABC_Grid";
  if (HasEnumEntry(camera, "Scan3dOutputMode", output_mode)) {
    arv_camera_set_string(camera, "Scan3dOutputMode", output_mode, &error);
    if (auto s = Check(error, std::string("Scan3dOutputMode=") + output_mode); !s) return s;
  }
  if (projected) {
    const auto read = [&](const char* name, double& value) -> Status {
      if (!HasFeature(camera, name)) return Error{description_ + " has no " + std::string(name)};
      value = arv_camera_get_float(camera, name, &error);
      return Check(error, name);
    };
    if (auto s = read("Scan3dFocalLength", scan3d_.focal_length_px); !s) return s;
    if (auto s = read("Scan3dPrincipalPointU", scan3d_.principal_point_u_px); !s) return s;
    if (auto s = read("Scan3dPrincipalPointV", scan3d_.principal_point_v_px); !s) return s;
    scan3d_.aspect_ratio = 1.0;
    if (HasFeature(camera, "Scan3dAspectRatio")) {
      if (auto s = read("Scan3dAspectRatio", scan3d_.aspect_ratio); !s) return s;
    }
  }
  if (enabled > 1) {
    arv_camera_gv_set_multipart(camera, TRUE, &error);
    if (auto s = Check(error, description_ + " cannot send multipart payloads (GevSCCFGMultipart)");
        !s) {
      return s;
    }
  }
  if (options_.ptp) {
    arv_camera_set_boolean(camera, "PtpEnable", TRUE, &error);
    if (auto s = Check(error, "PtpEnable"); !s) return s;
  }
  if (options_.packet_size > 0) {
    arv_camera_gv_set_packet_size(camera, static_cast<gint>(options_.packet_size), &error);
    if (auto s = Check(error, "GevSCPSPacketSize"); !s) return s;
  }

  // Acquisition: PhotoNeo supports only Continuous; a software trigger exposes one frame.
  arv_camera_set_acquisition_mode(camera, ARV_ACQUISITION_MODE_CONTINUOUS, &error);
  if (auto s = Check(error, "AcquisitionMode=Continuous"); !s) return s;
  if (options_.trigger == TriggerMode::kSoftware) {
    arv_camera_set_trigger(camera, "Software", &error);
    if (auto s = Check(error, "software trigger (TriggerSelector/Mode/Source)"); !s) return s;
  } else {
    arv_camera_clear_triggers(camera, &error);
    if (auto s = Check(error, "TriggerMode=Off"); !s) return s;
    if (options_.frame_rate_hz > 0) {
      arv_camera_set_frame_rate(camera, options_.frame_rate_hz, &error);
      if (auto s = Check(error, "AcquisitionFrameRate"); !s) return s;
    }
  }

  gint x = 0, y = 0, w = 0, h = 0;
  arv_camera_get_region(camera, &x, &y, &w, &h, &error);
  if (auto s = Check(error, "read the frame size"); !s) return s;
  width_ = static_cast<std::uint32_t>(w);
  height_ = static_cast<std::uint32_t>(h);
  const guint payload = arv_camera_get_payload(camera, &error);
  if (auto s = Check(error, "PayloadSize"); !s) return s;

  if (options_.stream_socket == StreamSocket::kStandard)
    arv_camera_gv_set_stream_options(camera, ARV_GV_STREAM_OPTION_PACKET_SOCKET_DISABLED);
  ArvStream* stream = arv_camera_create_stream(camera, nullptr, nullptr, &error);
  if (stream == nullptr) return Check(error, "create the GVSP stream");
  stream_ = stream;
  // A UDP socket's buffer must hold a whole frame's packets while the thread catches up.
  if (options_.stream_socket == StreamSocket::kStandard) {
    g_object_set(stream, "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_AUTO, "socket-buffer-size", 0,
                 nullptr);
  }
  // Buffers allocated once, recycled for the life of the connection.
  for (int i = 0; i < options_.buffers; ++i)
    arv_stream_push_buffer(stream, arv_buffer_new(payload, nullptr));
  parts_.reserve(8);
  arv_camera_start_acquisition(camera, &error);
  return Check(error, "AcquisitionStart");
}

Status AravisCamera::Trigger() {
  GError* error = nullptr;
  arv_camera_software_trigger(Cam(camera_), &error);
  return Check(error, "TriggerSoftware");
}

Expected<bool> AravisCamera::NextCloud(std::chrono::milliseconds timeout, CloudStorage& storage,
                                       FrameInfo& info) {
  ArvBuffer* buffer =
      arv_stream_timeout_pop_buffer(Stream(stream_), static_cast<guint64>(timeout.count()) * 1000u);
  if (buffer == nullptr) return false;
  // Give the buffer back to the stream whatever happens below.
  struct Requeue {
    ArvStream* stream;
    ArvBuffer* buffer;
    ~Requeue() { arv_stream_push_buffer(stream, buffer); }
  } requeue{Stream(stream_), buffer};

  info.frame_id = arv_buffer_get_frame_id(buffer);
  const ArvBufferStatus status = arv_buffer_get_status(buffer);
  if (status != ARV_BUFFER_STATUS_SUCCESS) {
    ++counters_.incomplete;
    last_drop_reason_ = "frame " + std::to_string(info.frame_id) + ": " + BufferStatusName(status);
    return false;
  }
  info.device_timestamp_ns = arv_buffer_get_timestamp(buffer);
  info.system_timestamp_ns = arv_buffer_get_system_timestamp(buffer);

  parts_.clear();
  const guint n_parts = arv_buffer_get_n_parts(buffer);
  for (guint i = 0; i < n_parts && parts_.size() < parts_.capacity(); ++i) {
    size_t size = 0;
    const void* data = arv_buffer_get_part_data(buffer, i, &size);
    camera::ImagePart part;
    part.pixel_format = arv_buffer_get_part_pixel_format(buffer, i);
    const gint w = arv_buffer_get_part_width(buffer, i);
    const gint h = arv_buffer_get_part_height(buffer, i);
    part.width = static_cast<std::uint32_t>(std::max(w, 0));
    part.height = static_cast<std::uint32_t>(std::max(h, 0));
    gint x_padding = 0, y_padding = 0;
    arv_buffer_get_part_padding(buffer, i, &x_padding, &y_padding);
    part.x_padding = static_cast<std::uint32_t>(std::max(x_padding, 0));
    part.data = {static_cast<const std::uint8_t*>(data), data ? size : 0};
    part.role = camera::ClassifyByPixelFormat(part.pixel_format);
    if (n_parts > 1) {
      const guint component_id = arv_buffer_get_part_component_id(buffer, i);
      for (const auto& [id, role] : roles_by_id_) {
        if (id == component_id) part.role = role;
      }
    }
    parts_.push_back(part);
  }
  const camera::ImagePart* range = nullptr;
  for (const auto& part : parts_) {
    if (part.role == ComponentRole::kRange) range = &part;
  }
  if (range == nullptr) {
    ++counters_.corrupted;
    last_drop_reason_ = "frame " + std::to_string(info.frame_id) + ": no Range part";
    return false;
  }
  const std::size_t count = static_cast<std::size_t>(range->width) * range->height;
  for (auto* v : {&storage.x, &storage.y, &storage.z}) {
    if (v->size() != count) v->resize(count);
  }
  const bool want_intensity = options_.intensity;
  if (storage.intensity.size() != (want_intensity ? count : 0))
    storage.intensity.resize(want_intensity ? count : 0);
  auto summary = camera::DecodeOrganizedCloud(
      parts_, scan3d_, options_.decode,
      {range->width, range->height, storage.x, storage.y, storage.z, storage.intensity});
  if (!summary) {
    ++counters_.corrupted;
    last_drop_reason_ = "frame " + std::to_string(info.frame_id) + ": " + summary.error().message;
    return false;
  }
  ++counters_.decoded;
  info.width = range->width;
  info.height = range->height;
  info.summary = *summary;
  return true;
}

}  // namespace selfcal::aravis

#include "tools/sim_cameras/fake_gev_camera.h"

#include <arpa/inet.h>
#include <arv.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "protocols/camera/gvsp.h"
#include "protocols/camera/pixel_format.h"

namespace selfcal::sim_cameras {
namespace {

namespace pfnc = camera::pfnc;

// IP (20) + UDP (8) + extended-id GVSP header (20) + multipart fields (part id, offset: 8 bytes).
constexpr std::size_t kMultipartOverhead = 56;

std::string Entry(const char* name, std::uint32_t value) {
  return std::string("\t\t<EnumEntry Name=\"") + name +
         "\" NameSpace=\"Standard\">\n\t\t\t<Value>" + std::to_string(value) +
         "</Value>\n\t\t</EnumEntry>\n";
}

std::string IntReg(const std::string& name, std::uint32_t address, const char* access,
                   const char* index = nullptr) {
  char text[512];
  std::snprintf(
      text, sizeof(text),
      "\t<IntReg Name=\"%s\" NameSpace=\"Custom\">\n\t\t<Address>0x%x</Address>\n%s"
      "\t\t<Length>4</Length>\n\t\t<AccessMode>%s</AccessMode>\n\t\t<pPort>Device</pPort>\n"
      "\t\t<Sign>Unsigned</Sign>\n\t\t<Endianess>BigEndian</Endianess>\n\t</IntReg>\n",
      name.c_str(), address,
      index ? (std::string("\t\t<pIndex Offset=\"4\">") + index + "</pIndex>\n").c_str() : "",
      access);
  return text;
}

std::string FloatFeature(const std::string& name, std::uint32_t address) {
  char text[640];
  std::snprintf(
      text, sizeof(text),
      "\t<Float Name=\"%s\" NameSpace=\"Standard\">\n\t\t<pValue>%sReg</pValue>\n\t</Float>\n"
      "\t<FloatReg Name=\"%sReg\" NameSpace=\"Custom\">\n\t\t<Address>0x%x</Address>\n"
      "\t\t<Length>8</Length>\n\t\t<AccessMode>RO</AccessMode>\n\t\t<pPort>Device</pPort>\n"
      "\t\t<Endianess>BigEndian</Endianess>\n\t</FloatReg>\n",
      name.c_str(), name.c_str(), name.c_str(), address);
  return text;
}

// Our features, PhotoNeo's names (GenICam SFNC 3D extensions).
std::string OurFeatures() {
  using namespace fake_gev;
  std::string xml = "\t<!-- selfcal: PhotoNeo-like components and Scan3d features -->\n";
  xml +=
      "\t<Category Name=\"ComponentControl\" NameSpace=\"Standard\">\n"
      "\t\t<pFeature>ComponentSelector</pFeature>\n\t\t<pFeature>ComponentEnable</pFeature>\n"
      "\t\t<pFeature>ComponentIDValue</pFeature>\n\t</Category>\n"
      "\t<Category Name=\"Scan3dControl\" NameSpace=\"Standard\">\n"
      "\t\t<pFeature>Scan3dOutputMode</pFeature>\n\t\t<pFeature>Scan3dFocalLength</pFeature>\n"
      "\t\t<pFeature>Scan3dPrincipalPointU</pFeature>\n\t\t<pFeature>Scan3dPrincipalPointV</"
      "pFeature>\n"
      "\t\t<pFeature>Scan3dAspectRatio</pFeature>\n\t</Category>\n";
  xml += "\t<Enumeration Name=\"ComponentSelector\" NameSpace=\"Standard\">\n" +
         Entry("Intensity", kIntensity) + Entry("Range", kRange) +
         Entry("Confidence", kConfidence) +
         "\t\t<pValue>ComponentSelectorReg</pValue>\n\t</Enumeration>\n";
  xml += IntReg("ComponentSelectorReg", kComponentSelector, "RW");
  xml +=
      "\t<Boolean Name=\"ComponentEnable\" NameSpace=\"Standard\">\n"
      "\t\t<pValue>ComponentEnableReg</pValue>\n\t\t<OnValue>1</OnValue>\n\t\t<OffValue>0</"
      "OffValue>\n"
      "\t</Boolean>\n";
  xml += IntReg("ComponentEnableReg", kComponentEnable, "RW", "ComponentSelectorReg");
  xml +=
      "\t<Integer Name=\"ComponentIDValue\" NameSpace=\"Standard\">\n"
      "\t\t<pValue>ComponentIDValueReg</pValue>\n\t</Integer>\n";
  xml += IntReg("ComponentIDValueReg", kComponentId, "RO", "ComponentSelectorReg");
  xml += "\t<Enumeration Name=\"Scan3dOutputMode\" NameSpace=\"Standard\">\n" +
         Entry("CalibratedABC_Grid", 0) + Entry("ProjectedC", 1) +
         "\t\t<pValue>Scan3dOutputModeReg</pValue>\n\t</Enumeration>\n";
  xml += IntReg("Scan3dOutputModeReg", kScan3dOutputMode, "RW");
  xml += FloatFeature("Scan3dFocalLength", kScan3dFocalLength);
  xml += FloatFeature("Scan3dPrincipalPointU", kScan3dPrincipalPointU);
  xml += FloatFeature("Scan3dPrincipalPointV", kScan3dPrincipalPointV);
  xml += FloatFeature("Scan3dAspectRatio", kScan3dAspectRatio);
  return xml;
}

Status InsertBefore(std::string& xml, const std::string& anchor, const std::string& text) {
  const auto at = xml.find(anchor);
  if (at == std::string::npos) {
    return Error{"libaravis' fake camera XML lacks '" + anchor + "' (aravis version changed?)"};
  }
  xml.insert(at, text);
  return OkStatus();
}

void WriteDouble(ArvFakeCamera* camera, std::uint32_t address, double value) {
  std::uint64_t bits;
  std::memcpy(&bits, &value, sizeof(bits));
  unsigned char bytes[8];
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<unsigned char>(bits >> (56 - 8 * i));
  arv_fake_camera_write_memory(camera, address, 8, bytes);
}

}  // namespace

Expected<std::string> BuildFakeGevGenicamXml(bool multipart) {
  ArvFakeCamera* reference = arv_fake_camera_new("xml");
  size_t size = 0;
  const char* base = arv_fake_camera_get_genicam_xml(reference, &size);
  std::string xml = base ? std::string(base, size) : std::string();
  g_object_unref(reference);
  if (xml.empty()) return Error{"libaravis returned no fake camera XML"};
  const std::string formats = Entry("Coord3D_ABC32f", pfnc::kCoord3dAbc32f) +
                              Entry("Coord3D_C32f", pfnc::kCoord3dC32f) +
                              Entry("Confidence8", pfnc::kConfidence8);
  if (auto s = InsertBefore(xml, "\t\t<pValue>PixelFormatRegister</pValue>", formats); !s)
    return s.error();
  if (auto s = InsertBefore(
          xml, "\t\t<pFeature>TransportLayerControl</pFeature>",
          "\t\t<pFeature>ComponentControl</pFeature>\n\t\t<pFeature>Scan3dControl</pFeature>\n");
      !s) {
    return s.error();
  }
  if (auto s = InsertBefore(xml, "\t<!-- Port -->", OurFeatures()); !s) return s.error();
  if (multipart) {
    using namespace fake_gev;
    const std::string formula =
        "<Formula>WIDTH * HEIGHT * ((PIXELFORMAT>>16)&amp;0xFF) / 8</Formula>";
    const auto at = xml.find(formula);
    if (at == std::string::npos)
      return Error{"libaravis' fake camera XML lacks the PayloadSize formula"};
    xml.replace(at, formula.size(),
                "<pVariable Name=\"INTENSITY\">IntensityEnableReg</pVariable>\n"
                "\t\t<pVariable Name=\"CONFIDENCE\">ConfidenceEnableReg</pVariable>\n"
                "\t\t<Formula>WIDTH * HEIGHT * (((PIXELFORMAT>>16)&amp;0xFF) / 8 + 2 * INTENSITY + "
                "CONFIDENCE)"
                "</Formula>");
    if (auto s = InsertBefore(
            xml, "\t<!-- Port -->",
            IntReg("IntensityEnableReg", kComponentEnable + 4 * kIntensity, "RO") +
                IntReg("ConfidenceEnableReg", kComponentEnable + 4 * kConfidence, "RO"));
        !s) {
      return s.error();
    }
  }
  return xml;
}

FakeGevCamera::FakeGevCamera(const FakeGevCameraOptions& options) : options_(options) {
  noise_.resize(1 << 16);
  for (std::size_t i = 0; i < noise_.size(); ++i) {
    noise_[i] = static_cast<float>(GaussianNoise(0x5E1FCA1, i));
  }
}

FakeGevCamera::~FakeGevCamera() {
  if (multipart_fd_ >= 0) ::close(multipart_fd_);
  if (gv_camera_ != nullptr) g_object_unref(static_cast<ArvGvFakeCamera*>(gv_camera_));
  if (!xml_path_.empty()) ::unlink(xml_path_.c_str());
}

Expected<std::unique_ptr<FakeGevCamera>> FakeGevCamera::Start(const FakeGevCameraOptions& options) {
  auto xml = BuildFakeGevGenicamXml(options.multipart);
  if (!xml) return xml.error();
  std::unique_ptr<FakeGevCamera> camera(new FakeGevCamera(options));
  char path[] = "/tmp/selfcal-fake-gev-XXXXXX.xml";
  const int fd = ::mkstemps(path, 4);
  if (fd < 0) return Error{"cannot create a temporary GenICam file in /tmp"};
  const bool written = ::write(fd, xml->data(), xml->size()) == static_cast<ssize_t>(xml->size());
  ::close(fd);
  camera->xml_path_ = path;
  if (!written) return Error{std::string("cannot write ") + path};

  ArvGvFakeCamera* gv = arv_gv_fake_camera_new_full(options.address.c_str(), options.serial.c_str(),
                                                    camera->xml_path_.c_str());
  if (gv == nullptr || !arv_gv_fake_camera_is_running(gv)) {
    if (gv != nullptr) g_object_unref(gv);
    return Error{"cannot start the fake GigE Vision camera on " + options.address +
                 " (GVCP port 3956 in use, or the address is not local)"};
  }
  camera->gv_camera_ = gv;
  if (options.multipart) {
    // libaravis' own stream goes nowhere; ours carries the frames (see the header).
    g_object_set(gv, "gvsp-lost-ratio", 1.0, nullptr);
    camera->multipart_fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (camera->multipart_fd_ < 0) return Error{"cannot create the multipart GVSP socket"};
  } else if (options.packet_loss_ratio > 0.0) {
    g_object_set(gv, "gvsp-lost-ratio", options.packet_loss_ratio, nullptr);
  }
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(gv);
  using namespace fake_gev;
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_WIDTH, options.width);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_HEIGHT, options.height);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_PIXEL_FORMAT, pfnc::kCoord3dAbc32f);
  arv_fake_camera_write_register(fake, ARV_FAKE_CAMERA_REGISTER_ACQUISITION_FRAME_PERIOD_US,
                                 static_cast<std::uint32_t>(1e6 / options.frame_rate_hz));
  arv_fake_camera_write_register(fake, kComponentEnable + 4 * kRange, 1);
  arv_fake_camera_write_register(fake, kComponentId + 4 * kIntensity, kIntensityId);
  arv_fake_camera_write_register(fake, kComponentId + 4 * kRange, kRangeId);
  arv_fake_camera_write_register(fake, kComponentId + 4 * kConfidence, kConfidenceId);
  arv_fake_camera_write_register(fake, kComponentSelector, kRange);
  WriteDouble(fake, kScan3dFocalLength, options.intrinsics.fx);
  WriteDouble(fake, kScan3dPrincipalPointU, options.intrinsics.cx);
  WriteDouble(fake, kScan3dPrincipalPointV, options.intrinsics.cy);
  WriteDouble(fake, kScan3dAspectRatio, options.intrinsics.fy / options.intrinsics.fx);
  if (!options.frame_depth) camera->UpdateTruth(options.width, options.height);
  arv_fake_camera_set_fill_pattern(
      fake,
      [](ArvBuffer* buffer, void* self, guint32 exposure, guint32 gain, ArvPixelFormat format) {
        Fill(buffer, self, exposure, gain, format);
      },
      camera.get());
  return camera;
}

void FakeGevCamera::UpdateTruth(std::uint32_t width, std::uint32_t height) {
  if (width == truth_width_ && height == truth_height_) return;
  truth_depth_m_.resize(static_cast<std::size_t>(width) * height);
  if (options_.depth_map) {
    truth_depth_m_ = options_.depth_map(width, height);
    truth_depth_m_.resize(static_cast<std::size_t>(width) * height, 0.0f);
    truth_width_ = width;
    truth_height_ = height;
    return;
  }
  for (std::uint32_t v = 0; v < height; ++v) {
    for (std::uint32_t u = 0; u < width; ++u) {
      truth_depth_m_[static_cast<std::size_t>(v) * width + u] =
          static_cast<float>(options_.scene.DepthAt(u, v, options_.intrinsics));
    }
  }
  truth_width_ = width;
  truth_height_ = height;
}

void FakeGevCamera::Fill(void* buffer_pointer, void* self_pointer, std::uint32_t, std::uint32_t,
                         std::uint32_t pixel_format) {
  auto* buffer = static_cast<ArvBuffer*>(buffer_pointer);
  auto* self = static_cast<FakeGevCamera*>(self_pointer);
  const auto width = static_cast<std::uint32_t>(arv_buffer_get_image_width(buffer));
  const auto height = static_cast<std::uint32_t>(arv_buffer_get_image_height(buffer));
  if (!self->options_.frame_depth) self->UpdateTruth(width, height);
  size_t ignored = 0;  // libaravis reports 0 here: the size follows from the format
  auto* data = static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, &ignored)));
  const std::uint64_t frame = arv_buffer_get_frame_id(buffer);
  const auto& k = self->options_.intrinsics;
  const auto sigma = static_cast<float>(self->options_.noise_sigma_m);
  const std::size_t noise_mask = self->noise_.size() - 1;
  const std::size_t noise_start = static_cast<std::size_t>(frame * 7919u);
  const bool field = static_cast<bool>(self->options_.frame_depth);
  if (field) {
    const std::chrono::duration<double> since_start =
        std::chrono::steady_clock::now() - self->started_;
    self->options_.frame_depth(frame, since_start.count(), width, height, self->frame_depth_m_);
    self->frame_depth_m_.resize(static_cast<std::size_t>(width) * height, 0.0f);
  }
  const std::vector<float>& depth = field ? self->frame_depth_m_ : self->truth_depth_m_;
  for (std::uint32_t v = 0; v < height; ++v) {
    for (std::uint32_t u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      const float truth = depth[i];
      const float noise = field ? 0.0f : sigma * self->noise_[(noise_start + i) & noise_mask];
      const float z = truth > 0.0f ? truth + noise : 0.0f;
      const float z_mm = 1000.0f * z;
      switch (pixel_format) {
        case pfnc::kCoord3dAbc32f: {
          // Invalid points are (0, 0, 0), as PhotoNeo sends them.
          const Eigen::Vector3d ray = k.Unproject(u, v, 1.0);
          const float xyz[3] = {z_mm * static_cast<float>(ray.x()),
                                z_mm * static_cast<float>(ray.y()), z_mm};
          std::memcpy(data + 12 * i, xyz, sizeof(xyz));
          break;
        }
        case pfnc::kCoord3dC32f:
          std::memcpy(data + 4 * i, &z_mm, 4);
          break;
        case pfnc::kConfidence8:
          data[i] = truth > 0.0f ? 255 : 0;
          break;
        case pfnc::kMono16: {
          const auto value = static_cast<std::uint16_t>(truth > 0.0f ? 4000.0f * truth : 0.0f);
          std::memcpy(data + 2 * i, &value, 2);
          break;
        }
        default:
          data[i * camera::BitsPerPixel(pixel_format) / 8] = static_cast<std::uint8_t>(u + v);
      }
    }
  }
  if (self->options_.multipart) {
    self->SendMultipart(frame, arv_buffer_get_timestamp(buffer), pixel_format, data, width, height);
  }
  self->frames_served_.fetch_add(1);
}

void FakeGevCamera::SendMultipart(std::uint64_t frame_id, std::uint64_t timestamp_ns,
                                  std::uint32_t range_format, const std::uint8_t* range,
                                  std::uint32_t width, std::uint32_t height) {
  using namespace fake_gev;
  auto* fake = arv_gv_fake_camera_get_fake_camera(static_cast<ArvGvFakeCamera*>(gv_camera_));
  const auto enabled = [&](std::uint32_t selector) {
    guint32 value = 0;
    arv_fake_camera_read_register(fake, kComponentEnable + 4 * selector, &value);
    return value != 0;
  };
  const std::size_t count = static_cast<std::size_t>(width) * height;
  if (range_format != pfnc::kCoord3dAbc32f && range_format != pfnc::kCoord3dC32f) return;
  intensity_.resize(2 * count);
  confidence_.resize(count);
  const std::vector<float>& depth = options_.frame_depth ? frame_depth_m_ : truth_depth_m_;
  for (std::size_t i = 0; i < count; ++i) {
    const float truth = depth[i];
    // Intensity: a gradient over the image, so that tests can check which pixel it came from.
    const auto value = static_cast<std::uint16_t>(i % 65536);
    std::memcpy(&intensity_[2 * i], &value, 2);
    // Confidence 0 (invalid) outside the view range and, so that a client's use of the
    // Confidence part shows, on the image diagonal u == v.
    const bool diagonal = i % width == i / width;
    confidence_[i] = truth > 0.0f && !diagonal ? 255 : 0;
  }
  camera::GvspLeader leader;
  leader.payload_type = camera::kGvspPayloadMultipart;
  leader.timestamp = timestamp_ns;
  std::vector<std::span<const std::uint8_t>> bytes;
  const auto add = [&](std::uint32_t format, std::uint32_t id, std::span<const std::uint8_t> data) {
    camera::GvspPartInfo part;
    part.length = data.size();
    part.pixel_format = format;
    part.data_purpose_id = static_cast<std::uint16_t>(id);
    part.width = width;
    part.height = height;
    leader.parts.push_back(part);
    bytes.push_back(data);
  };
  // Increasing component id: Intensity (1), Range (2), Confidence (6).
  if (enabled(kIntensity)) add(pfnc::kMono16, kIntensityId, intensity_);
  add(range_format, kRangeId, {range, count * (range_format == pfnc::kCoord3dAbc32f ? 12u : 4u)});
  if (enabled(kConfidence)) add(pfnc::kConfidence8, kConfidenceId, confidence_);
  const auto block_id = static_cast<std::uint16_t>(frame_id % 0xFFFF + 1);  // replaced below
  // Payload bytes per packet follow the packet size the client negotiated (GevSCPSPacketSize,
  // bootstrap register 0x0d04, low 16 bits) minus IP, UDP and GVSP headers, as receivers expect.
  guint32 packet_size = 0;
  arv_fake_camera_read_register(fake, 0x0d04, &packet_size);
  packet_size &= 0xFFFF;
  const std::size_t block_bytes = packet_size > 100 ? packet_size - kMultipartOverhead : 1024;
  // Multipart needs extended ids (GigE Vision 2): camera::ToExtendedIds; the block id is 64 bits.
  std::vector<std::vector<std::uint8_t>> packets =
      camera::PacketizeGvspBlock(block_id, leader, bytes, block_bytes);
  for (auto& packet : packets) packet = camera::ToExtendedIds(packet, frame_id + 1);
  GSocketAddress* address = arv_fake_camera_get_stream_address(fake);
  if (address == nullptr) return;
  sockaddr_in destination{};
  const bool ok = g_socket_address_to_native(address, &destination, sizeof destination, nullptr);
  g_object_unref(address);
  if (!ok) return;
  for (const auto& packet : packets) {
    (void)::sendto(multipart_fd_, packet.data(), packet.size(), 0,
                   reinterpret_cast<const sockaddr*>(&destination), sizeof destination);
  }
}

}  // namespace selfcal::sim_cameras

#include "tools/sim_cameras/fake_gev_camera.h"

#include <arv.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "protocols/camera/pixel_format.h"

namespace selfcal::sim_cameras {
namespace {

namespace pfnc = camera::pfnc;

std::string Entry(const char* name, std::uint32_t value) {
  return std::string("\t\t<EnumEntry Name=\"") + name + "\" NameSpace=\"Standard\">\n\t\t\t<Value>" +
         std::to_string(value) + "</Value>\n\t\t</EnumEntry>\n";
}

std::string IntReg(const std::string& name, std::uint32_t address, const char* access,
                   const char* index = nullptr) {
  char text[512];
  std::snprintf(text, sizeof(text),
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
  std::snprintf(text, sizeof(text),
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
      "\t\t<pFeature>Scan3dPrincipalPointU</pFeature>\n\t\t<pFeature>Scan3dPrincipalPointV</pFeature>\n"
      "\t\t<pFeature>Scan3dAspectRatio</pFeature>\n\t</Category>\n";
  xml += "\t<Enumeration Name=\"ComponentSelector\" NameSpace=\"Standard\">\n" +
         Entry("Intensity", kIntensity) + Entry("Range", kRange) + Entry("Confidence", kConfidence) +
         "\t\t<pValue>ComponentSelectorReg</pValue>\n\t</Enumeration>\n";
  xml += IntReg("ComponentSelectorReg", kComponentSelector, "RW");
  xml +=
      "\t<Boolean Name=\"ComponentEnable\" NameSpace=\"Standard\">\n"
      "\t\t<pValue>ComponentEnableReg</pValue>\n\t\t<OnValue>1</OnValue>\n\t\t<OffValue>0</OffValue>\n"
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

Expected<std::string> BuildFakeGevGenicamXml() {
  ArvFakeCamera* reference = arv_fake_camera_new("xml");
  size_t size = 0;
  const char* base = arv_fake_camera_get_genicam_xml(reference, &size);
  std::string xml = base ? std::string(base, size) : std::string();
  g_object_unref(reference);
  if (xml.empty()) return Error{"libaravis returned no fake camera XML"};
  const std::string formats = Entry("Coord3D_ABC32f", pfnc::kCoord3dAbc32f) +
                              Entry("Coord3D_C32f", pfnc::kCoord3dC32f) +
                              Entry("Confidence8", pfnc::kConfidence8);
  if (auto s = InsertBefore(xml, "\t\t<pValue>PixelFormatRegister</pValue>", formats); !s) return s.error();
  if (auto s = InsertBefore(xml, "\t\t<pFeature>TransportLayerControl</pFeature>",
                            "\t\t<pFeature>ComponentControl</pFeature>\n\t\t<pFeature>Scan3dControl</pFeature>\n");
      !s) {
    return s.error();
  }
  if (auto s = InsertBefore(xml, "\t<!-- Port -->", OurFeatures()); !s) return s.error();
  return xml;
}

FakeGevCamera::FakeGevCamera(const FakeGevCameraOptions& options) : options_(options) {
  noise_.resize(1 << 16);
  for (std::size_t i = 0; i < noise_.size(); ++i) {
    noise_[i] = static_cast<float>(GaussianNoise(0x5E1FCA1, i));
  }
}

FakeGevCamera::~FakeGevCamera() {
  if (gv_camera_ != nullptr) g_object_unref(static_cast<ArvGvFakeCamera*>(gv_camera_));
  if (!xml_path_.empty()) ::unlink(xml_path_.c_str());
}

Expected<std::unique_ptr<FakeGevCamera>> FakeGevCamera::Start(const FakeGevCameraOptions& options) {
  auto xml = BuildFakeGevGenicamXml();
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
  if (options.packet_loss_ratio > 0.0) {
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
  camera->UpdateTruth(options.width, options.height);
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
  self->UpdateTruth(width, height);
  size_t ignored = 0;  // libaravis reports 0 here: the size follows from the format
  auto* data = static_cast<std::uint8_t*>(const_cast<void*>(arv_buffer_get_data(buffer, &ignored)));
  const std::uint64_t frame = arv_buffer_get_frame_id(buffer);
  const auto& k = self->options_.intrinsics;
  const auto sigma = static_cast<float>(self->options_.noise_sigma_m);
  const std::size_t noise_mask = self->noise_.size() - 1;
  const std::size_t noise_start = static_cast<std::size_t>(frame * 7919u);
  for (std::uint32_t v = 0; v < height; ++v) {
    for (std::uint32_t u = 0; u < width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * width + u;
      const float truth = self->truth_depth_m_[i];
      const float z = truth > 0.0f ? truth + sigma * self->noise_[(noise_start + i) & noise_mask] : 0.0f;
      const float z_mm = 1000.0f * z;
      switch (pixel_format) {
        case pfnc::kCoord3dAbc32f: {
          // Invalid points are (0, 0, 0), as PhotoNeo sends them.
          const float xyz[3] = {z_mm * static_cast<float>((u - k.cx) / k.fx),
                                z_mm * static_cast<float>((v - k.cy) / k.fy), z_mm};
          std::memcpy(data + 12 * i, xyz, sizeof(xyz));
          break;
        }
        case pfnc::kCoord3dC32f: std::memcpy(data + 4 * i, &z_mm, 4); break;
        case pfnc::kConfidence8: data[i] = truth > 0.0f ? 255 : 0; break;
        case pfnc::kMono16: {
          const auto value = static_cast<std::uint16_t>(truth > 0.0f ? 4000.0f * truth : 0.0f);
          std::memcpy(data + 2 * i, &value, 2);
          break;
        }
        default: data[i * camera::BitsPerPixel(pixel_format) / 8] = static_cast<std::uint8_t>(u + v);
      }
    }
  }
  self->frames_served_.fetch_add(1);
}

}  // namespace selfcal::sim_cameras

#include "drivers/v4l2/v4l2_camera.h"

#include <linux/videodev2.h>
#include <sys/mman.h>

#include <bit>
#include <cerrno>
#include <cstring>
#include <ctime>

#include "core/timing/host_clock.h"

namespace selfcal::v4l2 {
namespace {

// Z16 pixels are little-endian; NextFrame() copies whole lines into 16-bit values (x86-64 and
// arm64 Linux are both little-endian).
static_assert(std::endian::native == std::endian::little, "Z16 lines are copied as they are");

std::string FourCc(std::uint32_t code) {
  std::string text(4, ' ');
  for (int i = 0; i < 4; ++i)
    text[static_cast<std::size_t>(i)] = static_cast<char>((code >> (8 * i)) & 0xFF);
  return text;
}

}  // namespace

Expected<std::unique_ptr<V4l2Camera>> V4l2Camera::Open(V4l2Io& io, const CameraOptions& options) {
  std::unique_ptr<V4l2Camera> self(new V4l2Camera(io));
  self->device_ = options.device;
  self->fd_ = io.Open(options.device);
  if (self->fd_ < 0) return Error{"cannot open " + options.device + ": " + std::strerror(errno)};
  if (auto status = self->Negotiate(options); !status) return status.error();
  if (auto status = self->StartStreaming(options.buffers); !status) return status.error();
  return self;
}

V4l2Camera::~V4l2Camera() {
  if (streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    io_.Ioctl(fd_, VIDIOC_STREAMOFF, &type);
  }
  for (const auto& mapping : mappings_) io_.Munmap(mapping.address, mapping.length);
  if (fd_ >= 0) io_.Close(fd_);
}

Status V4l2Camera::Negotiate(const CameraOptions& options) {
  const auto fail = [&](const std::string& what) {
    return Error{device_ + ": " + what + (errno ? std::string(": ") + std::strerror(errno) : "")};
  };
  v4l2_capability capability{};
  errno = 0;
  if (io_.Ioctl(fd_, VIDIOC_QUERYCAP, &capability) < 0)
    return fail("VIDIOC_QUERYCAP failed (not a V4L2 device?)");
  const std::uint32_t caps = (capability.capabilities & V4L2_CAP_DEVICE_CAPS)
                                 ? capability.device_caps
                                 : capability.capabilities;
  errno = 0;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE)) return fail("is not a video capture device");
  if (!(caps & V4L2_CAP_STREAMING)) return fail("does not support streaming I/O");

  // Z16 must be on offer; name what is offered otherwise.
  std::string offered;
  bool has_z16 = false;
  for (std::uint32_t index = 0; index < 64; ++index) {
    v4l2_fmtdesc description{};
    description.index = index;
    description.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (io_.Ioctl(fd_, VIDIOC_ENUM_FMT, &description) < 0) break;
    offered += (offered.empty() ? "" : ", ") + FourCc(description.pixelformat);
    has_z16 = has_z16 || description.pixelformat == V4L2_PIX_FMT_Z16;
  }
  errno = 0;
  if (!has_z16)
    return fail("offers no Z16 depth format (offers: " + (offered.empty() ? "none" : offered) +
                ")");

  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (io_.Ioctl(fd_, VIDIOC_G_FMT, &format) < 0) return fail("VIDIOC_G_FMT failed");
  if (options.width > 0) format.fmt.pix.width = options.width;
  if (options.height > 0) format.fmt.pix.height = options.height;
  format.fmt.pix.pixelformat = V4L2_PIX_FMT_Z16;
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (io_.Ioctl(fd_, VIDIOC_S_FMT, &format) < 0) return fail("VIDIOC_S_FMT to Z16 failed");
  // The driver may adjust what we asked for: take what it reports, but only Z16.
  errno = 0;
  if (format.fmt.pix.pixelformat != V4L2_PIX_FMT_Z16) {
    return fail("answered VIDIOC_S_FMT with " + FourCc(format.fmt.pix.pixelformat) +
                " instead of Z16");
  }
  if (format.fmt.pix.width == 0 || format.fmt.pix.height == 0 ||
      format.fmt.pix.bytesperline < 2 * format.fmt.pix.width) {
    return fail("reports an inconsistent Z16 format: " + std::to_string(format.fmt.pix.width) +
                "x" + std::to_string(format.fmt.pix.height) + ", " +
                std::to_string(format.fmt.pix.bytesperline) + " bytes per line");
  }
  format_.width = format.fmt.pix.width;
  format_.height = format.fmt.pix.height;
  format_.bytes_per_line = format.fmt.pix.bytesperline;

  v4l2_streamparm parameters{};
  parameters.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (options.fps > 0) {
    parameters.parm.capture.timeperframe = {1, options.fps};
    if (io_.Ioctl(fd_, VIDIOC_S_PARM, &parameters) < 0)
      return fail("VIDIOC_S_PARM (frame rate) failed");
  } else if (io_.Ioctl(fd_, VIDIOC_G_PARM, &parameters) < 0) {
    parameters = {};
  }
  const auto& period = parameters.parm.capture.timeperframe;
  format_.fps = period.numerator > 0 ? period.denominator / period.numerator : 0;
  return OkStatus();
}

Status V4l2Camera::StartStreaming(std::uint32_t count) {
  const auto fail = [&](const std::string& what) {
    return Error{device_ + ": " + what + (errno ? std::string(": ") + std::strerror(errno) : "")};
  };
  v4l2_requestbuffers request{};
  request.count = count;
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  errno = 0;
  if (io_.Ioctl(fd_, VIDIOC_REQBUFS, &request) < 0) return fail("VIDIOC_REQBUFS (mmap) failed");
  if (request.count < 2)
    return fail("granted " + std::to_string(request.count) + " buffers, need 2");
  const std::size_t frame_bytes = static_cast<std::size_t>(format_.bytes_per_line) * format_.height;
  for (std::uint32_t index = 0; index < request.count; ++index) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = index;
    errno = 0;
    if (io_.Ioctl(fd_, VIDIOC_QUERYBUF, &buffer) < 0)
      return fail("VIDIOC_QUERYBUF " + std::to_string(index) + " failed");
    if (buffer.length < frame_bytes) {
      return fail("buffer " + std::to_string(index) + " holds " + std::to_string(buffer.length) +
                  " bytes, a frame needs " + std::to_string(frame_bytes));
    }
    void* address = io_.Mmap(buffer.length, fd_, static_cast<off_t>(buffer.m.offset));
    if (address == MAP_FAILED) return fail("mmap of buffer " + std::to_string(index) + " failed");
    mappings_.push_back({address, buffer.length});
    if (io_.Ioctl(fd_, VIDIOC_QBUF, &buffer) < 0)
      return fail("VIDIOC_QBUF " + std::to_string(index) + " failed");
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  errno = 0;
  if (io_.Ioctl(fd_, VIDIOC_STREAMON, &type) < 0) return fail("VIDIOC_STREAMON failed");
  streaming_ = true;
  return OkStatus();
}

Expected<bool> V4l2Camera::NextFrame(int timeout_ms, std::vector<std::int16_t>& depth,
                                     Frame& frame) {
  const int ready = io_.Poll(fd_, timeout_ms);
  if (ready < 0) return Error{device_ + ": poll failed: " + std::strerror(errno)};
  if (ready == 0) return false;
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  if (io_.Ioctl(fd_, VIDIOC_DQBUF, &buffer) < 0) {
    if (errno == EAGAIN) return false;
    return Error{device_ + ": VIDIOC_DQBUF failed: " + std::strerror(errno)};
  }
  if (buffer.index >= mappings_.size()) {
    return Error{device_ + ": VIDIOC_DQBUF returned buffer " + std::to_string(buffer.index) +
                 " of " + std::to_string(mappings_.size())};
  }
  const std::size_t frame_bytes = static_cast<std::size_t>(format_.bytes_per_line) * format_.height;
  bool ok = true;
  if ((buffer.flags & V4L2_BUF_FLAG_ERROR) != 0 || buffer.bytesused < frame_bytes) {
    ++counters_.dropped;
    ok = false;
  } else {
    counters_.sequence_gaps += static_cast<std::uint64_t>(sequence_.Update(buffer.sequence).lost);
    const std::size_t count = static_cast<std::size_t>(format_.width) * format_.height;
    if (depth.size() != count) depth.resize(count);
    const auto* bytes = static_cast<const std::uint8_t*>(mappings_[buffer.index].address);
    for (std::uint32_t row = 0; row < format_.height; ++row) {
      std::memcpy(depth.data() + static_cast<std::size_t>(row) * format_.width,
                  bytes + static_cast<std::size_t>(row) * format_.bytes_per_line,
                  static_cast<std::size_t>(format_.width) * 2);
    }
    frame.device_ns = static_cast<std::int64_t>(buffer.timestamp.tv_sec) * 1'000'000'000 +
                      static_cast<std::int64_t>(buffer.timestamp.tv_usec) * 1000;
    // UVC drivers stamp buffers with CLOCK_MONOTONIC: shift to CLOCK_REALTIME.
    const bool monotonic =
        (buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    frame.host_ns = monotonic ? frame.device_ns + (timing::RealtimeNs() - timing::MonotonicNs())
                              : timing::RealtimeNs();
    frame.sequence = buffer.sequence;
    frame.width = format_.width;
    frame.height = format_.height;
    ++counters_.frames;
  }
  if (io_.Ioctl(fd_, VIDIOC_QBUF, &buffer) < 0) {
    return Error{device_ + ": VIDIOC_QBUF failed: " + std::strerror(errno)};
  }
  return ok;
}

}  // namespace selfcal::v4l2

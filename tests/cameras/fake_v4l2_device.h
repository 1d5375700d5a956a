// A Z16 depth camera behind the V4l2Io seam (there is no /dev/video* on this kernel): answers the
// ioctls a UVC driver answers, hands out buffers through Mmap, and fills each dequeued buffer with
// a known depth pattern and a CLOCK_MONOTONIC timestamp. A mock of the kernel, said so.
#pragma once

#include <linux/videodev2.h>
#include <sys/mman.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <deque>
#include <set>
#include <vector>

#include "drivers/v4l2/v4l2_io.h"

namespace selfcal::testing {

class FakeZ16Device : public v4l2::V4l2Io {
 public:
  struct Config {
    std::vector<std::uint32_t> formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_Z16};
    std::uint32_t width = 64, height = 48;
    std::uint32_t max_width = 640;  // S_FMT clamps to this, as drivers adjust
    std::uint32_t padding_bytes = 0;
    std::set<std::uint32_t> error_frames;    // frame numbers (from 0) flagged V4L2_BUF_FLAG_ERROR
    std::set<std::uint32_t> skipped_frames;  // frame numbers the "hardware" loses (sequence jumps)
    int unplug_after_frames = -1;
  };
  explicit FakeZ16Device(Config config) : config_(std::move(config)) {}

  static std::int16_t Depth(std::uint32_t u, std::uint32_t v, std::uint32_t frame) {
    return static_cast<std::int16_t>(500 + u + 10 * v + frame);
  }

  bool present = true;
  int opens = 0, closes = 0, maps = 0, unmaps = 0, streamoffs = 0;
  std::uint32_t frames_served = 0;

  int Open(const std::string&) override {
    if (!present) {
      errno = ENOENT;
      return -1;
    }
    ++opens;
    queue_.clear();
    streaming_ = false;
    return 42;
  }
  int Close(int) override {
    ++closes;
    return 0;
  }
  void* Mmap(std::size_t length, int, off_t offset) override {
    const auto index = static_cast<std::size_t>(offset) / kPage;
    if (index >= buffers_.size() || length > buffers_[index].size()) {
      errno = EINVAL;
      return MAP_FAILED;
    }
    ++maps;
    return buffers_[index].data();
  }
  int Munmap(void*, std::size_t) override {
    ++unmaps;
    return 0;
  }
  int Poll(int, int) override {
    if (!present) {
      errno = ENODEV;
      return -1;
    }
    return streaming_ && !queue_.empty() ? 1 : 0;
  }

  int Ioctl(int, unsigned long request, void* argument) override {
    switch (request) {
      case VIDIOC_QUERYCAP: {
        auto* c = static_cast<v4l2_capability*>(argument);
        *c = {};
        std::strcpy(reinterpret_cast<char*>(c->driver), "fake-uvc");
        c->capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING | V4L2_CAP_DEVICE_CAPS;
        c->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
        return 0;
      }
      case VIDIOC_ENUM_FMT: {
        auto* d = static_cast<v4l2_fmtdesc*>(argument);
        if (d->index >= config_.formats.size()) return Fail(EINVAL);
        d->pixelformat = config_.formats[d->index];
        return 0;
      }
      case VIDIOC_G_FMT:
      case VIDIOC_S_FMT: {
        auto* f = static_cast<v4l2_format*>(argument);
        if (request == VIDIOC_S_FMT) {
          bool offered = false;
          for (auto code : config_.formats) offered = offered || code == f->fmt.pix.pixelformat;
          // Like real drivers: an unknown format is replaced, a size is clamped.
          format_ = offered ? f->fmt.pix.pixelformat : config_.formats[0];
          config_.width = std::min(f->fmt.pix.width, config_.max_width);
          config_.height = f->fmt.pix.height;
        }
        f->fmt.pix.width = config_.width;
        f->fmt.pix.height = config_.height;
        f->fmt.pix.pixelformat = format_;
        f->fmt.pix.bytesperline = config_.width * 2 + config_.padding_bytes;
        f->fmt.pix.sizeimage = f->fmt.pix.bytesperline * config_.height;
        return 0;
      }
      case VIDIOC_S_PARM:
      case VIDIOC_G_PARM: {
        auto* p = static_cast<v4l2_streamparm*>(argument);
        p->parm.capture.timeperframe = {1, 30};
        return 0;
      }
      case VIDIOC_REQBUFS: {
        auto* r = static_cast<v4l2_requestbuffers*>(argument);
        r->count = std::min<std::uint32_t>(r->count, 8);
        buffers_.assign(r->count, std::vector<std::uint8_t>(Bytes()));
        return 0;
      }
      case VIDIOC_QUERYBUF: {
        auto* b = static_cast<v4l2_buffer*>(argument);
        if (b->index >= buffers_.size()) return Fail(EINVAL);
        b->length = static_cast<std::uint32_t>(buffers_[b->index].size());
        b->m.offset = b->index * kPage;
        return 0;
      }
      case VIDIOC_QBUF: {
        auto* b = static_cast<v4l2_buffer*>(argument);
        if (b->index >= buffers_.size()) return Fail(EINVAL);
        queue_.push_back(b->index);
        return 0;
      }
      case VIDIOC_STREAMON:
        streaming_ = true;
        return 0;
      case VIDIOC_STREAMOFF:
        ++streamoffs;
        streaming_ = false;
        return 0;
      case VIDIOC_DQBUF:
        return Dequeue(static_cast<v4l2_buffer*>(argument));
      default:
        return Fail(ENOTTY);
    }
  }

 private:
  static constexpr std::size_t kPage = 4096;
  static int Fail(int error) {
    errno = error;
    return -1;
  }
  std::size_t Bytes() const {
    return static_cast<std::size_t>(config_.width * 2 + config_.padding_bytes) * config_.height;
  }
  int Dequeue(v4l2_buffer* b) {
    if (!present || (config_.unplug_after_frames >= 0 &&
                     frames_served >= static_cast<std::uint32_t>(config_.unplug_after_frames))) {
      present = false;
      config_.unplug_after_frames = -1;  // unplugged once; plugged in again by the test
      return Fail(ENODEV);
    }
    if (queue_.empty()) return Fail(EAGAIN);
    while (config_.skipped_frames.count(frame_)) ++frame_;
    const std::uint32_t index = queue_.front();
    queue_.pop_front();
    auto& bytes = buffers_[index];
    const std::size_t line = config_.width * 2 + config_.padding_bytes;
    for (std::uint32_t v = 0; v < config_.height; ++v) {
      for (std::uint32_t u = 0; u < config_.width; ++u) {
        const std::int16_t d = Depth(u, v, frame_);
        std::memcpy(bytes.data() + v * line + 2 * u, &d, 2);
      }
      std::memset(bytes.data() + v * line + 2 * config_.width, 0xEE, config_.padding_bytes);
    }
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    *b = {};
    b->index = index;
    b->type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b->memory = V4L2_MEMORY_MMAP;
    b->bytesused = static_cast<std::uint32_t>(bytes.size());
    b->flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC |
               (config_.error_frames.count(frame_) ? V4L2_BUF_FLAG_ERROR : 0);
    b->sequence = frame_;
    b->timestamp.tv_sec = now.tv_sec;
    b->timestamp.tv_usec = now.tv_nsec / 1000;
    ++frame_;
    ++frames_served;
    return 0;
  }

  Config config_;
  std::uint32_t format_ = V4L2_PIX_FMT_YUYV;
  std::vector<std::vector<std::uint8_t>> buffers_;
  std::deque<std::uint32_t> queue_;
  bool streaming_ = false;
  std::uint32_t frame_ = 0;
};

}  // namespace selfcal::testing

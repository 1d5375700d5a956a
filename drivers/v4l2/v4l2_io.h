// The seam between the V4L2 camera code and the kernel: open, ioctl, mmap, poll. This kernel has
// no /dev/video* and no v4l2loopback or vivid (test-peers.md), so tests inject a device of their
// own through this interface; the process uses the system calls.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <memory>
#include <string>

namespace selfcal::v4l2 {

class V4l2Io {
 public:
  virtual ~V4l2Io() = default;
  // Each returns what the system call returns (-1 with errno on failure).
  virtual int Open(const std::string& path) = 0;
  virtual int Close(int fd) = 0;
  virtual int Ioctl(int fd, unsigned long request, void* argument) = 0;
  virtual void* Mmap(std::size_t length, int fd, off_t offset) = 0;  // MAP_FAILED on failure
  virtual int Munmap(void* address, std::size_t length) = 0;
  virtual int Poll(int fd, int timeout_ms) = 0;  // > 0 readable, 0 timeout, < 0 error
};

std::unique_ptr<V4l2Io> MakeSystemV4l2Io();

}  // namespace selfcal::v4l2

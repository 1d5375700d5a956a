#include "drivers/v4l2/v4l2_io.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>

namespace selfcal::v4l2 {
namespace {

class SystemV4l2Io final : public V4l2Io {
 public:
  int Open(const std::string& path) override {
    return ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  }
  int Close(int fd) override { return ::close(fd); }
  int Ioctl(int fd, unsigned long request, void* argument) override {
    int result;
    do {
      result = ::ioctl(fd, request, argument);
    } while (result < 0 && errno == EINTR);
    return result;
  }
  void* Mmap(std::size_t length, int fd, off_t offset) override {
    return ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
  }
  int Munmap(void* address, std::size_t length) override { return ::munmap(address, length); }
  int Poll(int fd, int timeout_ms) override {
    pollfd entry{fd, POLLIN, 0};
    return ::poll(&entry, 1, timeout_ms);
  }
};

}  // namespace

std::unique_ptr<V4l2Io> MakeSystemV4l2Io() { return std::make_unique<SystemV4l2Io>(); }

}  // namespace selfcal::v4l2

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "drivers/hokuyo/transport.h"

namespace selfcal::hokuyo {
namespace {

std::string Errno(const std::string& what) { return what + ": " + std::strerror(errno); }

struct BaudEntry {
  int baud;
  speed_t speed;
};
constexpr BaudEntry kBauds[] = {
    {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},
    {115200, B115200},   {230400, B230400},   {460800, B460800},   {500000, B500000},
    {576000, B576000},   {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
    {1500000, B1500000}, {2000000, B2000000}, {3000000, B3000000}, {4000000, B4000000},
};

bool SpeedFor(int baud, speed_t& speed) {
  for (const auto& entry : kBauds) {
    if (entry.baud == baud) {
      speed = entry.speed;
      return true;
    }
  }
  return false;
}

// A file descriptor transport: a TCP socket or a tty.
class FdTransport final : public Transport {
 public:
  FdTransport(int fd, std::string name, bool serial)
      : fd_(fd), name_(std::move(name)), serial_(serial) {}
  ~FdTransport() override { close(fd_); }

  Status Write(std::string_view bytes) override {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = write(fd_, bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && errno == EAGAIN) {
        pollfd p{fd_, POLLOUT, 0};
        if (poll(&p, 1, 1000) <= 0) return Error{"write timed out"};
        continue;
      }
      return Error{Errno("write")};
    }
    return OkStatus();
  }

  Expected<std::size_t> Read(char* buffer, std::size_t capacity,
                             std::chrono::microseconds timeout) override {
    pollfd p{fd_, POLLIN, 0};
    const timespec ts{static_cast<time_t>(timeout.count() / 1000000),
                      static_cast<long>(timeout.count() % 1000000) * 1000};
    const int ready = ppoll(&p, 1, &ts, nullptr);
    if (ready < 0) {
      if (errno == EINTR) return std::size_t{0};
      return Error{Errno("poll")};
    }
    if (ready == 0) return std::size_t{0};
    const ssize_t n = read(fd_, buffer, capacity);
    if (n > 0) return static_cast<std::size_t>(n);
    if (n == 0) return Error{"link closed by the device"};
    if (errno == EAGAIN || errno == EINTR) return std::size_t{0};
    return Error{Errno("read (device gone?)")};
  }

  void DiscardInput() override {
    if (serial_) tcflush(fd_, TCIFLUSH);
    char buffer[4096];
    while (read(fd_, buffer, sizeof(buffer)) > 0) {
    }
  }

  std::string Describe() const override { return name_; }
  bool is_serial() const override { return serial_; }

  Status SetBaud(int baud) override {
    if (!serial_) return OkStatus();
    speed_t speed;
    if (!SpeedFor(baud, speed)) return Error{"unsupported bit rate " + std::to_string(baud)};
    termios tio{};
    if (tcgetattr(fd_, &tio) != 0) return Error{Errno("tcgetattr")};
    cfsetispeed(&tio, speed);
    cfsetospeed(&tio, speed);
    if (tcsetattr(fd_, TCSANOW, &tio) != 0) return Error{Errno("tcsetattr")};
    return OkStatus();
  }

 private:
  int fd_;
  std::string name_;
  bool serial_;
};

}  // namespace

bool IsSupportedBaud(int baud) {
  speed_t speed;
  return SpeedFor(baud, speed);
}

Expected<std::unique_ptr<Transport>> OpenTcp(const std::string& host, int port,
                                             std::chrono::milliseconds timeout) {
  const std::string name = "tcp://" + host + ":" + std::to_string(port);
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV;
  addrinfo* result = nullptr;
  if (getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &result) != 0 || !result) {
    return Error{name + ": cannot resolve host"};
  }
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd < 0) {
    freeaddrinfo(result);
    return Error{Errno(name + ": socket")};
  }
  const int rc = connect(fd, result->ai_addr, result->ai_addrlen);
  freeaddrinfo(result);
  if (rc != 0 && errno != EINPROGRESS) {
    const std::string error = Errno(name + ": connect");
    close(fd);
    return Error{error};
  }
  if (rc != 0) {
    pollfd p{fd, POLLOUT, 0};
    if (poll(&p, 1, static_cast<int>(timeout.count())) <= 0) {
      close(fd);
      return Error{name + ": connect timed out"};
    }
    int error = 0;
    socklen_t length = sizeof(error);
    getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length);
    if (error != 0) {
      close(fd);
      return Error{name + ": connect: " + std::strerror(error)};
    }
  }
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  return std::unique_ptr<Transport>(new FdTransport(fd, name, false));
}

Expected<std::unique_ptr<Transport>> OpenSerial(const std::string& path, int baud) {
  speed_t speed;
  if (!SpeedFor(baud, speed)) return Error{path + ": unsupported bit rate " + std::to_string(baud)};
  const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return Error{Errno(path + ": open")};
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    const std::string error = Errno(path + ": not a tty");
    close(fd);
    return Error{error};
  }
  cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  cfsetispeed(&tio, speed);
  cfsetospeed(&tio, speed);
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    const std::string error = Errno(path + ": tcsetattr");
    close(fd);
    return Error{error};
  }
  tcflush(fd, TCIOFLUSH);
  return std::unique_ptr<Transport>(new FdTransport(fd, path, true));
}

}  // namespace selfcal::hokuyo

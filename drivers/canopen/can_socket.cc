#include "drivers/canopen/can_socket.h"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace selfcal::canopen {

Expected<std::unique_ptr<CanSocket>> CanSocket::OpenSocketCan(const std::string& interface) {
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    if (errno == EAFNOSUPPORT) {
      return Error{
          "SocketCAN: this kernel has no AF_CAN (socket(PF_CAN) failed with "
          "EAFNOSUPPORT); load the can and can_raw modules"};
    }
    return Error{std::string("SocketCAN: socket: ") + std::strerror(errno)};
  }
  std::unique_ptr<CanSocket> socket(new CanSocket(fd));
  ifreq request{};
  if (interface.size() >= sizeof(request.ifr_name)) {
    return Error{"SocketCAN: interface name '" + interface + "' is too long"};
  }
  std::strncpy(request.ifr_name, interface.c_str(), sizeof(request.ifr_name) - 1);
  if (::ioctl(fd, SIOCGIFINDEX, &request) != 0) {
    return Error{"SocketCAN: no interface '" + interface + "': " + std::strerror(errno)};
  }
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = request.ifr_ifindex;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0) {
    return Error{"SocketCAN: bind to '" + interface + "': " + std::strerror(errno)};
  }
  return socket;
}

std::unique_ptr<CanSocket> CanSocket::FromFd(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK);
  return std::unique_ptr<CanSocket>(new CanSocket(fd));
}

CanSocket::~CanSocket() {
  if (fd_ >= 0) ::close(fd_);
}

Expected<std::optional<CanFrame>> CanSocket::Read() {
  while (true) {
    can_frame raw{};
    const ssize_t n = ::read(fd_, &raw, sizeof(raw));
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK) return std::optional<CanFrame>{};
      if (errno == EINTR) continue;
      return Error{std::string("SocketCAN: read: ") + std::strerror(errno)};
    }
    if (static_cast<std::size_t>(n) != sizeof(raw)) {
      return Error{"SocketCAN: read " + std::to_string(n) + " bytes, not a 16-byte can_frame"};
    }
    if (raw.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG | CAN_ERR_FLAG)) continue;
    if (raw.len > 8)
      return Error{"SocketCAN: can_frame length " + std::to_string(raw.len) + " > 8"};
    CanFrame frame;
    frame.id = raw.can_id & CAN_SFF_MASK;
    frame.length = raw.len;
    std::memcpy(frame.data.data(), raw.data, raw.len);
    return std::optional<CanFrame>(frame);
  }
}

Status CanSocket::Write(const CanFrame& frame) {
  can_frame raw{};
  raw.can_id = frame.id & CAN_SFF_MASK;
  raw.len = frame.length;
  std::memcpy(raw.data, frame.data.data(), frame.length);
  if (::write(fd_, &raw, sizeof(raw)) != static_cast<ssize_t>(sizeof(raw))) {
    return Error{"SocketCAN: write " + FormatCansend(frame) + ": " + std::strerror(errno)};
  }
  return OkStatus();
}

}  // namespace selfcal::canopen

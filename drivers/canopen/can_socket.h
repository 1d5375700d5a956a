// The SocketCAN seam: a CAN_RAW socket, or any file descriptor that carries 16-byte
// `struct can_frame` datagrams (a socketpair in tests, since this kernel has no AF_CAN).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "core/util/expected.h"
#include "protocols/canopen/canopen_frames.h"

namespace selfcal::canopen {

class CanSocket {
 public:
  // socket(PF_CAN, SOCK_RAW, CAN_RAW) bound to `interface`. The error says when the kernel has
  // no SocketCAN (EAFNOSUPPORT) or the interface does not exist.
  static Expected<std::unique_ptr<CanSocket>> OpenSocketCan(const std::string& interface);
  // Takes ownership of `fd` (made non-blocking), e.g. one end of
  // socketpair(AF_UNIX, SOCK_SEQPACKET) carrying struct can_frame.
  static std::unique_ptr<CanSocket> FromFd(int fd);
  ~CanSocket();

  int fd() const { return fd_; }
  // The next frame, or nullopt when none waits. Extended, remote and error frames are skipped
  // (CANopen uses none of them); a datagram that is not a can_frame is an error.
  Expected<std::optional<CanFrame>> Read();
  Status Write(const CanFrame& frame);

 private:
  explicit CanSocket(int fd) : fd_(fd) {}
  int fd_ = -1;
};

}  // namespace selfcal::canopen

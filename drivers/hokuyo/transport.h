// Byte transports to a Hokuyo: TCP (Ethernet models) and serial (USB CDC-ACM, RS-232).
// Read waits at most `timeout`; a closed or vanished link is an error so the driver reconnects.
// Errors of an open transport say what failed, not which link: whoever reports them names the
// link once (Describe()). Errors of OpenTcp and OpenSerial name it, as there is no transport yet.
#pragma once

#include <chrono>
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

#include "core/util/expected.h"

namespace selfcal::hokuyo {

class Transport {
 public:
  virtual ~Transport() = default;
  virtual Status Write(std::string_view bytes) = 0;
  // Bytes read into `buffer` (0 on timeout); an error when the link is gone.
  virtual Expected<std::size_t> Read(char* buffer, std::size_t capacity,
                                     std::chrono::microseconds timeout) = 0;
  // Discards bytes received but not read (after a reconnect, before the handshake).
  virtual void DiscardInput() = 0;
  virtual std::string Describe() const = 0;
  // Serial only: the line rate (0 on TCP and USB where it does not matter).
  virtual Status SetBaud(int /*baud*/) { return OkStatus(); }
  virtual bool is_serial() const { return false; }
};

// Connects to host:port within `timeout`.
Expected<std::unique_ptr<Transport>> OpenTcp(const std::string& host, int port,
                                             std::chrono::milliseconds timeout);

// Opens a tty (/dev/ttyACM0, /dev/ttyS0, a pty) raw, 8N1, at `baud`.
Expected<std::unique_ptr<Transport>> OpenSerial(const std::string& path, int baud);

// Whether termios can set this rate.
bool IsSupportedBaud(int baud);

}  // namespace selfcal::hokuyo

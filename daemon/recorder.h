// A session's recording: the joint-state, sensor and marker channels as received, written to
// recording.lcmlog.partial and renamed into place only when the motion completed. A write error
// (a full disk) is kept, not thrown at the bus handler that met it: the daemon fails the session
// at its next step.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "core/util/expected.h"
#include "protocols/lcm_log/lcm_log.h"

namespace selfcal::daemon {

class Recorder {
 public:
  Status Open(const std::string& path);
  bool recording() const { return writer_.has_value(); }

  void Write(const std::string& channel, std::int64_t utime, std::span<const std::uint8_t> data);
  template <typename Message>
  requires requires(const Message& m) { m.getEncodedSize(); }
  void Write(const std::string& channel, std::int64_t utime, const Message& message) {
    const auto bytes = EncodeLcm(message);
    Write(channel, utime, bytes);
  }
  // The first write error since Open; empty while all is well.
  const std::string& error() const { return error_; }

  // Flushes, fsyncs and renames into place; closes.
  Status Commit();
  // Closes without committing: the log stays .partial (a session that did not complete).
  void Discard();

 private:
  std::optional<LcmLogWriter> writer_;
  std::string error_;
};

}  // namespace selfcal::daemon

// LCM log files (the format of lcm-logger) over liblcm's LogFile API.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/util/expected.h"
#include "protocols/lcm_log/lcm_codec.h"

namespace lcm {
class LogFile;
}

namespace selfcal {

struct LogEvent {
  std::int64_t event_number = 0;
  std::int64_t utime = 0;  // host time [us] at which the event was logged
  std::string channel;
  std::vector<std::uint8_t> data;
};

// What the reader and the writer share: an open lcm::LogFile (closed on destruction, moved
// with its owner) and the path it was opened for.
class LcmLogFile {
 public:
  LcmLogFile(LcmLogFile&&) noexcept;
  LcmLogFile& operator=(LcmLogFile&&) noexcept;
  const std::string& path() const { return path_; }

 protected:
  LcmLogFile(std::string path, std::unique_ptr<lcm::LogFile> file);
  ~LcmLogFile();

  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
};

class LcmLogReader : public LcmLogFile {
 public:
  static Expected<LcmLogReader> Open(const std::string& path);

  // The next event, or false at the end of the log. A truncated last event ends the log.
  bool Next(LogEvent& event);
  // After Next() returned false: the bytes at the end of the log that form no complete event (a
  // torn last event: the log was cut off or is still being written); 0 at a clean end.
  std::int64_t torn_bytes() const { return torn_bytes_; }

 private:
  using LcmLogFile::LcmLogFile;
  bool ended_ = false;  // Next() returned false once: the end and torn_bytes_ are known
  std::int64_t torn_bytes_ = 0;
};

// Writes `path.partial` and renames it to `path` in Commit(), after fsync: a crash never leaves
// a log at `path` that looks complete.
class LcmLogWriter : public LcmLogFile {
 public:
  static Expected<LcmLogWriter> Open(const std::string& path);

  Status Write(const std::string& channel, std::int64_t utime, std::span<const std::uint8_t> data);
  template <typename Message>
  requires requires(const Message& m) { m.getEncodedSize(); }
  Status Write(const std::string& channel, std::int64_t utime, const Message& message) {
    const auto bytes = EncodeLcm(message);
    return Write(channel, utime, bytes);
  }
  // Flushes, fsyncs and renames into place. The writer is closed afterwards.
  Status Commit();

 private:
  using LcmLogFile::LcmLogFile;
  std::int64_t next_event_ = 0;
};

}  // namespace selfcal

#include "protocols/lcm_log/lcm_log.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <lcm/lcm-cpp.hpp>

#include "core/util/atomic_file.h"

namespace selfcal {

LcmLogReader::LcmLogReader(std::string path, std::unique_ptr<lcm::LogFile> file)
    : path_(std::move(path)), file_(std::move(file)) {}
LcmLogReader::LcmLogReader(LcmLogReader&&) noexcept = default;
LcmLogReader& LcmLogReader::operator=(LcmLogReader&&) noexcept = default;
LcmLogReader::~LcmLogReader() = default;

Expected<LcmLogReader> LcmLogReader::Open(const std::string& path) {
  auto file = std::make_unique<lcm::LogFile>(path, "r");
  // readNextEvent() crashes on a file that did not open: check first.
  if (!file->good()) return Error{path + ": cannot open LCM log: " + std::strerror(errno)};
  return LcmLogReader(path, std::move(file));
}

bool LcmLogReader::Next(LogEvent& event) {
  if (!file_) return false;
  const lcm::LogEvent* raw = file_->readNextEvent();
  if (raw == nullptr) return false;
  event.event_number = raw->eventnum;
  event.utime = raw->timestamp;
  event.channel = raw->channel;
  const auto* begin = static_cast<const std::uint8_t*>(raw->data);
  event.data.assign(begin, begin + raw->datalen);
  return true;
}

LcmLogWriter::LcmLogWriter(std::string path, std::unique_ptr<lcm::LogFile> file)
    : path_(std::move(path)), file_(std::move(file)) {}
LcmLogWriter::LcmLogWriter(LcmLogWriter&&) noexcept = default;
LcmLogWriter& LcmLogWriter::operator=(LcmLogWriter&&) noexcept = default;
LcmLogWriter::~LcmLogWriter() = default;

Expected<LcmLogWriter> LcmLogWriter::Open(const std::string& path) {
  auto file = std::make_unique<lcm::LogFile>(path + ".partial", "w");
  if (!file->good()) {
    return Error{path + ".partial: cannot create LCM log: " + std::strerror(errno)};
  }
  return LcmLogWriter(path, std::move(file));
}

Status LcmLogWriter::Write(const std::string& channel, std::int64_t utime,
                           std::span<const std::uint8_t> data) {
  if (!file_) return Error{path_ + ": write after Commit()"};
  lcm::LogEvent event;
  event.eventnum = next_event_++;
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = static_cast<int32_t>(data.size());
  event.data = const_cast<std::uint8_t*>(data.data());  // liblcm's API is not const-correct
  if (file_->writeEvent(&event) != 0) {
    return Error{path_ + ".partial: cannot write event " + std::to_string(event.eventnum) + " on " +
                 channel + ": " + std::strerror(errno)};
  }
  return OkStatus();
}

Status LcmLogWriter::Commit() {
  if (!file_) return Error{path_ + ": Commit() called twice"};
  if (std::fflush(file_->getFilePtr()) != 0) {
    return Error{path_ + ".partial: flush failed: " + std::strerror(errno)};
  }
  file_.reset();
  return CommitFile(path_ + ".partial", path_);
}

}  // namespace selfcal

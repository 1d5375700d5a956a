#include "daemon/recorder.h"

namespace selfcal::daemon {

Status Recorder::Open(const std::string& path) {
  Discard();
  auto writer = LcmLogWriter::Open(path);
  if (!writer) return writer.error();
  writer_.emplace(std::move(writer).value());
  return OkStatus();
}

void Recorder::Write(const std::string& channel, std::int64_t utime,
                     std::span<const std::uint8_t> data) {
  if (!writer_ || !error_.empty()) return;
  if (auto written = writer_->Write(channel, utime, data); !written) {
    error_ = written.error().message;
  }
}

Status Recorder::Commit() {
  if (!writer_) return Error{"no recording is open"};
  auto committed = writer_->Commit();
  writer_.reset();
  return committed;
}

void Recorder::Discard() {
  writer_.reset();
  error_.clear();
}

}  // namespace selfcal::daemon

#include "protocols/lcm_log/lcm_log.h"

#include <sys/stat.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <lcm/lcm-cpp.hpp>

#include "core/util/atomic_file.h"

namespace selfcal {

LcmLogFile::LcmLogFile(std::string path, std::unique_ptr<lcm::LogFile> file)
    : path_(std::move(path)), file_(std::move(file)) {}
LcmLogFile::LcmLogFile(LcmLogFile&&) noexcept = default;
LcmLogFile& LcmLogFile::operator=(LcmLogFile&&) noexcept = default;
LcmLogFile::~LcmLogFile() = default;

namespace {

// Every event of an LCM log begins with this word, big-endian; so does the file.
constexpr unsigned char kEventSyncWord[4] = {0xED, 0xA1, 0xDA, 0x01};

// Why the file at `path` is no LCM log: a folder, a file that does not begin with the sync word
// (liblcm would skip any bytes looking for that word, and read a text file as a log with no
// events). An empty file is an empty log.
Status CheckLogFile(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    return Error{path + ": cannot open LCM log: " + std::strerror(errno)};
  }
  if (S_ISDIR(info.st_mode)) return Error{path + ": is a folder, not an LCM log"};
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return Error{path + ": cannot open LCM log: " + std::strerror(errno)};
  unsigned char head[4] = {};
  const std::size_t read = std::fread(head, 1, sizeof(head), file);
  std::fclose(file);
  if (read > 0 && (read < sizeof(head) || std::memcmp(head, kEventSyncWord, sizeof(head)) != 0)) {
    return Error{path + ": not an LCM log (it does not begin with the event sync word 0xEDA1DA01)"};
  }
  return OkStatus();
}

// Whether the next event's header (after the sync word liblcm looks for) declares a channel and
// data that the rest of the file can hold. liblcm allocates what a header declares before it
// reads a byte of it (1.4 GB from a 40-byte file, found by fuzz_lcm_log) and writes into a failed
// allocation; a header that cannot be honoured is a torn or corrupt event and ends the log. The
// file position is left where it was.
bool NextEventFits(std::FILE* file) {
  struct stat info {};
  const off_t start = ::ftello(file);
  if (start < 0 || ::fstat(::fileno(file), &info) != 0) return false;
  std::uint32_t word = 0;
  int c = 0;
  while (word != 0xEDA1DA01u && (c = std::fgetc(file)) != EOF) {
    word = word << 8 | static_cast<std::uint32_t>(c);
  }
  std::array<unsigned char, 24> header{};  // event number, time, channel and data lengths
  const bool complete =
      word == 0xEDA1DA01u && std::fread(header.data(), 1, header.size(), file) == header.size();
  const off_t body = ::ftello(file);
  ::fseeko(file, start, SEEK_SET);
  if (!complete) return true;  // liblcm finds the end itself
  const auto length = [&](std::size_t at) {
    return std::int64_t{header[at]} << 24 | std::int64_t{header[at + 1]} << 16 |
           std::int64_t{header[at + 2]} << 8 | std::int64_t{header[at + 3]};
  };
  const std::int64_t channel_bytes = length(16);
  const std::int64_t data_bytes = length(20);
  return channel_bytes >= 1 && channel_bytes < 1000 && data_bytes >= 0 &&
         data_bytes < (1LL << 31) && body + channel_bytes + data_bytes <= info.st_size;
}

}  // namespace

Expected<LcmLogReader> LcmLogReader::Open(const std::string& path) {
  if (const Status checked = CheckLogFile(path); !checked) return checked.error();
  auto file = std::make_unique<lcm::LogFile>(path, "r");
  // readNextEvent() crashes on a file that did not open: check first.
  if (!file->good()) return Error{path + ": cannot open LCM log: " + std::strerror(errno)};
  return LcmLogReader(path, std::move(file));
}

bool LcmLogReader::Next(LogEvent& event) {
  if (!file_ || ended_) return false;
  std::FILE* stream = file_->getFilePtr();
  const std::int64_t offset = ::ftello(stream);
  const lcm::LogEvent* raw = NextEventFits(stream) ? file_->readNextEvent() : nullptr;
  if (raw == nullptr) {
    // The size now, not at Open(): a log still being written has grown since.
    struct stat info {};
    const bool sized = ::fstat(::fileno(stream), &info) == 0;
    torn_bytes_ = sized && offset >= 0 && info.st_size > offset ? info.st_size - offset : 0;
    ended_ = true;
    return false;
  }
  event.event_number = raw->eventnum;
  event.utime = raw->timestamp;
  event.channel = raw->channel;
  const auto* begin = static_cast<const std::uint8_t*>(raw->data);
  event.data.assign(begin, begin + raw->datalen);
  return true;
}

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

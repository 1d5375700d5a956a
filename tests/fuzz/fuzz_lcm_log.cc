// Any bytes as an LCM log file (lcm-logger's format: sync word, event number, time, channel and
// data lengths, channel, data): the reader returns the events it finds and stops at the end or at
// a torn or corrupt event; never a crash, a read beyond the file or an allocation the file cannot
// fill.
#include <cstdint>

#include "protocols/lcm_log/lcm_log.h"
#include "tests/fuzz/fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = selfcal::fuzz::InputPath(".lcmlog");
  selfcal::fuzz::WriteFile(path, data, size);
  auto reader = selfcal::LcmLogReader::Open(path);
  if (!reader.ok()) return 0;
  selfcal::LogEvent event;
  std::size_t bytes = 0;
  while (reader->Next(event)) {
    bytes += event.channel.size() + event.data.size();
    if (bytes > size) __builtin_trap();  // more than the file holds
  }
  return 0;
}

// SCIP 2.0 response blocks, sensor to host (protocols.md 1.2): an echo line, a status line
// (2 characters + checksum), data lines (payload + checksum, at most 64 payload characters) and
// an empty line. Framing finds block boundaries in a byte stream; parsing checks every checksum.
// Errors name the byte offset in the stream and the line.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/util/expected.h"

namespace selfcal::scip {

inline constexpr std::size_t kMaxDataPayload = 64;  // characters per data line before the sum
inline constexpr std::size_t kMaxEchoLength = 64;   // command (<= 15) + ';' + tag (<= 16), generous
inline constexpr std::size_t kDefaultMaxBlockBytes =
    64 * 1024;  // a 3-echo NE of 1081 steps ~ 23 kB

struct Block {
  std::uint64_t offset = 0;  // byte offset of the echo line in the stream
  std::string echo;          // the command as echoed, without LF
  std::string status;        // 2 characters; empty when the block had only an echo
  // Data line payloads without their checksum characters, and where each line starts.
  std::vector<std::string> lines;
  std::vector<std::uint64_t> line_offsets;
};

// Parses one complete block (`bytes` ends with the terminating empty line). Info replies
// (VV, PP, II) carry "KEY:VALUE;" lines whose checksum covers "KEY:VALUE" only; both that and a
// checksum over the whole payload are accepted there, as urg_library does.
Expected<Block> ParseBlock(std::string_view bytes, std::uint64_t stream_offset = 0);

// Appends a reply block as a sensor sends it (for the simulator and tests): echo, status with
// its checksum, the given data lines with theirs, and the empty line.
void AppendStatusLine(std::string& out, std::string_view status);
void AppendDataLine(std::string& out, std::string_view payload);
// "KEY:VALUE;" + checksum over "KEY:VALUE" + LF.
void AppendInfoLine(std::string& out, std::string_view key, std::string_view value);
// Cuts an encoded value stream into lines of 64 characters, each with its checksum.
void AppendDataBlock(std::string& out, std::string_view values);

// Splits a byte stream into blocks. Bytes arrive in any chunks; Next() returns each complete
// block in order. A malformed block (bad checksum, junk, overlong line or block) is returned as
// an error and skipped, so the stream continues with the following block.
class BlockFramer {
 public:
  explicit BlockFramer(std::size_t max_block_bytes = kDefaultMaxBlockBytes);

  void Append(std::string_view bytes);
  // A block, an error for a malformed one, or nullopt when more bytes are needed.
  std::optional<Expected<Block>> Next();
  // Drops everything buffered (after a reconnect).
  void Reset();

  std::uint64_t stream_offset() const { return consumed_; }
  std::size_t buffered() const { return buffer_.size() - head_; }

 private:
  std::size_t max_block_bytes_;
  std::string buffer_;
  std::size_t head_ = 0;        // start of unconsumed bytes in buffer_
  std::size_t scan_from_ = 0;   // where to resume looking for "\n\n" (relative to head_)
  std::uint64_t consumed_ = 0;  // stream offset of buffer_[head_]
};

}  // namespace selfcal::scip

#include "protocols/scip/block.h"

#include "protocols/scip/encoding.h"

namespace selfcal::scip {
namespace {

std::string Where(std::uint64_t offset, std::size_t line) {
  return "byte " + std::to_string(offset) + " (line " + std::to_string(line + 1) + " of block)";
}

bool IsPrintable(std::string_view text) {
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u > 0x7E) return false;
  }
  return true;
}

bool IsInfoCommand(std::string_view echo) {
  return echo.starts_with("VV") || echo.starts_with("PP") || echo.starts_with("II");
}

// Shows a short excerpt of bad bytes in an error, escaped.
std::string Excerpt(std::string_view text) {
  std::string out;
  for (const char c : text.substr(0, 24)) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u <= 0x7E && c != '"' && c != '\\') {
      out.push_back(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof(hex), "\\x%02X", u);
      out.append(hex);
    }
  }
  if (text.size() > 24) out.append("...");
  return "\"" + out + "\"";
}

}  // namespace

Expected<Block> ParseBlock(std::string_view bytes, std::uint64_t stream_offset) {
  if (bytes.size() < 2 || !bytes.ends_with("\n\n")) {
    return Error{"byte " + std::to_string(stream_offset + bytes.size()) +
                 ": block truncated (no terminating empty line)"};
  }
  Block block;
  block.offset = stream_offset;
  // Lines without the final empty one.
  const std::string_view body = bytes.substr(0, bytes.size() - 1);
  std::size_t position = 0;
  std::size_t line_index = 0;
  const bool info = IsInfoCommand(body.substr(0, body.find('\n')));
  while (position < body.size()) {
    const std::size_t end = body.find('\n', position);
    const std::string_view line = body.substr(position, end - position);
    const std::uint64_t line_offset = stream_offset + position;
    if (line_index == 0) {
      if (line.empty()) return Error{Where(line_offset, 0) + ": empty echo line"};
      if (line.size() > kMaxEchoLength) {
        return Error{Where(line_offset, 0) + ": echo line of " + std::to_string(line.size()) +
                     " characters exceeds " + std::to_string(kMaxEchoLength)};
      }
      if (!IsPrintable(line)) {
        return Error{Where(line_offset, 0) + ": echo line has non-printable bytes " +
                     Excerpt(line)};
      }
      block.echo = std::string(line);
    } else if (line_index == 1) {
      if (line.size() != 3) {
        return Error{Where(line_offset, 1) + ": status line of " + std::to_string(line.size()) +
                     " characters, expected 2 + checksum: " + Excerpt(line)};
      }
      if (Checksum(line.substr(0, 2)) != line[2]) {
        return Error{Where(line_offset + 2, 1) + ": status checksum mismatch in " + Excerpt(line) +
                     " (expected '" + std::string(1, Checksum(line.substr(0, 2))) + "')"};
      }
      block.status = std::string(line.substr(0, 2));
    } else {
      if (line.size() < 2) {
        return Error{Where(line_offset, line_index) + ": data line of " +
                     std::to_string(line.size()) + " characters has no checksum"};
      }
      if (line.size() > kMaxDataPayload + 1) {
        return Error{Where(line_offset, line_index) + ": data line of " +
                     std::to_string(line.size()) + " characters exceeds 64 + checksum"};
      }
      const std::string_view payload = line.substr(0, line.size() - 1);
      const char sum = line.back();
      bool good = Checksum(payload) == sum;
      if (!good && info && payload.size() >= 2 && payload.back() == ';') {
        good = Checksum(payload.substr(0, payload.size() - 1)) == sum;
      }
      if (!good) {
        return Error{Where(line_offset + line.size() - 1, line_index) +
                     ": data checksum mismatch in " + Excerpt(line)};
      }
      block.lines.emplace_back(payload);
      block.line_offsets.push_back(line_offset);
    }
    position = end + 1;
    ++line_index;
  }
  if (line_index < 2) {
    return Error{Where(stream_offset, 1) + ": reply to " + Excerpt(block.echo) +
                 " has no status line"};
  }
  return block;
}

void AppendStatusLine(std::string& out, std::string_view status) {
  out.append(status);
  out.push_back(Checksum(status));
  out.push_back('\n');
}

void AppendDataLine(std::string& out, std::string_view payload) {
  out.append(payload);
  out.push_back(Checksum(payload));
  out.push_back('\n');
}

void AppendInfoLine(std::string& out, std::string_view key, std::string_view value) {
  std::string payload;
  payload.append(key);
  payload.push_back(':');
  payload.append(value);
  out.append(payload);
  out.push_back(';');
  out.push_back(Checksum(payload));
  out.push_back('\n');
}

void AppendDataBlock(std::string& out, std::string_view values) {
  for (std::size_t i = 0; i < values.size(); i += kMaxDataPayload) {
    AppendDataLine(out, values.substr(i, kMaxDataPayload));
  }
}

BlockFramer::BlockFramer(std::size_t max_block_bytes) : max_block_bytes_(max_block_bytes) {}

void BlockFramer::Append(std::string_view bytes) {
  // Compact once the consumed prefix dominates, so the buffer does not grow without bound.
  if (head_ > 0 && head_ >= buffer_.size() / 2) {
    buffer_.erase(0, head_);
    head_ = 0;
  }
  buffer_.append(bytes);
}

void BlockFramer::Reset() {
  consumed_ += buffer_.size() - head_;
  buffer_.clear();
  head_ = 0;
  scan_from_ = 0;
}

std::optional<Expected<Block>> BlockFramer::Next() {
  // Stray LFs between blocks are harmless (a sensor answers a bare LF with one).
  while (head_ < buffer_.size() && buffer_[head_] == '\n') {
    ++head_;
    ++consumed_;
    if (scan_from_ > 0) --scan_from_;
  }
  const std::string_view pending(buffer_.data() + head_, buffer_.size() - head_);
  const std::size_t end = pending.find("\n\n", scan_from_);
  if (end == std::string_view::npos) {
    if (pending.size() > max_block_bytes_) {
      // Junk or a runaway block: drop it all but a trailing LF that may start a terminator.
      const std::uint64_t at = consumed_;
      const std::size_t drop = pending.back() == '\n' ? pending.size() - 1 : pending.size();
      head_ += drop;
      consumed_ += drop;
      scan_from_ = 0;
      return Expected<Block>(Error{"byte " + std::to_string(at) + ": no block end within " +
                                   std::to_string(max_block_bytes_) + " bytes; dropped " +
                                   std::to_string(drop) + " bytes"});
    }
    scan_from_ = pending.empty() ? 0 : pending.size() - 1;
    return std::nullopt;
  }
  const std::size_t size = end + 2;
  const std::uint64_t at = consumed_;
  const std::string_view bytes = pending.substr(0, size);
  head_ += size;
  consumed_ += size;
  scan_from_ = 0;
  if (size > max_block_bytes_) {
    return Expected<Block>(Error{"byte " + std::to_string(at) + ": block of " +
                                 std::to_string(size) + " bytes exceeds the limit of " +
                                 std::to_string(max_block_bytes_)});
  }
  return ParseBlock(bytes, at);
}

}  // namespace selfcal::scip

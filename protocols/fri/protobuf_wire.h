// The protobuf wire format (varints, fixed64, length-delimited fields), written from the public
// encoding rules: just enough for the FRI messages. Reader errors name the byte offset from the
// start of the datagram and the field path; the writer writes into a caller's fixed buffer.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "core/util/expected.h"

namespace selfcal::fri::wire {

enum class WireType : std::uint8_t {
  kVarint = 0,
  kFixed64 = 1,
  kLengthDelimited = 2,
  kFixed32 = 5
};

struct FieldKey {
  std::uint32_t number = 0;
  WireType type = WireType::kVarint;
  std::size_t offset = 0;  // absolute offset of the key
};

// Reads one message (or a nested one: Sub()) field by field.
class Reader {
 public:
  Reader(std::span<const std::uint8_t> bytes, std::size_t base_offset, std::string path)
      : bytes_(bytes), base_(base_offset), path_(std::move(path)) {}

  bool AtEnd() const { return position_ >= bytes_.size(); }
  Expected<FieldKey> NextKey();
  Expected<std::uint64_t> Varint(const std::string& field);
  Expected<double> Fixed64Double(const std::string& field);
  // A nested message of the field just read (wire type must be length-delimited).
  Expected<Reader> Sub(const std::string& field);
  // Skips the value of an unknown field of type `type`.
  Status Skip(const FieldKey& key);

  std::size_t AbsoluteOffset() const { return base_ + position_; }
  const std::string& path() const { return path_; }
  Error MakeError(const std::string& field, std::size_t offset, const std::string& what) const;

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t base_ = 0;
  std::size_t position_ = 0;
  std::string path_;
};

// Writes into a fixed buffer; in counting mode (no buffer) only measures. Overflow is sticky.
class Writer {
 public:
  Writer() = default;  // counting mode
  explicit Writer(std::span<std::uint8_t> out) : out_(out), counting_(false) {}

  void Key(std::uint32_t field, WireType type);
  void Varint(std::uint64_t value);
  void VarintField(std::uint32_t field, std::uint64_t value);
  // int32 as protobuf does: negative values as 10-byte two's complement varints.
  void Int32Field(std::uint32_t field, std::int32_t value);
  void DoubleField(std::uint32_t field, double value);
  // A nested message written by `body(Writer&)`: measured first, then written.
  template <typename Body>
  void MessageField(std::uint32_t field, Body&& body) {
    Writer counter;
    body(counter);
    Key(field, WireType::kLengthDelimited);
    Varint(counter.size());
    body(*this);
  }

  std::size_t size() const { return size_; }
  bool overflow() const { return overflow_; }

 private:
  void Byte(std::uint8_t byte);
  std::span<std::uint8_t> out_;
  bool counting_ = true;
  std::size_t size_ = 0;
  bool overflow_ = false;
};

}  // namespace selfcal::fri::wire

#include "protocols/fri/protobuf_wire.h"

#include <bit>
#include <cstring>

namespace selfcal::fri::wire {

Error Reader::MakeError(const std::string& field, std::size_t offset,
                        const std::string& what) const {
  std::string where = path_;
  if (!field.empty()) where += (where.empty() ? "" : ".") + field;
  return Error{"byte " + std::to_string(offset) + ": " + where + ": " + what};
}

Expected<std::uint64_t> Reader::Varint(const std::string& field) {
  const std::size_t start = AbsoluteOffset();
  std::uint64_t value = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (position_ >= bytes_.size()) return MakeError(field, start, "truncated varint");
    const std::uint8_t byte = bytes_[position_++];
    if (shift == 63 && (byte & 0x7e) != 0)
      return MakeError(field, start, "varint overflows 64 bits");
    value |= static_cast<std::uint64_t>(byte & 0x7f) << shift;
    if ((byte & 0x80) == 0) return value;
  }
  return MakeError(field, start, "varint longer than 10 bytes");
}

Expected<FieldKey> Reader::NextKey() {
  const std::size_t offset = AbsoluteOffset();
  auto key = Varint("key");
  if (!key.ok()) return key.error();
  const std::uint64_t number = *key >> 3;
  const auto type = static_cast<std::uint8_t>(*key & 7);
  if (number == 0 || number > 0x1fffffff) {
    return MakeError("", offset, "invalid field number " + std::to_string(number));
  }
  if (type != 0 && type != 1 && type != 2 && type != 5) {
    return MakeError(
        "", offset,
        "unsupported wire type " + std::to_string(type) + " for field " + std::to_string(number));
  }
  return FieldKey{static_cast<std::uint32_t>(number), static_cast<WireType>(type), offset};
}

Expected<double> Reader::Fixed64Double(const std::string& field) {
  if (bytes_.size() - position_ < 8) return MakeError(field, AbsoluteOffset(), "truncated double");
  std::uint64_t bits = 0;
  for (int i = 7; i >= 0; --i) bits = (bits << 8) | bytes_[position_ + static_cast<std::size_t>(i)];
  position_ += 8;
  return std::bit_cast<double>(bits);
}

Expected<Reader> Reader::Sub(const std::string& field) {
  const std::size_t start = AbsoluteOffset();
  auto length = Varint(field);
  if (!length.ok()) return length.error();
  if (*length > bytes_.size() - position_) {
    return MakeError(field, start,
                     "length " + std::to_string(*length) + " exceeds the " +
                         std::to_string(bytes_.size() - position_) + " bytes left");
  }
  Reader sub(bytes_.subspan(position_, static_cast<std::size_t>(*length)), AbsoluteOffset(),
             path_.empty() ? field : path_ + "." + field);
  position_ += static_cast<std::size_t>(*length);
  return sub;
}

Status Reader::Skip(const FieldKey& key) {
  const std::string field = "field " + std::to_string(key.number);
  switch (key.type) {
    case WireType::kVarint: {
      auto v = Varint(field);
      if (!v.ok()) return v.error();
      return OkStatus();
    }
    case WireType::kFixed64:
    case WireType::kFixed32: {
      const std::size_t n = key.type == WireType::kFixed64 ? 8 : 4;
      if (bytes_.size() - position_ < n) return MakeError(field, AbsoluteOffset(), "truncated");
      position_ += n;
      return OkStatus();
    }
    case WireType::kLengthDelimited: {
      auto sub = Sub(field);
      if (!sub.ok()) return sub.error();
      return OkStatus();
    }
  }
  return MakeError(field, key.offset, "unsupported wire type");
}

void Writer::Byte(std::uint8_t byte) {
  if (!counting_) {
    if (size_ >= out_.size()) {
      overflow_ = true;
      return;
    }
    out_[size_] = byte;
  }
  ++size_;
}

void Writer::Varint(std::uint64_t value) {
  while (value >= 0x80) {
    Byte(static_cast<std::uint8_t>(value | 0x80));
    value >>= 7;
  }
  Byte(static_cast<std::uint8_t>(value));
}

void Writer::Key(std::uint32_t field, WireType type) {
  Varint((static_cast<std::uint64_t>(field) << 3) | static_cast<std::uint8_t>(type));
}

void Writer::VarintField(std::uint32_t field, std::uint64_t value) {
  Key(field, WireType::kVarint);
  Varint(value);
}

void Writer::Int32Field(std::uint32_t field, std::int32_t value) {
  VarintField(field, static_cast<std::uint64_t>(static_cast<std::int64_t>(value)));
}

void Writer::DoubleField(std::uint32_t field, double value) {
  Key(field, WireType::kFixed64);
  const auto bits = std::bit_cast<std::uint64_t>(value);
  for (int i = 0; i < 8; ++i) Byte(static_cast<std::uint8_t>(bits >> (8 * i)));
}

}  // namespace selfcal::fri::wire

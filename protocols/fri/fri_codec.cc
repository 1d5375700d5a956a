#include "protocols/fri/fri_codec.h"

#include <algorithm>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "protocols/fri/protobuf_wire.h"

namespace selfcal::fri {

const char* ToString(SessionState state) {
  switch (state) {
    case SessionState::kIdle:
      return "IDLE";
    case SessionState::kMonitoringWait:
      return "MONITORING_WAIT";
    case SessionState::kMonitoringReady:
      return "MONITORING_READY";
    case SessionState::kCommandingWait:
      return "COMMANDING_WAIT";
    case SessionState::kCommandingActive:
      return "COMMANDING_ACTIVE";
  }
  return "UNKNOWN";
}

const char* ToString(ConnectionQuality quality) {
  switch (quality) {
    case ConnectionQuality::kPoor:
      return "POOR";
    case ConnectionQuality::kFair:
      return "FAIR";
    case ConnectionQuality::kGood:
      return "GOOD";
    case ConnectionQuality::kExcellent:
      return "EXCELLENT";
  }
  return "UNKNOWN";
}

namespace {

using wire::FieldKey;
using wire::Reader;
using wire::WireType;
using wire::Writer;

// Propagates an error from an Expected or Status expression.
#define FRI_TRY(var, expr) \
  auto var = (expr);       \
  if (!var.ok()) return var.error()

Status ExpectType(const Reader& reader, const FieldKey& key, WireType type, const char* field) {
  if (key.type != type) {
    return reader.MakeError(field, key.offset,
                            "wrong wire type " + std::to_string(static_cast<int>(key.type)));
  }
  return OkStatus();
}

Expected<std::uint32_t> ReadUint32(Reader& reader, const FieldKey& key, const char* field) {
  FRI_TRY(type_ok, ExpectType(reader, key, WireType::kVarint, field));
  FRI_TRY(value, reader.Varint(field));
  // uint32 fields are written as at most 32-bit varints; protobuf truncates larger ones.
  if (*value > 0xffffffffULL) return reader.MakeError(field, key.offset, "value exceeds uint32");
  return static_cast<std::uint32_t>(*value);
}

Expected<std::int32_t> ReadInt32(Reader& reader, const FieldKey& key, const char* field) {
  FRI_TRY(type_ok, ExpectType(reader, key, WireType::kVarint, field));
  FRI_TRY(value, reader.Varint(field));
  const auto as_signed = static_cast<std::int64_t>(*value);
  if (as_signed < INT32_MIN || as_signed > INT32_MAX) {
    return reader.MakeError(field, key.offset, "value exceeds int32");
  }
  return static_cast<std::int32_t>(as_signed);
}

template <typename Enum>
Expected<Enum> ReadEnum(Reader& reader, const FieldKey& key, const char* field, int max_value) {
  FRI_TRY(value, ReadInt32(reader, key, field));
  if (*value < 0 || *value > max_value) {
    return reader.MakeError(field, key.offset, "unknown enum value " + std::to_string(*value));
  }
  return static_cast<Enum>(*value);
}

Expected<double> ReadDouble(Reader& reader, const FieldKey& key, const char* field) {
  FRI_TRY(type_ok, ExpectType(reader, key, WireType::kFixed64, field));
  return reader.Fixed64Double(field);
}

Expected<Reader> ReadSub(Reader& reader, const FieldKey& key, const char* field) {
  FRI_TRY(type_ok, ExpectType(reader, key, WireType::kLengthDelimited, field));
  return reader.Sub(field);
}

// JointValues / CartesianVector: field 1 = repeated double. Accepts the packed form too, as any
// protobuf parser must.
Expected<std::vector<double>> ReadDoubles(Reader& parent, const FieldKey& parent_key,
                                          const char* field) {
  FRI_TRY(reader, ReadSub(parent, parent_key, field));
  std::vector<double> values;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    if (key->number != 1) {
      FRI_TRY(skipped, reader->Skip(*key));
      continue;
    }
    if (key->type == WireType::kLengthDelimited) {
      FRI_TRY(packed, reader->Sub("value"));
      while (!packed->AtEnd()) {
        if (values.size() >= kMaxJointValues) {
          return reader->MakeError("value", key->offset, "more than 32 values");
        }
        FRI_TRY(v, packed->Fixed64Double("value"));
        values.push_back(*v);
      }
      continue;
    }
    if (values.size() >= kMaxJointValues) {
      return reader->MakeError("value", key->offset, "more than 32 values");
    }
    FRI_TRY(v, ReadDouble(*reader, *key, "value"));
    values.push_back(*v);
  }
  return values;
}

// --- the message schema ----------------------------------------------------------------------
//
// Every message selfcal reads and writes is a table of its fields (number and name as in
// fri.proto); one decoder and one encoder work from the tables. A field a table does not name is
// skipped when decoding and never written.

template <typename Message>
struct Field {
  std::uint32_t number;
  const char* name;
  bool required;  // fri.proto's `required`: decoding fails without it
  Status (*read)(Reader& reader, const FieldKey& key, const char* name, Message& message);
  void (*write)(Writer& writer, std::uint32_t number, const Message& message);
};

// The fields of `Message`, in the order they are written; specialized for every message below.
template <typename Message>
std::span<const Field<Message>> FieldsOf();

template <typename Member>
struct MemberOf;
template <typename Message, typename Stored>
struct MemberOf<Stored Message::*> {
  using Class = Message;
  using Type = Stored;
};
template <auto kMember>
using MessageOf = typename MemberOf<decltype(kMember)>::Class;

template <typename T>
inline constexpr bool kIsOptional = false;
template <typename T>
inline constexpr bool kIsOptional<std::optional<T>> = true;
// A repeated scalar field (driveState); a vector of doubles is a JointValues message instead.
template <typename T>
inline constexpr bool kIsRepeated = false;
template <typename T>
inline constexpr bool kIsRepeated<std::vector<T>> = std::is_enum_v<T>;

// The largest value fri.proto defines for each enum: a larger one is an error, not a new state.
constexpr int LastValue(SessionState) { return 4; }
constexpr int LastValue(ConnectionQuality) { return 3; }
constexpr int LastValue(SafetyState) { return 3; }
constexpr int LastValue(DriveState) { return 2; }
constexpr int LastValue(OperationMode) { return 2; }
constexpr int LastValue(ControlMode) { return 3; }
constexpr int LastValue(ClientCommandMode) { return 3; }
constexpr int LastValue(OverlayType) { return 2; }

// What a decoded message must satisfy beyond its fields' types: nothing, but for a time stamp.
template <typename Message>
Status Validate(const Reader&, std::size_t, const Message&) {
  return OkStatus();
}
Status Validate(const Reader& reader, std::size_t offset, const TimeStamp& stamp) {
  if (stamp.nanosec >= 1000000000u) return reader.MakeError("nanosec", offset, "nanosec >= 1e9");
  return OkStatus();
}

// Reads the fields of a `Message` up to the end of `reader`, then checks that the required ones
// were there: a missing one is an error at `offset`, the key of the field that holds the message.
template <typename Message>
Expected<Message> ReadFields(Reader& reader, std::size_t offset) {
  const std::span<const Field<Message>> fields = FieldsOf<Message>();
  Message message;
  std::uint64_t seen = 0;  // bit k: fields[k] was read (a message has fewer than 64 fields)
  while (!reader.AtEnd()) {
    FRI_TRY(key, reader.NextKey());
    const auto field = std::find_if(fields.begin(), fields.end(), [&](const Field<Message>& f) {
      return f.number == key->number;
    });
    if (field == fields.end()) {
      FRI_TRY(skipped, reader.Skip(*key));
      continue;
    }
    FRI_TRY(stored, field->read(reader, *key, field->name, message));
    seen |= std::uint64_t{1} << (field - fields.begin());
  }
  for (std::size_t k = 0; k < fields.size(); ++k) {
    if (fields[k].required && !(seen & (std::uint64_t{1} << k))) {
      return reader.MakeError(fields[k].name, offset, "required field missing");
    }
  }
  FRI_TRY(valid, Validate(reader, offset, message));
  return message;
}

template <typename T>
Expected<T> ReadValue(Reader& reader, const FieldKey& key, const char* name) {
  if constexpr (std::is_same_v<T, std::uint32_t>) {
    return ReadUint32(reader, key, name);
  } else if constexpr (std::is_same_v<T, std::int32_t>) {
    return ReadInt32(reader, key, name);
  } else if constexpr (std::is_same_v<T, double>) {
    return ReadDouble(reader, key, name);
  } else if constexpr (std::is_enum_v<T>) {
    return ReadEnum<T>(reader, key, name, LastValue(T{}));
  } else if constexpr (std::is_same_v<T, JointValues>) {
    return ReadDoubles(reader, key, name);
  } else {
    FRI_TRY(sub, ReadSub(reader, key, name));
    return ReadFields<T>(*sub, key.offset);
  }
}

// Reads the value of field `key` into the member `kMember` of `message`.
template <auto kMember>
Status ReadMember(Reader& reader, const FieldKey& key, const char* name,
                  MessageOf<kMember>& message) {
  using Stored = typename MemberOf<decltype(kMember)>::Type;
  Stored& member = message.*kMember;
  if constexpr (kIsRepeated<Stored>) {
    if (member.size() >= kMaxJointValues) {
      return reader.MakeError(name, key.offset, "more than 32 values");
    }
    FRI_TRY(value, ReadValue<typename Stored::value_type>(reader, key, name));
    member.push_back(*value);
  } else if constexpr (kIsOptional<Stored>) {
    FRI_TRY(value, ReadValue<typename Stored::value_type>(reader, key, name));
    member = std::move(*value);
  } else {
    FRI_TRY(value, ReadValue<Stored>(reader, key, name));
    member = std::move(*value);
  }
  return OkStatus();
}

void WriteDoubles(Writer& w, std::uint32_t field, const std::vector<double>& values) {
  w.MessageField(field, [&](Writer& inner) {
    for (double v : values) inner.DoubleField(1, v);
  });
}

template <typename Message>
void WriteFields(Writer& writer, const Message& message) {
  for (const Field<Message>& field : FieldsOf<Message>())
    field.write(writer, field.number, message);
}

template <typename T>
void WriteValue(Writer& writer, std::uint32_t number, const T& value) {
  if constexpr (std::is_same_v<T, std::uint32_t>) {
    writer.VarintField(number, value);
  } else if constexpr (std::is_same_v<T, std::int32_t>) {
    writer.Int32Field(number, value);
  } else if constexpr (std::is_same_v<T, double>) {
    writer.DoubleField(number, value);
  } else if constexpr (std::is_enum_v<T>) {
    writer.Int32Field(number, static_cast<std::int32_t>(value));
  } else if constexpr (std::is_same_v<T, JointValues>) {
    WriteDoubles(writer, number, value);
  } else {
    writer.MessageField(number, [&](Writer& inner) { WriteFields(inner, value); });
  }
}

// Writes the member `kMember` of `message` as field `number`: an absent optional not at all, a
// repeated field once per value.
template <auto kMember>
void WriteMember(Writer& writer, std::uint32_t number, const MessageOf<kMember>& message) {
  using Stored = typename MemberOf<decltype(kMember)>::Type;
  const Stored& member = message.*kMember;
  if constexpr (kIsRepeated<Stored>) {
    for (const auto& value : member) WriteValue(writer, number, value);
  } else if constexpr (kIsOptional<Stored>) {
    if (member) WriteValue(writer, number, *member);
  } else {
    WriteValue(writer, number, member);
  }
}

template <auto kMember>
constexpr Field<MessageOf<kMember>> Member(std::uint32_t number, const char* name) {
  return {number, name, false, &ReadMember<kMember>, &WriteMember<kMember>};
}
template <auto kMember>
constexpr Field<MessageOf<kMember>> Required(std::uint32_t number, const char* name) {
  return {number, name, true, &ReadMember<kMember>, &WriteMember<kMember>};
}

template <>
std::span<const Field<MessageHeader>> FieldsOf() {
  static constexpr Field<MessageHeader> kFields[] = {
      Required<&MessageHeader::message_identifier>(1, "messageIdentifier"),
      Required<&MessageHeader::sequence_counter>(2, "sequenceCounter"),
      Required<&MessageHeader::reflected_sequence_counter>(3, "reflectedSequenceCounter"),
  };
  return kFields;
}

template <>
std::span<const Field<TimeStamp>> FieldsOf() {
  static constexpr Field<TimeStamp> kFields[] = {
      Required<&TimeStamp::sec>(1, "sec"),
      Required<&TimeStamp::nanosec>(2, "nanosec"),
  };
  return kFields;
}

template <>
std::span<const Field<ConnectionInfo>> FieldsOf() {
  static constexpr Field<ConnectionInfo> kFields[] = {
      Required<&ConnectionInfo::session_state>(1, "sessionState"),
      Required<&ConnectionInfo::quality>(2, "quality"),
      Member<&ConnectionInfo::send_period_ms>(3, "sendPeriod"),
      Member<&ConnectionInfo::receive_multiplier>(4, "receiveMultiplier"),
  };
  return kFields;
}

template <>
std::span<const Field<RobotInfo>> FieldsOf() {
  static constexpr Field<RobotInfo> kFields[] = {
      Member<&RobotInfo::number_of_joints>(1, "numberOfJoints"),
      Member<&RobotInfo::safety_state>(2, "safetyState"),
      Member<&RobotInfo::drive_state>(5, "driveState"),
      Member<&RobotInfo::operation_mode>(6, "operationMode"),
      Member<&RobotInfo::control_mode>(7, "controlMode"),
  };
  return kFields;
}

template <>
std::span<const Field<MonitorData>> FieldsOf() {
  static constexpr Field<MonitorData> kFields[] = {
      Member<&MonitorData::measured_joint_position>(1, "measuredJointPosition"),
      Member<&MonitorData::measured_torque>(2, "measuredTorque"),
      Member<&MonitorData::commanded_joint_position>(3, "commandedJointPosition"),
      Member<&MonitorData::commanded_torque>(4, "commandedTorque"),
      Member<&MonitorData::external_torque>(5, "externalTorque"),
      Member<&MonitorData::timestamp>(15, "timestamp"),
  };
  return kFields;
}

template <>
std::span<const Field<IpoData>> FieldsOf() {
  static constexpr Field<IpoData> kFields[] = {
      Member<&IpoData::joint_position>(1, "jointPosition"),
      Member<&IpoData::client_command_mode>(10, "clientCommandMode"),
      Member<&IpoData::overlay_type>(11, "overlayType"),
      Member<&IpoData::tracking_performance>(12, "trackingPerformance"),
  };
  return kFields;
}

// MessageEndOf.messageChecksum, a message of one field, is kept flat in EndOfMessage (crc32, and
// has_checksum for a checksum message without it).
struct Checksum {
  std::optional<std::int32_t> crc32;
};

template <>
std::span<const Field<Checksum>> FieldsOf() {
  static constexpr Field<Checksum> kFields[] = {Member<&Checksum::crc32>(1, "crc32")};
  return kFields;
}

Status ReadChecksum(Reader& reader, const FieldKey& key, const char* name, EndOfMessage& end) {
  FRI_TRY(checksum, ReadValue<Checksum>(reader, key, name));
  end.has_checksum = true;
  if (checksum->crc32) end.crc32 = checksum->crc32;
  return OkStatus();
}

void WriteChecksum(Writer& writer, std::uint32_t number, const EndOfMessage& end) {
  if (end.has_checksum || end.crc32) WriteValue(writer, number, Checksum{end.crc32});
}

template <>
std::span<const Field<EndOfMessage>> FieldsOf() {
  static constexpr Field<EndOfMessage> kFields[] = {
      Member<&EndOfMessage::message_length>(1, "messageLength"),
      {2, "messageChecksum", false, &ReadChecksum, &WriteChecksum},
  };
  return kFields;
}

template <>
std::span<const Field<CommandData>> FieldsOf() {
  static constexpr Field<CommandData> kFields[] = {
      Member<&CommandData::joint_position>(1, "jointPosition"),
      Member<&CommandData::cartesian_wrench_feed_forward>(2, "cartesianWrenchFeedForward"),
      Member<&CommandData::joint_torque>(3, "jointTorque"),
  };
  return kFields;
}

template <>
std::span<const Field<MonitoringMessage>> FieldsOf() {
  static constexpr Field<MonitoringMessage> kFields[] = {
      Required<&MonitoringMessage::header>(1, "header"),
      Member<&MonitoringMessage::robot_info>(2, "robotInfo"),
      Member<&MonitoringMessage::monitor_data>(3, "monitorData"),
      Member<&MonitoringMessage::connection_info>(4, "connectionInfo"),
      Member<&MonitoringMessage::ipo_data>(5, "ipoData"),
      Member<&MonitoringMessage::end_of_message>(15, "endOfMessageData"),
  };
  return kFields;
}

template <>
std::span<const Field<CommandMessage>> FieldsOf() {
  static constexpr Field<CommandMessage> kFields[] = {
      Required<&CommandMessage::header>(1, "header"),
      Member<&CommandMessage::command_data>(2, "commandData"),
      Member<&CommandMessage::end_of_message>(15, "endOfMessageData"),
  };
  return kFields;
}

Status CheckSize(std::span<const std::uint8_t> bytes, const char* what) {
  if (bytes.empty()) return Error{std::string("byte 0: ") + what + ": empty datagram"};
  if (bytes.size() > kMaxMessageBytes) {
    return Error{std::string("byte ") + std::to_string(kMaxMessageBytes) + ": " + what + ": " +
                 std::to_string(bytes.size()) + " bytes exceed the FRI limit of 1500"};
  }
  return OkStatus();
}

template <typename Message>
Expected<Message> Decode(std::span<const std::uint8_t> bytes, const char* what) {
  FRI_TRY(size_ok, CheckSize(bytes, what));
  Reader reader(bytes, 0, what);
  return ReadFields<Message>(reader, 0);
}

bool TooMany(const std::optional<std::vector<double>>& values) {
  return values && values->size() > kMaxJointValues;
}

template <typename Message>
Expected<std::size_t> Encode(const Message& message, std::span<std::uint8_t> out,
                             const char* what) {
  Writer w(out);
  WriteFields(w, message);
  if (w.overflow()) {
    return Error{std::string(what) + ": needs more than the " + std::to_string(out.size()) +
                 " bytes of the output buffer"};
  }
  return w.size();
}

}  // namespace

Expected<MonitoringMessage> DecodeMonitoringMessage(std::span<const std::uint8_t> bytes) {
  return Decode<MonitoringMessage>(bytes, "FRIMonitoringMessage");
}

Expected<CommandMessage> DecodeCommandMessage(std::span<const std::uint8_t> bytes) {
  return Decode<CommandMessage>(bytes, "FRICommandMessage");
}

Expected<std::size_t> EncodeMonitoringMessage(const MonitoringMessage& message,
                                              std::span<std::uint8_t> out) {
  if (message.monitor_data) {
    const auto& d = *message.monitor_data;
    if (TooMany(d.measured_joint_position) || TooMany(d.measured_torque) ||
        TooMany(d.commanded_joint_position) || TooMany(d.commanded_torque) ||
        TooMany(d.external_torque)) {
      return Error{"FRIMonitoringMessage.monitorData: more than 32 joint values"};
    }
  }
  if (message.ipo_data && TooMany(message.ipo_data->joint_position)) {
    return Error{"FRIMonitoringMessage.ipoData.jointPosition: more than 32 joint values"};
  }
  return Encode(message, out, "FRIMonitoringMessage");
}

Expected<std::size_t> EncodeCommandMessage(const CommandMessage& message,
                                           std::span<std::uint8_t> out) {
  if (message.command_data) {
    const auto& d = *message.command_data;
    if (TooMany(d.joint_position) || TooMany(d.joint_torque) ||
        TooMany(d.cartesian_wrench_feed_forward)) {
      return Error{"FRICommandMessage.commandData: more than 32 values"};
    }
  }
  return Encode(message, out, "FRICommandMessage");
}

}  // namespace selfcal::fri

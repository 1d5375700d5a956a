#include "protocols/fri/fri_codec.h"

#include <string>

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

Expected<MessageHeader> ReadHeader(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "header"));
  MessageHeader header;
  bool has[3] = {false, false, false};
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    std::uint32_t* target = nullptr;
    const char* name = nullptr;
    switch (key->number) {
      case 1:
        target = &header.message_identifier;
        name = "messageIdentifier";
        break;
      case 2:
        target = &header.sequence_counter;
        name = "sequenceCounter";
        break;
      case 3:
        target = &header.reflected_sequence_counter;
        name = "reflectedSequenceCounter";
        break;
      default: {
        FRI_TRY(skipped, reader->Skip(*key));
        continue;
      }
    }
    FRI_TRY(value, ReadUint32(*reader, *key, name));
    *target = *value;
    has[key->number - 1] = true;
  }
  const char* names[3] = {"messageIdentifier", "sequenceCounter", "reflectedSequenceCounter"};
  for (int i = 0; i < 3; ++i) {
    if (!has[i]) return reader->MakeError(names[i], parent_key.offset, "required field missing");
  }
  return header;
}

Expected<TimeStamp> ReadTimeStamp(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "timestamp"));
  TimeStamp stamp;
  bool has_sec = false, has_nanosec = false;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    if (key->number == 1) {
      FRI_TRY(v, ReadUint32(*reader, *key, "sec"));
      stamp.sec = *v;
      has_sec = true;
    } else if (key->number == 2) {
      FRI_TRY(v, ReadUint32(*reader, *key, "nanosec"));
      stamp.nanosec = *v;
      has_nanosec = true;
    } else {
      FRI_TRY(skipped, reader->Skip(*key));
    }
  }
  if (!has_sec) return reader->MakeError("sec", parent_key.offset, "required field missing");
  if (!has_nanosec)
    return reader->MakeError("nanosec", parent_key.offset, "required field missing");
  if (stamp.nanosec >= 1000000000u) {
    return reader->MakeError("nanosec", parent_key.offset, "nanosec >= 1e9");
  }
  return stamp;
}

Expected<ConnectionInfo> ReadConnectionInfo(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "connectionInfo"));
  ConnectionInfo info;
  bool has_state = false, has_quality = false;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    switch (key->number) {
      case 1: {
        FRI_TRY(v, ReadEnum<SessionState>(*reader, *key, "sessionState", 4));
        info.session_state = *v;
        has_state = true;
        break;
      }
      case 2: {
        FRI_TRY(v, ReadEnum<ConnectionQuality>(*reader, *key, "quality", 3));
        info.quality = *v;
        has_quality = true;
        break;
      }
      case 3: {
        FRI_TRY(v, ReadUint32(*reader, *key, "sendPeriod"));
        info.send_period_ms = *v;
        break;
      }
      case 4: {
        FRI_TRY(v, ReadUint32(*reader, *key, "receiveMultiplier"));
        info.receive_multiplier = *v;
        break;
      }
      default: {
        FRI_TRY(skipped, reader->Skip(*key));
      }
    }
  }
  if (!has_state) {
    return reader->MakeError("sessionState", parent_key.offset, "required field missing");
  }
  if (!has_quality)
    return reader->MakeError("quality", parent_key.offset, "required field missing");
  return info;
}

Expected<RobotInfo> ReadRobotInfo(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "robotInfo"));
  RobotInfo info;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    switch (key->number) {
      case 1: {
        FRI_TRY(v, ReadInt32(*reader, *key, "numberOfJoints"));
        info.number_of_joints = *v;
        break;
      }
      case 2: {
        FRI_TRY(v, ReadEnum<SafetyState>(*reader, *key, "safetyState", 3));
        info.safety_state = *v;
        break;
      }
      case 5: {
        if (info.drive_state.size() >= kMaxJointValues) {
          return reader->MakeError("driveState", key->offset, "more than 32 values");
        }
        FRI_TRY(v, ReadEnum<DriveState>(*reader, *key, "driveState", 2));
        info.drive_state.push_back(*v);
        break;
      }
      case 6: {
        FRI_TRY(v, ReadEnum<OperationMode>(*reader, *key, "operationMode", 2));
        info.operation_mode = *v;
        break;
      }
      case 7: {
        FRI_TRY(v, ReadEnum<ControlMode>(*reader, *key, "controlMode", 3));
        info.control_mode = *v;
        break;
      }
      default: {
        FRI_TRY(skipped, reader->Skip(*key));
      }
    }
  }
  return info;
}

Expected<MonitorData> ReadMonitorData(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "monitorData"));
  MonitorData data;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    std::optional<JointValues>* target = nullptr;
    const char* name = nullptr;
    switch (key->number) {
      case 1:
        target = &data.measured_joint_position;
        name = "measuredJointPosition";
        break;
      case 2:
        target = &data.measured_torque;
        name = "measuredTorque";
        break;
      case 3:
        target = &data.commanded_joint_position;
        name = "commandedJointPosition";
        break;
      case 4:
        target = &data.commanded_torque;
        name = "commandedTorque";
        break;
      case 5:
        target = &data.external_torque;
        name = "externalTorque";
        break;
      case 15: {
        FRI_TRY(stamp, ReadTimeStamp(*reader, *key));
        data.timestamp = *stamp;
        continue;
      }
      default: {
        FRI_TRY(skipped, reader->Skip(*key));
        continue;
      }
    }
    FRI_TRY(values, ReadDoubles(*reader, *key, name));
    *target = std::move(*values);
  }
  return data;
}

Expected<IpoData> ReadIpoData(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "ipoData"));
  IpoData data;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    switch (key->number) {
      case 1: {
        FRI_TRY(v, ReadDoubles(*reader, *key, "jointPosition"));
        data.joint_position = std::move(*v);
        break;
      }
      case 10: {
        FRI_TRY(v, ReadEnum<ClientCommandMode>(*reader, *key, "clientCommandMode", 3));
        data.client_command_mode = *v;
        break;
      }
      case 11: {
        FRI_TRY(v, ReadEnum<OverlayType>(*reader, *key, "overlayType", 2));
        data.overlay_type = *v;
        break;
      }
      case 12: {
        FRI_TRY(v, ReadDouble(*reader, *key, "trackingPerformance"));
        data.tracking_performance = *v;
        break;
      }
      default: {
        FRI_TRY(skipped, reader->Skip(*key));
      }
    }
  }
  return data;
}

Expected<EndOfMessage> ReadEndOfMessage(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "endOfMessageData"));
  EndOfMessage end;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    if (key->number == 1) {
      FRI_TRY(v, ReadInt32(*reader, *key, "messageLength"));
      end.message_length = *v;
    } else if (key->number == 2) {
      FRI_TRY(checksum, ReadSub(*reader, *key, "messageChecksum"));
      end.has_checksum = true;
      while (!checksum->AtEnd()) {
        FRI_TRY(inner, checksum->NextKey());
        if (inner->number == 1) {
          FRI_TRY(v, ReadInt32(*checksum, *inner, "crc32"));
          end.crc32 = *v;
        } else {
          FRI_TRY(skipped, checksum->Skip(*inner));
        }
      }
    } else {
      FRI_TRY(skipped, reader->Skip(*key));
    }
  }
  return end;
}

Expected<CommandData> ReadCommandData(Reader& parent, const FieldKey& parent_key) {
  FRI_TRY(reader, ReadSub(parent, parent_key, "commandData"));
  CommandData data;
  while (!reader->AtEnd()) {
    FRI_TRY(key, reader->NextKey());
    switch (key->number) {
      case 1: {
        FRI_TRY(v, ReadDoubles(*reader, *key, "jointPosition"));
        data.joint_position = std::move(*v);
        break;
      }
      case 2: {
        FRI_TRY(v, ReadDoubles(*reader, *key, "cartesianWrenchFeedForward"));
        data.cartesian_wrench_feed_forward = std::move(*v);
        break;
      }
      case 3: {
        FRI_TRY(v, ReadDoubles(*reader, *key, "jointTorque"));
        data.joint_torque = std::move(*v);
        break;
      }
      default: {
        FRI_TRY(skipped, reader->Skip(*key));
      }
    }
  }
  return data;
}

Status CheckSize(std::span<const std::uint8_t> bytes, const char* what) {
  if (bytes.empty()) return Error{std::string("byte 0: ") + what + ": empty datagram"};
  if (bytes.size() > kMaxMessageBytes) {
    return Error{std::string("byte ") + std::to_string(kMaxMessageBytes) + ": " + what + ": " +
                 std::to_string(bytes.size()) + " bytes exceed the FRI limit of 1500"};
  }
  return OkStatus();
}

// --- encoding --------------------------------------------------------------------------------

void WriteDoubles(Writer& w, std::uint32_t field, const std::vector<double>& values) {
  w.MessageField(field, [&](Writer& inner) {
    for (double v : values) inner.DoubleField(1, v);
  });
}

void WriteHeader(Writer& w, const MessageHeader& header) {
  w.MessageField(1, [&](Writer& inner) {
    inner.VarintField(1, header.message_identifier);
    inner.VarintField(2, header.sequence_counter);
    inner.VarintField(3, header.reflected_sequence_counter);
  });
}

void WriteEndOfMessage(Writer& w, const EndOfMessage& end) {
  w.MessageField(15, [&](Writer& inner) {
    if (end.message_length) inner.Int32Field(1, *end.message_length);
    if (end.has_checksum || end.crc32) {
      inner.MessageField(2, [&](Writer& checksum) {
        if (end.crc32) checksum.Int32Field(1, *end.crc32);
      });
    }
  });
}

bool TooMany(const std::optional<std::vector<double>>& values) {
  return values && values->size() > kMaxJointValues;
}

Expected<std::size_t> Finish(const Writer& w, std::size_t capacity, const char* what) {
  if (w.overflow()) {
    return Error{std::string(what) + ": needs more than the " + std::to_string(capacity) +
                 " bytes of the output buffer"};
  }
  return w.size();
}

// The top level both messages share: a required header (field 1) and the end of message
// (field 15). `read_body` reads the other fields it knows and returns false for the rest, which
// are skipped.
template <typename Message, typename ReadBody>
Expected<Message> DecodeTopLevel(std::span<const std::uint8_t> bytes, const char* what,
                                 ReadBody read_body) {
  FRI_TRY(size_ok, CheckSize(bytes, what));
  Reader reader(bytes, 0, what);
  Message message;
  bool has_header = false;
  while (!reader.AtEnd()) {
    FRI_TRY(key, reader.NextKey());
    if (key->number == 1) {
      FRI_TRY(v, ReadHeader(reader, *key));
      message.header = *v;
      has_header = true;
    } else if (key->number == 15) {
      FRI_TRY(v, ReadEndOfMessage(reader, *key));
      message.end_of_message = *v;
    } else {
      FRI_TRY(known, read_body(reader, *key, message));
      if (!*known) {
        FRI_TRY(skipped, reader.Skip(*key));
      }
    }
  }
  if (!has_header) return reader.MakeError("header", 0, "required field missing");
  return message;
}

Expected<bool> ReadMonitoringBody(Reader& reader, const FieldKey& key, MonitoringMessage& message) {
  switch (key.number) {
    case 2: {
      FRI_TRY(v, ReadRobotInfo(reader, key));
      message.robot_info = std::move(*v);
      return true;
    }
    case 3: {
      FRI_TRY(v, ReadMonitorData(reader, key));
      message.monitor_data = std::move(*v);
      return true;
    }
    case 4: {
      FRI_TRY(v, ReadConnectionInfo(reader, key));
      message.connection_info = *v;
      return true;
    }
    case 5: {
      FRI_TRY(v, ReadIpoData(reader, key));
      message.ipo_data = std::move(*v);
      return true;
    }
  }
  return false;
}

Expected<bool> ReadCommandBody(Reader& reader, const FieldKey& key, CommandMessage& message) {
  if (key.number != 2) return false;
  FRI_TRY(v, ReadCommandData(reader, key));
  message.command_data = std::move(*v);
  return true;
}

}  // namespace

Expected<MonitoringMessage> DecodeMonitoringMessage(std::span<const std::uint8_t> bytes) {
  return DecodeTopLevel<MonitoringMessage>(bytes, "FRIMonitoringMessage", ReadMonitoringBody);
}

Expected<CommandMessage> DecodeCommandMessage(std::span<const std::uint8_t> bytes) {
  return DecodeTopLevel<CommandMessage>(bytes, "FRICommandMessage", ReadCommandBody);
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
  Writer w(out);
  WriteHeader(w, message.header);
  if (message.robot_info) {
    const auto& info = *message.robot_info;
    w.MessageField(2, [&](Writer& inner) {
      if (info.number_of_joints) inner.Int32Field(1, *info.number_of_joints);
      if (info.safety_state) inner.Int32Field(2, static_cast<std::int32_t>(*info.safety_state));
      for (DriveState s : info.drive_state) inner.Int32Field(5, static_cast<std::int32_t>(s));
      if (info.operation_mode) inner.Int32Field(6, static_cast<std::int32_t>(*info.operation_mode));
      if (info.control_mode) inner.Int32Field(7, static_cast<std::int32_t>(*info.control_mode));
    });
  }
  if (message.monitor_data) {
    const auto& d = *message.monitor_data;
    w.MessageField(3, [&](Writer& inner) {
      if (d.measured_joint_position) WriteDoubles(inner, 1, *d.measured_joint_position);
      if (d.measured_torque) WriteDoubles(inner, 2, *d.measured_torque);
      if (d.commanded_joint_position) WriteDoubles(inner, 3, *d.commanded_joint_position);
      if (d.commanded_torque) WriteDoubles(inner, 4, *d.commanded_torque);
      if (d.external_torque) WriteDoubles(inner, 5, *d.external_torque);
      if (d.timestamp) {
        inner.MessageField(15, [&](Writer& stamp) {
          stamp.VarintField(1, d.timestamp->sec);
          stamp.VarintField(2, d.timestamp->nanosec);
        });
      }
    });
  }
  if (message.connection_info) {
    const auto& c = *message.connection_info;
    w.MessageField(4, [&](Writer& inner) {
      inner.Int32Field(1, static_cast<std::int32_t>(c.session_state));
      inner.Int32Field(2, static_cast<std::int32_t>(c.quality));
      if (c.send_period_ms) inner.VarintField(3, *c.send_period_ms);
      if (c.receive_multiplier) inner.VarintField(4, *c.receive_multiplier);
    });
  }
  if (message.ipo_data) {
    const auto& ipo = *message.ipo_data;
    w.MessageField(5, [&](Writer& inner) {
      if (ipo.joint_position) WriteDoubles(inner, 1, *ipo.joint_position);
      if (ipo.client_command_mode) {
        inner.Int32Field(10, static_cast<std::int32_t>(*ipo.client_command_mode));
      }
      if (ipo.overlay_type) inner.Int32Field(11, static_cast<std::int32_t>(*ipo.overlay_type));
      if (ipo.tracking_performance) inner.DoubleField(12, *ipo.tracking_performance);
    });
  }
  if (message.end_of_message) WriteEndOfMessage(w, *message.end_of_message);
  return Finish(w, out.size(), "FRIMonitoringMessage");
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
  Writer w(out);
  WriteHeader(w, message.header);
  if (message.command_data) {
    const auto& d = *message.command_data;
    w.MessageField(2, [&](Writer& inner) {
      if (d.joint_position) WriteDoubles(inner, 1, *d.joint_position);
      if (d.cartesian_wrench_feed_forward) WriteDoubles(inner, 2, *d.cartesian_wrench_feed_forward);
      if (d.joint_torque) WriteDoubles(inner, 3, *d.joint_torque);
    });
  }
  if (message.end_of_message) WriteEndOfMessage(w, *message.end_of_message);
  return Finish(w, out.size(), "FRICommandMessage");
}

}  // namespace selfcal::fri

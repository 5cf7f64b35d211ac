#include "hardware/protocol.h"

#include <algorithm>
#include <cmath>

namespace graspbed::hardware {
namespace {

void PutU16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}
void PutU32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
uint16_t GetU16(const uint8_t* p) { return static_cast<uint16_t>(p[0] | (p[1] << 8)); }
uint32_t GetU32(const uint8_t* p) {
  return static_cast<uint32_t>(p[0]) | (static_cast<uint32_t>(p[1]) << 8) |
         (static_cast<uint32_t>(p[2]) << 16) | (static_cast<uint32_t>(p[3]) << 24);
}

void PutHeader(uint8_t* body, PacketType type, uint16_t sequence, uint8_t version = kBaseProtocolVersion) {
  body[0] = static_cast<uint8_t>(type);
  body[1] = version;
  PutU16(body + 2, sequence);
}

int32_t ToWireI32(double value, double scale) {
  if (!std::isfinite(value)) return 0;
  const double scaled = std::round(value * scale);
  return static_cast<int32_t>(std::clamp(scaled, -2147483647.0, 2147483647.0));
}

void PutHandDigit(uint8_t* p, const HandDigitWire& digit) {
  p[0] = digit.joint_count;
  p[1] = digit.flags;
  PutU16(p + 2, 0);
  for (int j = 0; j < kMaxHandJoints; ++j) {
    PutU32(p + 4 + 4 * j, static_cast<uint32_t>(digit.position[j]));
    PutU32(p + 12 + 4 * j, static_cast<uint32_t>(digit.velocity[j]));
  }
  PutU32(p + 20, static_cast<uint32_t>(digit.motor_current_ua));
  PutU32(p + 24, digit.stall_current_ua);
}

void GetHandDigit(const uint8_t* p, HandDigitWire* digit) {
  digit->joint_count = p[0];
  digit->flags = p[1];
  for (int j = 0; j < kMaxHandJoints; ++j) {
    digit->position[j] = static_cast<int32_t>(GetU32(p + 4 + 4 * j));
    digit->velocity[j] = static_cast<int32_t>(GetU32(p + 12 + 4 * j));
  }
  digit->motor_current_ua = static_cast<int32_t>(GetU32(p + 20));
  digit->stall_current_ua = GetU32(p + 24);
}

PacketError ParseFrame(std::span<const uint8_t> body, TactileFramePacket* frame) {
  const uint8_t* p = body.data();
  if (body.size() < 10) return PacketError::kBadLength;
  const uint8_t n = p[8];
  if (n < 1 || n > kMaxFrameUnits) return PacketError::kBadUnitCount;
  if (body.size() != TactileFrameBodySize(n)) return PacketError::kBadLength;
  frame->device_time_us = GetU32(p + 4);
  frame->unit_count = n;
  frame->flags = p[9];
  for (int k = 0; k < n; ++k) {
    frame->r1_milliohm[k] = GetU32(p + 10 + 8 * k);
    frame->r2_milliohm[k] = GetU32(p + 14 + 8 * k);
  }
  return PacketError::kNone;
}

PacketError ParseHand(std::span<const uint8_t> body, HandPacket* hand) {
  const uint8_t* p = body.data();
  if (body.size() < 10) return PacketError::kBadLength;
  const uint8_t n = p[8];
  if (n < 1 || n > kMaxHandDigits) return PacketError::kBadHandCount;
  if (body.size() != HandBodySize(n)) return PacketError::kBadLength;
  for (int d = 0; d < n; ++d) {
    if (p[10 + kHandDigitWireSize * static_cast<size_t>(d)] > kMaxHandJoints)
      return PacketError::kBadHandCount;
  }
  hand->device_time_us = GetU32(p + 4);
  hand->digit_count = n;
  for (int d = 0; d < n; ++d)
    GetHandDigit(p + 10 + kHandDigitWireSize * static_cast<size_t>(d), &hand->digits[d]);
  for (int d = n; d < kMaxHandDigits; ++d) hand->digits[d] = HandDigitWire{};
  return PacketError::kNone;
}

PacketError ParseBaseType(PacketType type, std::span<const uint8_t> body, DecodedPacket* packet) {
  const uint8_t* p = body.data();
  switch (type) {
    case PacketType::kTactileFrame:
      return ParseFrame(body, &packet->frame);
    case PacketType::kHello:
      if (body.size() != kHelloBodySize) return PacketError::kBadLength;
      packet->hello.firmware_version = GetU16(p + 4);
      packet->hello.unit_count = p[6];
      packet->hello.max_version = p[7];
      packet->hello.nominal_rate_hz = GetU16(p + 8);
      packet->hello.nominal_r0_milliohm = GetU32(p + 12);
      return PacketError::kNone;
    case PacketType::kMotorCommand:
      if (body.size() != kMotorCommandBodySize) return PacketError::kBadLength;
      packet->motor.effort = static_cast<int16_t>(GetU16(p + 4));
      packet->motor.flags = p[6];
      return PacketError::kNone;
    case PacketType::kStreamControl:
      if (body.size() != kStreamControlBodySize) return PacketError::kBadLength;
      packet->stream.start = p[4] == 1;
      return PacketError::kNone;
    default:
      return PacketError::kUnknownType;
  }
}

void SetSequence(PacketType type, uint16_t sequence, DecodedPacket* packet) {
  switch (type) {
    case PacketType::kTactileFrame:
      packet->frame.sequence = sequence;
      break;
    case PacketType::kHello:
      packet->hello.sequence = sequence;
      break;
    case PacketType::kHand:
      packet->hand.sequence = sequence;
      break;
    case PacketType::kMotorCommand:
      packet->motor.sequence = sequence;
      break;
    case PacketType::kStreamControl:
      packet->stream.sequence = sequence;
      break;
    case PacketType::kProtocolSelect:
      packet->select.sequence = sequence;
      break;
  }
}

// Appends the CRC to `body_size` bytes in `scratch`, COBS-encodes into `out` and adds the delimiter.
size_t Finish(std::array<uint8_t, kMaxPacketSize>& scratch, size_t body_size, std::span<uint8_t> out) {
  const uint16_t crc = Crc16CcittFalse(std::span<const uint8_t>(scratch.data(), body_size));
  PutU16(scratch.data() + body_size, crc);
  const size_t packet_size = body_size + kCrcSize;
  if (out.size() < CobsMaxEncodedSize(packet_size) + 1) return 0;
  const auto encoded =
      CobsEncode(std::span<const uint8_t>(scratch.data(), packet_size), out.first(out.size() - 1));
  if (!encoded) return 0;
  out[*encoded] = 0x00;
  return *encoded + 1;
}

}  // namespace

size_t EncodePacket(const TactileFramePacket& packet, std::span<uint8_t> out) {
  if (packet.unit_count < 1 || packet.unit_count > kMaxUnitsOnWire) return 0;
  std::array<uint8_t, kMaxPacketSize> body;
  PutHeader(body.data(), PacketType::kTactileFrame, packet.sequence);
  PutU32(body.data() + 4, packet.device_time_us);
  body[8] = packet.unit_count;
  body[9] = packet.flags;
  for (int k = 0; k < packet.unit_count; ++k) {
    PutU32(body.data() + 10 + 8 * k, packet.r1_milliohm[k]);
    PutU32(body.data() + 14 + 8 * k, packet.r2_milliohm[k]);
  }
  return Finish(body, TactileFrameBodySize(packet.unit_count), out);
}

size_t EncodePacket(const HelloPacket& packet, std::span<uint8_t> out) {
  std::array<uint8_t, kMaxPacketSize> body;
  PutHeader(body.data(), PacketType::kHello, packet.sequence);
  PutU16(body.data() + 4, packet.firmware_version);
  body[6] = packet.unit_count;
  body[7] = packet.max_version;
  PutU16(body.data() + 8, packet.nominal_rate_hz);
  PutU16(body.data() + 10, 0);
  PutU32(body.data() + 12, packet.nominal_r0_milliohm);
  return Finish(body, kHelloBodySize, out);
}

size_t EncodePacket(const MotorCommandPacket& packet, std::span<uint8_t> out) {
  std::array<uint8_t, kMaxPacketSize> body;
  PutHeader(body.data(), PacketType::kMotorCommand, packet.sequence);
  PutU16(body.data() + 4, static_cast<uint16_t>(packet.effort));
  body[6] = packet.flags;
  body[7] = 0;
  return Finish(body, kMotorCommandBodySize, out);
}

size_t EncodePacket(const StreamControlPacket& packet, std::span<uint8_t> out) {
  std::array<uint8_t, kMaxPacketSize> body;
  PutHeader(body.data(), PacketType::kStreamControl, packet.sequence);
  body[4] = packet.start ? 1 : 0;
  return Finish(body, kStreamControlBodySize, out);
}

size_t EncodePacket(const HandPacket& packet, std::span<uint8_t> out) {
  if (packet.digit_count < 1 || packet.digit_count > kMaxHandDigits) return 0;
  std::array<uint8_t, kMaxPacketSize> body;
  PutHeader(body.data(), PacketType::kHand, packet.sequence, kHandProtocolVersion);
  PutU32(body.data() + 4, packet.device_time_us);
  body[8] = packet.digit_count;
  body[9] = 0;
  for (int d = 0; d < packet.digit_count; ++d) {
    if (packet.digits[d].joint_count > kMaxHandJoints) return 0;
    PutHandDigit(body.data() + 10 + kHandDigitWireSize * static_cast<size_t>(d), packet.digits[d]);
  }
  return Finish(body, HandBodySize(packet.digit_count), out);
}

size_t EncodePacket(const ProtocolSelectPacket& packet, std::span<uint8_t> out) {
  std::array<uint8_t, kMaxPacketSize> body;
  PutHeader(body.data(), PacketType::kProtocolSelect, packet.sequence, kHandProtocolVersion);
  body[4] = packet.version;
  body[5] = 0;
  return Finish(body, kProtocolSelectBodySize, out);
}

size_t EncodeBody(std::span<const uint8_t> body, std::span<uint8_t> out) {
  if (body.empty() || body.size() > kMaxPacketSize - kCrcSize) return 0;
  std::array<uint8_t, kMaxPacketSize> scratch;
  std::copy(body.begin(), body.end(), scratch.begin());
  return Finish(scratch, body.size(), out);
}

const char* ToString(PacketError error) {
  switch (error) {
    case PacketError::kNone:
      return "none";
    case PacketError::kCobs:
      return "cobs";
    case PacketError::kCrc:
      return "crc";
    case PacketError::kTooShort:
      return "too short";
    case PacketError::kTooLong:
      return "too long";
    case PacketError::kBadLength:
      return "bad length";
    case PacketError::kBadUnitCount:
      return "bad unit count";
    case PacketError::kBadHandCount:
      return "bad digit or joint count";
    case PacketError::kUnknownVersion:
      return "unknown version";
    case PacketError::kUnknownType:
      return "unknown type";
  }
  return "?";
}

PacketError ParseBody(std::span<const uint8_t> body, DecodedPacket* packet) {
  if (body.size() < kHeaderSize) return PacketError::kTooShort;
  const uint8_t* p = body.data();
  const uint8_t version = p[1];
  if (version < 1 || version > kProtocolVersion) return PacketError::kUnknownVersion;
  const auto type = static_cast<PacketType>(p[0]);
  PacketError error = PacketError::kUnknownType;
  if (type == PacketType::kHand || type == PacketType::kProtocolSelect) {
    // Version 2's own packets: a packet claiming version 1 is of a type version 1 does not define.
    if (version < kHandProtocolVersion) return PacketError::kUnknownType;
    if (type == PacketType::kHand) {
      error = ParseHand(body, &packet->hand);
    } else if (body.size() != kProtocolSelectBodySize) {
      error = PacketError::kBadLength;
    } else {
      packet->select.version = p[4];
      error = PacketError::kNone;
    }
  } else {
    error = ParseBaseType(type, body, packet);
  }
  if (error != PacketError::kNone) return error;
  SetSequence(type, GetU16(p + 2), packet);
  packet->type = type;
  return PacketError::kNone;
}

double MilliohmToOhm(uint32_t milliohm) {
  if (milliohm == kOpenCircuitMilliohm) return sensor::kOpenCircuitOhm;
  return static_cast<double>(milliohm) * 1e-3;
}

uint32_t OhmToMilliohm(double ohm) {
  if (!(ohm == ohm)) return kOpenCircuitMilliohm;  // NaN: no reading
  if (ohm <= 0.0) return 0;
  const double milliohm = std::round(ohm * 1e3);
  // The largest finite value is one below the open-circuit marker.
  if (milliohm >= static_cast<double>(kOpenCircuitMilliohm)) return kOpenCircuitMilliohm;
  return static_cast<uint32_t>(milliohm);
}

void ToRawFrame(const TactileFramePacket& packet, sensor::RawFrame* frame) {
  frame->sequence = packet.sequence;
  frame->time_s = static_cast<double>(packet.device_time_us) * 1e-6;
  frame->unit_count = packet.unit_count;
  frame->flags = packet.flags;
  for (int k = 0; k < packet.unit_count; ++k) {
    frame->r1_ohm[k] = MilliohmToOhm(packet.r1_milliohm[k]);
    frame->r2_ohm[k] = MilliohmToOhm(packet.r2_milliohm[k]);
  }
}

void FromRawFrame(const sensor::RawFrame& frame, uint16_t sequence, uint32_t device_time_us,
                  TactileFramePacket* packet) {
  packet->sequence = sequence;
  packet->device_time_us = device_time_us;
  const int n = std::clamp(frame.unit_count, 0, kMaxFrameUnits);
  packet->unit_count = static_cast<uint8_t>(n);
  packet->flags = frame.flags;
  for (int k = 0; k < n; ++k) {
    packet->r1_milliohm[k] = OhmToMilliohm(frame.r1_ohm[k]);
    packet->r2_milliohm[k] = OhmToMilliohm(frame.r2_ohm[k]);
  }
}

void ToHandState(const HandPacket& packet, hand::HandState* state) {
  state->digit_count = std::min<int>(packet.digit_count, hand::kMaxDigits);
  for (int d = 0; d < hand::kMaxDigits; ++d) {
    hand::DigitState& digit = state->digits[d];
    digit = hand::DigitState{};
    if (d >= state->digit_count) continue;
    const HandDigitWire& wire = packet.digits[d];
    digit.joint_count = std::min<int>(wire.joint_count, hand::kMaxDigitJoints);
    digit.linear = (wire.flags & kHandLinear) != 0;
    digit.position_known = (wire.flags & kHandPositionKnown) != 0 && digit.joint_count > 0;
    digit.velocity_known = (wire.flags & kHandVelocityKnown) != 0 && digit.joint_count > 0;
    for (int j = 0; j < digit.joint_count; ++j) {
      if (digit.position_known) digit.joint_position[j] = wire.position[j] * 1e-6;
      if (digit.velocity_known) digit.joint_velocity[j] = wire.velocity[j] * 1e-6;
    }
    digit.current_known = (wire.flags & kHandCurrentKnown) != 0;
    if (digit.current_known) digit.motor_current_a = wire.motor_current_ua * 1e-6;
    digit.stall_current_a = wire.stall_current_ua * 1e-6;
    digit.stops_known = (wire.flags & kHandStopsKnown) != 0;
    digit.at_open_stop = digit.stops_known && (wire.flags & kHandAtOpenStop) != 0;
    digit.at_closed_stop = digit.stops_known && (wire.flags & kHandAtClosedStop) != 0;
    digit.encoder_fault = (wire.flags & kHandEncoderFault) != 0;
  }
}

void FromHandState(const hand::HandState& state, uint16_t sequence, uint32_t device_time_us,
                   HandPacket* packet) {
  packet->sequence = sequence;
  packet->device_time_us = device_time_us;
  packet->digit_count = static_cast<uint8_t>(std::clamp(state.digit_count, 0, kMaxHandDigits));
  for (int d = 0; d < kMaxHandDigits; ++d) {
    HandDigitWire& wire = packet->digits[d];
    wire = HandDigitWire{};
    if (d >= packet->digit_count) continue;
    const hand::DigitState& digit = state.digits[d];
    wire.joint_count = static_cast<uint8_t>(std::clamp(digit.joint_count, 0, kMaxHandJoints));
    if (digit.linear) wire.flags |= kHandLinear;
    if (digit.position_known) wire.flags |= kHandPositionKnown;
    if (digit.velocity_known) wire.flags |= kHandVelocityKnown;
    if (digit.current_known) wire.flags |= kHandCurrentKnown;
    if (digit.stops_known) wire.flags |= kHandStopsKnown;
    if (digit.stops_known && digit.at_open_stop) wire.flags |= kHandAtOpenStop;
    if (digit.stops_known && digit.at_closed_stop) wire.flags |= kHandAtClosedStop;
    if (digit.encoder_fault) wire.flags |= kHandEncoderFault;
    for (int j = 0; j < wire.joint_count; ++j) {
      wire.position[j] = digit.position_known ? ToWireI32(digit.joint_position[j], 1e6) : 0;
      wire.velocity[j] = digit.velocity_known ? ToWireI32(digit.joint_velocity[j], 1e6) : 0;
    }
    wire.motor_current_ua = digit.current_known ? ToWireI32(digit.motor_current_a, 1e6) : 0;
    const double stall_ua =
        std::isfinite(digit.stall_current_a) ? std::round(digit.stall_current_a * 1e6) : 0.0;
    wire.stall_current_ua = static_cast<uint32_t>(std::clamp(stall_ua, 0.0, 4294967295.0));
  }
}

int16_t EffortToWire(double effort) {
  if (!(effort == effort)) return 0;
  return static_cast<int16_t>(std::lround(std::clamp(effort, -1.0, 1.0) * 32767.0));
}

double EffortFromWire(int16_t effort) { return std::clamp(static_cast<double>(effort) / 32767.0, -1.0, 1.0); }

}  // namespace graspbed::hardware

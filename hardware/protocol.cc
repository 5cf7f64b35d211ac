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

void PutHeader(uint8_t* body, PacketType type, uint16_t sequence) {
  body[0] = static_cast<uint8_t>(type);
  body[1] = kProtocolVersion;
  PutU16(body + 2, sequence);
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
  body[7] = 0;
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
  if (p[1] != kProtocolVersion) return PacketError::kUnknownVersion;
  const uint16_t sequence = GetU16(p + 2);
  switch (static_cast<PacketType>(p[0])) {
    case PacketType::kTactileFrame: {
      if (body.size() < 10) return PacketError::kBadLength;
      const uint8_t n = p[8];
      if (n < 1 || n > kMaxFrameUnits) return PacketError::kBadUnitCount;
      if (body.size() != TactileFrameBodySize(n)) return PacketError::kBadLength;
      TactileFramePacket& frame = packet->frame;
      frame.sequence = sequence;
      frame.device_time_us = GetU32(p + 4);
      frame.unit_count = n;
      frame.flags = p[9];
      for (int k = 0; k < n; ++k) {
        frame.r1_milliohm[k] = GetU32(p + 10 + 8 * k);
        frame.r2_milliohm[k] = GetU32(p + 14 + 8 * k);
      }
      packet->type = PacketType::kTactileFrame;
      return PacketError::kNone;
    }
    case PacketType::kHello: {
      if (body.size() != kHelloBodySize) return PacketError::kBadLength;
      HelloPacket& hello = packet->hello;
      hello.sequence = sequence;
      hello.firmware_version = GetU16(p + 4);
      hello.unit_count = p[6];
      hello.nominal_rate_hz = GetU16(p + 8);
      hello.nominal_r0_milliohm = GetU32(p + 12);
      packet->type = PacketType::kHello;
      return PacketError::kNone;
    }
    case PacketType::kMotorCommand: {
      if (body.size() != kMotorCommandBodySize) return PacketError::kBadLength;
      packet->motor.sequence = sequence;
      packet->motor.effort = static_cast<int16_t>(GetU16(p + 4));
      packet->motor.flags = p[6];
      packet->type = PacketType::kMotorCommand;
      return PacketError::kNone;
    }
    case PacketType::kStreamControl: {
      if (body.size() != kStreamControlBodySize) return PacketError::kBadLength;
      packet->stream.sequence = sequence;
      packet->stream.start = p[4] == 1;
      packet->type = PacketType::kStreamControl;
      return PacketError::kNone;
    }
  }
  return PacketError::kUnknownType;
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

int16_t EffortToWire(double effort) {
  if (!(effort == effort)) return 0;
  return static_cast<int16_t>(std::lround(std::clamp(effort, -1.0, 1.0) * 32767.0));
}

double EffortFromWire(int16_t effort) { return std::clamp(static_cast<double>(effort) / 32767.0, -1.0, 1.0); }

}  // namespace graspbed::hardware

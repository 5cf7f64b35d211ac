#pragma once
/// Packets of wire protocol version 1 (docs/protocol.md): their fields as plain structs, and encoding to /
/// decoding from wire bytes. Fixed-size storage throughout, so nothing here allocates.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sensor/raw_frame.h"
#include "hardware/framing.h"

namespace graspbed::hardware {

/// The protocol version this code speaks (header byte 1).
inline constexpr uint8_t kProtocolVersion = 1;
/// Largest decoded packet (body + CRC) [bytes]; anything longer is an error.
inline constexpr size_t kMaxPacketSize = 512;
/// Largest packet on the wire: COBS encoding of kMaxPacketSize bytes plus the 0x00 delimiter [bytes].
inline constexpr size_t kMaxWirePacketSize = CobsMaxEncodedSize(kMaxPacketSize) + 1;
/// Common header length (type, version, sequence) [bytes].
inline constexpr size_t kHeaderSize = 4;
/// CRC trailer length [bytes].
inline constexpr size_t kCrcSize = 2;
/// Largest value of the unit count field (docs/protocol.md: 1..64).
inline constexpr int kMaxFrameUnits = 64;
/// Most units that fit the 512-byte packet limit: 10 + 8N + 2 <= 512 gives N <= 62. The count field
/// goes up to 64 (docs/protocol.md), but frames of 63 or 64 units would exceed the maximum packet
/// size; they are refused by the encoder and arrive at the decoder as too-long packets.
inline constexpr int kMaxUnitsOnWire = 62;
/// Wire value of a channel that reads open circuit [milliohm].
inline constexpr uint32_t kOpenCircuitMilliohm = 0xFFFFFFFFu;

static_assert(kMaxFrameUnits <= sensor::kMaxUnits, "RawFrame must hold every unit a frame can carry");

/// Packet type (header byte 0).
enum class PacketType : uint8_t {
  kTactileFrame = 0x01,   ///< device -> host
  kHello = 0x02,          ///< device -> host
  kMotorCommand = 0x81,   ///< host -> device
  kStreamControl = 0x82,  ///< host -> device
};

/// TACTILE_FRAME flag bits (byte 9).
inline constexpr uint8_t kFlagAdcOverrun = 0x01;
inline constexpr uint8_t kFlagSupplyFault = 0x02;

/// MOTOR_COMMAND flag bits (byte 6).
inline constexpr uint8_t kMotorEnable = 0x01;
inline constexpr uint8_t kMotorBrake = 0x02;

/// 0x01 TACTILE_FRAME: one sample of every unit.
struct TactileFramePacket {
  uint16_t sequence = 0;
  uint32_t device_time_us = 0;                         ///< device clock at the sample [us], wraps at 2^32
  uint8_t unit_count = 0;                              ///< 1..64
  uint8_t flags = 0;                                   ///< kFlagAdcOverrun | kFlagSupplyFault
  std::array<uint32_t, kMaxFrameUnits> r1_milliohm{};  ///< layout order; 0xFFFFFFFF open, 0 short
  std::array<uint32_t, kMaxFrameUnits> r2_milliohm{};
};

/// 0x02 HELLO: sent by the device on connect and every second.
struct HelloPacket {
  uint16_t sequence = 0;
  uint16_t firmware_version = 0;
  uint8_t unit_count = 0;
  uint16_t nominal_rate_hz = 0;      ///< nominal frame rate [Hz]
  uint32_t nominal_r0_milliohm = 0;  ///< nominal unstrained gauge resistance [milliohm]
};

/// 0x81 MOTOR_COMMAND: grip motor effort.
struct MotorCommandPacket {
  uint16_t sequence = 0;
  int16_t effort = 0;  ///< -32767..32767 maps to -1..1, positive closes
  uint8_t flags = 0;   ///< kMotorEnable | kMotorBrake
};

/// 0x82 STREAM_CONTROL: start (1) or stop (0) streaming frames.
struct StreamControlPacket {
  uint16_t sequence = 0;
  bool start = false;
};

/// Body sizes (header included, CRC excluded) [bytes].
inline constexpr size_t TactileFrameBodySize(int unit_count) {
  return 10 + 8 * static_cast<size_t>(unit_count);
}
inline constexpr size_t kHelloBodySize = 16;
inline constexpr size_t kMotorCommandBodySize = 8;
inline constexpr size_t kStreamControlBodySize = 5;

/// Encodes a packet as it goes on the wire: body + CRC, COBS-encoded, then the 0x00 delimiter.
/// Returns the number of bytes written, or 0 when `out` is too small (size it kMaxWirePacketSize)
/// or the packet is invalid (unit count outside 1..kMaxUnitsOnWire).
size_t EncodePacket(const TactileFramePacket& packet, std::span<uint8_t> out);
size_t EncodePacket(const HelloPacket& packet, std::span<uint8_t> out);
size_t EncodePacket(const MotorCommandPacket& packet, std::span<uint8_t> out);
size_t EncodePacket(const StreamControlPacket& packet, std::span<uint8_t> out);

/// Frames an arbitrary body (header included): appends its CRC, COBS-encodes, adds the delimiter.
/// For packets this version does not define (tests, fault injection). Returns bytes written or 0
/// when the body is empty or over kMaxPacketSize - kCrcSize, or `out` is too small.
size_t EncodeBody(std::span<const uint8_t> body, std::span<uint8_t> out);

/// Why a decoded packet was refused.
enum class PacketError : uint8_t {
  kNone,
  kCobs,            ///< malformed COBS blocks (bytes lost or corrupted)
  kCrc,             ///< CRC mismatch
  kTooShort,        ///< shorter than header + CRC
  kTooLong,         ///< over kMaxPacketSize without a delimiter
  kBadLength,       ///< body length does not match the packet type (or its unit count)
  kBadUnitCount,    ///< TACTILE_FRAME unit count outside 1..64
  kUnknownVersion,  ///< a protocol version other than kProtocolVersion
  kUnknownType,     ///< a packet type this version does not define
};

/// Short name of an error ("crc", "cobs", ...).
const char* ToString(PacketError error);

/// One decoded packet: `type` tells which member holds it. Fixed size, reused by the decoder.
struct DecodedPacket {
  PacketType type = PacketType::kHello;
  TactileFramePacket frame;
  HelloPacket hello;
  MotorCommandPacket motor;
  StreamControlPacket stream;
};

/// Parses a CRC-checked body (header included, CRC stripped) into `packet`. Reads only
/// body[0..body.size()); checks version, type and exact length.
PacketError ParseBody(std::span<const uint8_t> body, DecodedPacket* packet);

/// Converts a milliohm wire value to Ohm: 0xFFFFFFFF -> sensor::kOpenCircuitOhm, 0 -> 0 (short).
double MilliohmToOhm(uint32_t milliohm);
/// Converts Ohm to the wire value: inf/NaN or anything >= 0xFFFFFFFF mOhm -> open; < 0 -> 0.
uint32_t OhmToMilliohm(double ohm);

/// Fills `frame` from a decoded TACTILE_FRAME (times in seconds of device time).
void ToRawFrame(const TactileFramePacket& packet, sensor::RawFrame* frame);
/// Fills a TACTILE_FRAME from a RawFrame (sequence and device time given separately).
void FromRawFrame(const sensor::RawFrame& frame, uint16_t sequence, uint32_t device_time_us,
                  TactileFramePacket* packet);

/// Motor effort in [-1, 1] to the wire's i16 (clamped), and back.
int16_t EffortToWire(double effort);
double EffortFromWire(int16_t effort);

}  // namespace graspbed::hardware

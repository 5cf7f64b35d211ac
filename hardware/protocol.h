#pragma once
/// Packets of wire protocol version 2 (docs/protocol.md): their fields as plain structs, and encoding to /
/// decoding from wire bytes. Version 2 adds HAND (the hand's proprioception) and PROTOCOL_SELECT, and
/// the version a device speaks in HELLO; the packets of version 1 are unchanged and keep version byte
/// 1, so a version-1 receiver reads them. Fixed-size storage throughout, so nothing here allocates.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hand/hand_state.h"
#include "sensor/raw_frame.h"
#include "hardware/framing.h"

namespace graspbed::hardware {

/// The highest protocol version this code speaks; it accepts every version from 1 up to it.
inline constexpr uint8_t kProtocolVersion = 2;
/// The version byte (header byte 1) of the packets version 1 defines (HELLO, TACTILE_FRAME,
/// MOTOR_COMMAND, STREAM_CONTROL): unchanged in version 2, so they keep the byte a version-1
/// receiver accepts.
inline constexpr uint8_t kBaseProtocolVersion = 1;
/// The version that added HAND and PROTOCOL_SELECT (their version byte).
inline constexpr uint8_t kHandProtocolVersion = 2;
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
  kTactileFrame = 0x01,    ///< device -> host
  kHello = 0x02,           ///< device -> host
  kHand = 0x03,            ///< device -> host, version 2
  kMotorCommand = 0x81,    ///< host -> device
  kStreamControl = 0x82,   ///< host -> device
  kProtocolSelect = 0x83,  ///< host -> device, version 2
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

/// 0x02 HELLO: sent by the device on connect and every second (always with version byte 1).
struct HelloPacket {
  uint16_t sequence = 0;
  uint16_t firmware_version = 0;
  uint8_t unit_count = 0;
  /// Highest protocol version the device speaks (byte 7; reserved and 0 in a version-1 device, which
  /// reads as 1).
  uint8_t max_version = 0;
  uint16_t nominal_rate_hz = 0;      ///< nominal frame rate [Hz]
  uint32_t nominal_r0_milliohm = 0;  ///< nominal unstrained gauge resistance [milliohm]
};

/// The protocol version a HELLO says its device speaks: its max_version, 0 read as 1.
inline uint8_t DeviceVersion(const HelloPacket& hello) {
  return hello.max_version == 0 ? 1 : hello.max_version;
}

/// HAND flag bits (per digit, byte 1 of its block).
inline constexpr uint8_t kHandLinear = 0x01;  ///< slides: positions in [um], else hinges [urad]
inline constexpr uint8_t kHandPositionKnown = 0x02;
inline constexpr uint8_t kHandVelocityKnown = 0x04;
inline constexpr uint8_t kHandCurrentKnown = 0x08;
inline constexpr uint8_t kHandStopsKnown = 0x10;
inline constexpr uint8_t kHandAtOpenStop = 0x20;
inline constexpr uint8_t kHandAtClosedStop = 0x40;
inline constexpr uint8_t kHandEncoderFault = 0x80;
/// Most digits and joints per digit a HAND carries (the wire's limits, equal to the host's).
inline constexpr int kMaxHandDigits = 2;
inline constexpr int kMaxHandJoints = 2;
static_assert(kMaxHandDigits == hand::kMaxDigits && kMaxHandJoints == hand::kMaxDigitJoints);

/// One digit of a HAND packet, in wire units.
struct HandDigitWire {
  uint8_t joint_count = 0;                         ///< 0..kMaxHandJoints
  uint8_t flags = 0;                               ///< kHand* bits
  std::array<int32_t, kMaxHandJoints> position{};  ///< from the open pose [urad] or [um] (kHandLinear)
  std::array<int32_t, kMaxHandJoints> velocity{};  ///< [urad/s] or [um/s]
  int32_t motor_current_ua = 0;                    ///< drive motor current [uA], + closing
  uint32_t stall_current_ua = 0;                   ///< current at stall, full effort [uA]; 0 unknown
};

/// 0x03 HAND (version 2): the hand's proprioception at one sample.
struct HandPacket {
  uint16_t sequence = 0;
  uint32_t device_time_us = 0;  ///< device clock at the sample [us] (the TACTILE_FRAME clock)
  uint8_t digit_count = 0;      ///< 1..kMaxHandDigits
  std::array<HandDigitWire, kMaxHandDigits> digits{};
};

/// 0x83 PROTOCOL_SELECT (version 2): the version the host chose for this connection.
struct ProtocolSelectPacket {
  uint16_t sequence = 0;
  uint8_t version = kProtocolVersion;
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
inline constexpr size_t kHandDigitWireSize = 28;
inline constexpr size_t HandBodySize(int digit_count) {
  return 10 + kHandDigitWireSize * static_cast<size_t>(digit_count);
}
inline constexpr size_t kProtocolSelectBodySize = 6;
inline constexpr size_t kMotorCommandBodySize = 8;
inline constexpr size_t kStreamControlBodySize = 5;

/// Encodes a packet as it goes on the wire: body + CRC, COBS-encoded, then the 0x00 delimiter.
/// Returns the number of bytes written, or 0 when `out` is too small (size it kMaxWirePacketSize)
/// or the packet is invalid (unit count outside 1..kMaxUnitsOnWire).
size_t EncodePacket(const TactileFramePacket& packet, std::span<uint8_t> out);
size_t EncodePacket(const HelloPacket& packet, std::span<uint8_t> out);
size_t EncodePacket(const MotorCommandPacket& packet, std::span<uint8_t> out);
size_t EncodePacket(const StreamControlPacket& packet, std::span<uint8_t> out);
/// HAND: 0 also for a digit count outside 1..kMaxHandDigits or a joint count over kMaxHandJoints.
size_t EncodePacket(const HandPacket& packet, std::span<uint8_t> out);
size_t EncodePacket(const ProtocolSelectPacket& packet, std::span<uint8_t> out);

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
  kBadHandCount,    ///< HAND digit count outside 1..2 or a joint count over 2
  kUnknownVersion,  ///< a protocol version this code does not speak (0, or over kProtocolVersion)
  kUnknownType,     ///< a packet type the packet's version does not define
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
  HandPacket hand;
  ProtocolSelectPacket select;
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

/// Fills `state` from a decoded HAND: digits, joints, known flags and values in SI units (unknown
/// values 0, their flags false). `time_s` and `stale` are left to the caller.
void ToHandState(const HandPacket& packet, hand::HandState* state);
/// Fills a HAND from `state` (digits beyond kMaxHandDigits dropped; unknown or non-finite values
/// sent as 0 with their known flag clear; values clamped to the i32 range).
void FromHandState(const hand::HandState& state, uint16_t sequence, uint32_t device_time_us,
                   HandPacket* packet);

/// Motor effort in [-1, 1] to the wire's i16 (clamped), and back.
int16_t EffortToWire(double effort);
double EffortFromWire(int16_t effort);

}  // namespace graspbed::hardware

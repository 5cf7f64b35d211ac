// libFuzzer target for the wire decoder: arbitrary bytes, fed in chunks whose sizes the input picks,
// must never crash, read out of bounds (ASan), overflow (UBSan) or deliver an inconsistent packet.
// HAND (protocol version 2) is converted to a hand::HandState as the host does. Every packet it
// delivers must survive a round trip (encode again, decode again, same fields), and
// the body parser is also fuzzed directly, past the CRC that random bytes rarely pass.
// Build, seed corpus and run: docs/hardware.md "Fuzzing".
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "sensor/raw_frame.h"
#include "hardware/framing.h"
#include "hardware/protocol.h"
#include "hardware/stream_decoder.h"

using namespace graspbed::hardware;

namespace {

void Check(bool ok) {
  if (!ok) abort();
}

bool SameFields(const DecodedPacket& a, const DecodedPacket& b) {
  if (a.type != b.type) return false;
  switch (a.type) {
    case PacketType::kTactileFrame: {
      const TactileFramePacket& x = a.frame;
      const TactileFramePacket& y = b.frame;
      if (x.sequence != y.sequence || x.device_time_us != y.device_time_us || x.unit_count != y.unit_count ||
          x.flags != y.flags) {
        return false;
      }
      return std::equal(x.r1_milliohm.begin(), x.r1_milliohm.begin() + x.unit_count, y.r1_milliohm.begin()) &&
             std::equal(x.r2_milliohm.begin(), x.r2_milliohm.begin() + x.unit_count, y.r2_milliohm.begin());
    }
    case PacketType::kHello:
      return a.hello.sequence == b.hello.sequence && a.hello.firmware_version == b.hello.firmware_version &&
             a.hello.unit_count == b.hello.unit_count && a.hello.max_version == b.hello.max_version &&
             a.hello.nominal_rate_hz == b.hello.nominal_rate_hz &&
             a.hello.nominal_r0_milliohm == b.hello.nominal_r0_milliohm;
    case PacketType::kHand: {
      const HandPacket& x = a.hand;
      const HandPacket& y = b.hand;
      if (x.sequence != y.sequence || x.device_time_us != y.device_time_us ||
          x.digit_count != y.digit_count) {
        return false;
      }
      for (int d = 0; d < x.digit_count; ++d) {
        const HandDigitWire& p = x.digits[d];
        const HandDigitWire& q = y.digits[d];
        if (p.joint_count != q.joint_count || p.flags != q.flags || p.position != q.position ||
            p.velocity != q.velocity || p.motor_current_ua != q.motor_current_ua ||
            p.stall_current_ua != q.stall_current_ua) {
          return false;
        }
      }
      return true;
    }
    case PacketType::kProtocolSelect:
      return a.select.sequence == b.select.sequence && a.select.version == b.select.version;
    case PacketType::kMotorCommand:
      return a.motor.sequence == b.motor.sequence && a.motor.effort == b.motor.effort &&
             a.motor.flags == b.motor.flags;
    case PacketType::kStreamControl:
      return a.stream.sequence == b.stream.sequence && a.stream.start == b.stream.start;
  }
  return false;
}

// Encodes `packet` again and decodes the bytes with a fresh decoder: one packet, the same fields,
// every byte consumed.
void CheckRoundTrip(const DecodedPacket& packet) {
  std::array<uint8_t, kMaxWirePacketSize> wire;
  size_t size = 0;
  switch (packet.type) {
    case PacketType::kTactileFrame:
      size = EncodePacket(packet.frame, wire);
      break;
    case PacketType::kHello:
      size = EncodePacket(packet.hello, wire);
      break;
    case PacketType::kMotorCommand:
      size = EncodePacket(packet.motor, wire);
      break;
    case PacketType::kStreamControl:
      size = EncodePacket(packet.stream, wire);
      break;
    case PacketType::kHand:
      size = EncodePacket(packet.hand, wire);
      break;
    case PacketType::kProtocolSelect:
      size = EncodePacket(packet.select, wire);
      break;
  }
  Check(size > 0);  // anything the decoder accepts fits on the wire
  StreamDecoder decoder;
  static DecodedPacket again;
  const FeedResult fed = decoder.Feed(std::span<const uint8_t>(wire.data(), size), &again);
  Check(fed.packet && fed.consumed == size);
  Check(SameFields(packet, again));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  // First byte: chunk length (1..256) so split reads across packet boundaries are exercised.
  const size_t chunk = static_cast<size_t>(data[0]) + 1;
  std::span<const uint8_t> input(data + 1, size - 1);
  StreamDecoder decoder;
  static DecodedPacket packet;  // large: keep it off the fuzzer's stack
  static graspbed::sensor::RawFrame raw;
  static graspbed::hand::HandState hand;
  uint64_t packets = 0;
  while (!input.empty()) {
    std::span<const uint8_t> piece = input.first(std::min(chunk, input.size()));
    while (!piece.empty()) {
      const FeedResult fed = decoder.Feed(piece, &packet);
      Check(fed.consumed > 0 && fed.consumed <= piece.size());  // progress, and never past the input
      piece = piece.subspan(fed.consumed);
      input = input.subspan(fed.consumed);
      if (!fed.packet) continue;
      ++packets;
      if (packet.type == PacketType::kTactileFrame) {
        Check(packet.frame.unit_count >= 1 && packet.frame.unit_count <= kMaxUnitsOnWire);
        ToRawFrame(packet.frame, &raw);
      }
      if (packet.type == PacketType::kHand) {
        Check(packet.hand.digit_count >= 1 && packet.hand.digit_count <= kMaxHandDigits);
        ToHandState(packet.hand, &hand);
        Check(hand.digit_count == packet.hand.digit_count);
      }
      CheckRoundTrip(packet);
    }
  }
  Check(decoder.stats().packets == packets);

  // The body parser on the raw bytes (no CRC in the way): it must stay inside the body it is given.
  const std::span<const uint8_t> body(data + 1, std::min<size_t>(size - 1, kMaxPacketSize - kCrcSize));
  if (ParseBody(body, &packet) == PacketError::kNone) CheckRoundTrip(packet);

  // The one-shot COBS decoder on the same bytes must not misbehave either; what it decodes must
  // encode back to the same bytes' decoding.
  std::array<uint8_t, kMaxPacketSize> out;
  const std::span<const uint8_t> cobs(data, std::min<size_t>(size, 600));
  if (const auto decoded = CobsDecode(cobs, out)) {
    std::array<uint8_t, CobsMaxEncodedSize(kMaxPacketSize)> encoded;
    const auto length = CobsEncode(std::span<const uint8_t>(out.data(), *decoded), encoded);
    Check(length.has_value());
    std::array<uint8_t, kMaxPacketSize> twice;
    const auto again = CobsDecode(std::span<const uint8_t>(encoded.data(), *length), twice);
    Check(again.has_value() && *again == *decoded &&
          std::equal(out.begin(), out.begin() + *decoded, twice.begin()));
  }
  return 0;
}

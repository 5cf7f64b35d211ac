// Codec: CRC and COBS check values, the packet examples of docs/protocol.md byte for byte, packet
// round trips, and the streaming decoder's resync after every kind of corruption the protocol lists.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <random>
#include <string_view>
#include <vector>

#include "hardware/framing.h"
#include "hardware/protocol.h"
#include "hardware/stream_decoder.h"

namespace graspbed::hardware {
namespace {

std::vector<uint8_t> Bytes(std::string_view text) { return {text.begin(), text.end()}; }

TEST(Crc16, CheckValue) {
  const auto data = Bytes("123456789");
  EXPECT_EQ(Crc16CcittFalse(data), 0x29B1);
  EXPECT_EQ(Crc16CcittFalse({}), 0xFFFF);  // init, no final xor
}

TEST(Cobs, CheckValue) {
  const std::vector<uint8_t> input = {0x11, 0x22, 0x00, 0x33};
  std::array<uint8_t, 16> out{};
  const auto size = CobsEncode(input, out);
  ASSERT_TRUE(size.has_value());
  EXPECT_EQ(std::vector<uint8_t>(out.begin(), out.begin() + *size),
            (std::vector<uint8_t>{0x03, 0x11, 0x22, 0x02, 0x33}));
  std::array<uint8_t, 16> back{};
  const auto decoded = CobsDecode(std::span<const uint8_t>(out.data(), *size), back);
  ASSERT_TRUE(decoded.has_value());
  EXPECT_EQ(std::vector<uint8_t>(back.begin(), back.begin() + *decoded), input);
}

TEST(Cobs, RoundTripsEdgeLengthsAndZeros) {
  std::mt19937 rng(7);
  for (size_t length : {0u, 1u, 253u, 254u, 255u, 508u, 512u}) {
    for (int zeros : {0, 1, 2}) {  // 0: no zeros, 1: random bytes, 2: all zeros
      std::vector<uint8_t> input(length);
      for (auto& b : input)
        b = zeros == 2 ? 0 : static_cast<uint8_t>(zeros == 0 ? 1 + rng() % 255 : rng() % 256);
      std::vector<uint8_t> encoded(CobsMaxEncodedSize(length));
      const auto size = CobsEncode(input, encoded);
      ASSERT_TRUE(size.has_value());
      for (size_t i = 0; i < *size; ++i) ASSERT_NE(encoded[i], 0) << "length " << length;
      std::vector<uint8_t> decoded(length + 1);
      const auto back = CobsDecode(std::span<const uint8_t>(encoded.data(), *size), decoded);
      ASSERT_TRUE(back.has_value()) << "length " << length;
      decoded.resize(*back);
      EXPECT_EQ(decoded, input) << "length " << length << " zeros " << zeros;
    }
  }
}

// The two complete packets docs/protocol.md gives implementers ("Check values"), byte for byte.
TEST(Protocol, DocumentedExamplePacketsOnTheWire) {
  std::array<uint8_t, kMaxWirePacketSize> out{};
  size_t size = EncodePacket(StreamControlPacket{.sequence = 0, .start = true}, out);
  EXPECT_EQ(std::vector<uint8_t>(out.begin(), out.begin() + size),
            (std::vector<uint8_t>{0x03, 0x82, 0x01, 0x01, 0x04, 0x01, 0xCA, 0x11, 0x00}));
  size = EncodePacket(MotorCommandPacket{.sequence = 7, .effort = EffortToWire(0.5), .flags = kMotorEnable},
                      out);
  EXPECT_EQ(std::vector<uint8_t>(out.begin(), out.begin() + size),
            (std::vector<uint8_t>{0x04, 0x81, 0x01, 0x07, 0x01, 0x03, 0x40, 0x01, 0x03, 0xD0, 0xD5, 0x00}));
}

TactileFramePacket MakeFrame(uint16_t seq, int units) {
  TactileFramePacket frame;
  frame.sequence = seq;
  frame.device_time_us = 1000u * seq + 0xABCD0000u;
  frame.unit_count = static_cast<uint8_t>(units);
  frame.flags = kFlagAdcOverrun;
  for (int k = 0; k < units; ++k) {
    frame.r1_milliohm[k] = 3'400'000u + 1000u * k + seq;
    frame.r2_milliohm[k] = 3'400'000u - 1000u * k;
  }
  frame.r1_milliohm[0] = kOpenCircuitMilliohm;
  frame.r2_milliohm[0] = 0;
  frame.r1_milliohm[1] = 0x00FF00FFu;  // zero bytes inside the body exercise COBS
  return frame;
}

std::vector<uint8_t> Wire(const auto& packet) {
  std::array<uint8_t, kMaxWirePacketSize> out{};
  const size_t size = EncodePacket(packet, out);
  EXPECT_GT(size, 0u);
  return {out.begin(), out.begin() + size};
}

// Feeds all of `bytes`, collecting the sequence numbers of decoded frames.
std::vector<uint16_t> DecodeFrames(StreamDecoder& decoder, const std::vector<uint8_t>& bytes) {
  std::vector<uint16_t> seqs;
  DecodedPacket packet;
  std::span<const uint8_t> rest(bytes);
  while (!rest.empty()) {
    const FeedResult r = decoder.Feed(rest, &packet);
    rest = rest.subspan(r.consumed);
    if (r.packet && packet.type == PacketType::kTactileFrame) seqs.push_back(packet.frame.sequence);
  }
  return seqs;
}

TEST(Protocol, FrameRoundTripAndWireSize) {
  const TactileFramePacket frame = MakeFrame(513, 20);
  const auto wire = Wire(frame);
  EXPECT_EQ(wire.back(), 0x00);
  // 170 body + 2 CRC bytes, one COBS code per zero-free run plus one, and the delimiter (~175).
  EXPECT_GE(wire.size(), 170u + 2 + 1 + 1);
  EXPECT_LE(wire.size(), 170u + 2 + 1 + 1 + 40);
  StreamDecoder decoder;
  DecodedPacket packet;
  const FeedResult r = decoder.Feed(wire, &packet);
  ASSERT_TRUE(r.packet);
  EXPECT_EQ(r.consumed, wire.size());
  ASSERT_EQ(packet.type, PacketType::kTactileFrame);
  EXPECT_EQ(packet.frame.sequence, 513);
  EXPECT_EQ(packet.frame.device_time_us, frame.device_time_us);
  EXPECT_EQ(packet.frame.unit_count, 20);
  EXPECT_EQ(packet.frame.flags, kFlagAdcOverrun);
  EXPECT_EQ(packet.frame.r1_milliohm, frame.r1_milliohm);
  EXPECT_EQ(packet.frame.r2_milliohm, frame.r2_milliohm);

  sensor::RawFrame raw;
  ToRawFrame(packet.frame, &raw);
  EXPECT_TRUE(std::isinf(raw.r1_ohm[0]));
  EXPECT_EQ(raw.r2_ohm[0], sensor::kShortCircuitOhm);
  EXPECT_DOUBLE_EQ(raw.r1_ohm[5], (3'400'000.0 + 5000 + 513) * 1e-3);
  EXPECT_EQ(raw.unit_count, 20);
}

TEST(Protocol, OtherPacketsRoundTrip) {
  StreamDecoder decoder;
  DecodedPacket packet;
  HelloPacket hello{.sequence = 65535,
                    .firmware_version = 0x0102,
                    .unit_count = 9,
                    .nominal_rate_hz = 1000,
                    .nominal_r0_milliohm = 3'400'000};
  ASSERT_TRUE(decoder.Feed(Wire(hello), &packet).packet);
  ASSERT_EQ(packet.type, PacketType::kHello);
  EXPECT_EQ(packet.hello.sequence, 65535);
  EXPECT_EQ(packet.hello.firmware_version, 0x0102);
  EXPECT_EQ(packet.hello.unit_count, 9);
  EXPECT_EQ(packet.hello.nominal_rate_hz, 1000);
  EXPECT_EQ(packet.hello.nominal_r0_milliohm, 3'400'000u);

  MotorCommandPacket motor{.sequence = 3, .effort = -32767, .flags = kMotorEnable | kMotorBrake};
  ASSERT_TRUE(decoder.Feed(Wire(motor), &packet).packet);
  ASSERT_EQ(packet.type, PacketType::kMotorCommand);
  EXPECT_EQ(packet.motor.effort, -32767);
  EXPECT_EQ(packet.motor.flags, kMotorEnable | kMotorBrake);

  StreamControlPacket stream{.sequence = 4, .start = true};
  ASSERT_TRUE(decoder.Feed(Wire(stream), &packet).packet);
  ASSERT_EQ(packet.type, PacketType::kStreamControl);
  EXPECT_TRUE(packet.stream.start);
  EXPECT_EQ(decoder.stats().corrupt(), 0u);
}

TEST(Protocol, FramesBeyondThePacketLimitAreRefused) {
  std::array<uint8_t, kMaxWirePacketSize> out{};
  EXPECT_GT(EncodePacket(MakeFrame(1, kMaxUnitsOnWire), out), 0u);
  EXPECT_EQ(EncodePacket(MakeFrame(1, kMaxUnitsOnWire + 1), out), 0u);  // 63 units: 516 bytes
  EXPECT_EQ(EncodePacket(MakeFrame(1, 0), out), 0u);
  std::array<uint8_t, 16> small{};
  EXPECT_EQ(EncodePacket(MakeFrame(1, 20), small), 0u);
}

TEST(Protocol, ResistanceAndEffortConversions) {
  EXPECT_EQ(OhmToMilliohm(3400.0), 3'400'000u);
  EXPECT_EQ(OhmToMilliohm(sensor::kOpenCircuitOhm), kOpenCircuitMilliohm);
  EXPECT_EQ(OhmToMilliohm(std::nan("")), kOpenCircuitMilliohm);
  EXPECT_EQ(OhmToMilliohm(0.0), 0u);
  EXPECT_EQ(OhmToMilliohm(-5.0), 0u);
  EXPECT_EQ(OhmToMilliohm(1e12), kOpenCircuitMilliohm);
  EXPECT_TRUE(std::isinf(MilliohmToOhm(kOpenCircuitMilliohm)));
  EXPECT_EQ(MilliohmToOhm(0), 0.0);
  EXPECT_EQ(EffortToWire(1.0), 32767);
  EXPECT_EQ(EffortToWire(-2.0), -32767);
  EXPECT_EQ(EffortToWire(0.0), 0);
  EXPECT_NEAR(EffortFromWire(EffortToWire(0.25)), 0.25, 1.0 / 32767);
}

TEST(Protocol, HeaderBytesAreLittleEndian) {
  const auto wire = Wire(MotorCommandPacket{.sequence = 0x0201, .effort = 0x0403, .flags = 1});
  std::array<uint8_t, 16> body{};
  const auto size = CobsDecode(std::span<const uint8_t>(wire.data(), wire.size() - 1), body);
  ASSERT_TRUE(size.has_value());
  ASSERT_EQ(*size, kMotorCommandBodySize + kCrcSize);
  EXPECT_EQ((std::vector<uint8_t>(body.begin(), body.begin() + 8)),
            (std::vector<uint8_t>{0x81, 0x01, 0x01, 0x02, 0x03, 0x04, 0x01, 0x00}));
  const uint16_t crc = Crc16CcittFalse(std::span<const uint8_t>(body.data(), 8));
  EXPECT_EQ(body[8], crc & 0xFF);
  EXPECT_EQ(body[9], crc >> 8);
}

// Every frame of a clean stream decodes; corruption of one packet loses exactly that one.
class DecoderResync : public ::testing::Test {
 protected:
  std::vector<uint8_t> Frames(uint16_t first, uint16_t count) {
    std::vector<uint8_t> out;
    for (uint16_t s = first; s < first + count; ++s) {
      const auto w = Wire(MakeFrame(s, 20));
      out.insert(out.end(), w.begin(), w.end());
    }
    return out;
  }
  StreamDecoder decoder_;
};

TEST_F(DecoderResync, FlippedByteIsCrcErrorAndNextFrameDecodes) {
  auto a = Frames(0, 1);
  a[40] ^= 0x5A;
  ASSERT_NE(a[40], 0);
  auto bytes = a;
  const auto b = Frames(1, 2);
  bytes.insert(bytes.end(), b.begin(), b.end());
  EXPECT_EQ(DecodeFrames(decoder_, bytes), (std::vector<uint16_t>{1, 2}));
  EXPECT_EQ(decoder_.stats().crc_errors + decoder_.stats().cobs_errors, 1u);
  EXPECT_EQ(decoder_.stats().corrupt(), 1u);
}

TEST_F(DecoderResync, EveryLostByteOfAFrameIsOneCorruptPacket) {
  const auto frame = Frames(7, 1);
  const auto next = Frames(8, 1);
  for (size_t lost = 0; lost + 1 < frame.size(); ++lost) {  // every byte but the delimiter
    StreamDecoder decoder;
    auto bytes = frame;
    bytes.erase(bytes.begin() + static_cast<long>(lost));
    bytes.insert(bytes.end(), next.begin(), next.end());
    EXPECT_EQ(DecodeFrames(decoder, bytes), (std::vector<uint16_t>{8})) << "lost byte " << lost;
    EXPECT_EQ(decoder.stats().corrupt(), 1u) << "lost byte " << lost;
  }
}

TEST_F(DecoderResync, EveryFlippedBitOfAFrameIsOneCorruptPacket) {
  const auto frame = Frames(7, 1);
  const auto next = Frames(8, 1);
  for (size_t i = 0; i + 1 < frame.size(); ++i) {
    for (int bit = 0; bit < 8; ++bit) {
      auto bytes = frame;
      bytes[i] ^= static_cast<uint8_t>(1u << bit);
      if (bytes[i] == 0) continue;  // a new delimiter splits the packet: covered below
      bytes.insert(bytes.end(), next.begin(), next.end());
      StreamDecoder decoder;
      EXPECT_EQ(DecodeFrames(decoder, bytes), (std::vector<uint16_t>{8})) << i << ":" << bit;
      EXPECT_EQ(decoder.stats().corrupt(), 1u) << i << ":" << bit;
    }
  }
}

TEST_F(DecoderResync, ByteTurnedIntoDelimiterSplitsIntoTwoCorruptPieces) {
  auto bytes = Frames(0, 1);
  bytes[50] = 0x00;
  const auto next = Frames(1, 1);
  bytes.insert(bytes.end(), next.begin(), next.end());
  EXPECT_EQ(DecodeFrames(decoder_, bytes), (std::vector<uint16_t>{1}));
  EXPECT_EQ(decoder_.stats().corrupt(), 2u);
}

TEST_F(DecoderResync, GarbageBetweenPacketsCostsOnlyTheFollowingPacket) {
  std::vector<uint8_t> bytes = Frames(0, 1);
  for (int i = 1; i <= 37; ++i) bytes.push_back(static_cast<uint8_t>(i * 7 % 255 + 1));  // no delimiter
  const auto rest = Frames(1, 2);
  bytes.insert(bytes.end(), rest.begin(), rest.end());
  EXPECT_EQ(DecodeFrames(decoder_, bytes), (std::vector<uint16_t>{0, 2}));
  EXPECT_EQ(decoder_.stats().corrupt(), 1u);

  // Garbage that ends in a delimiter costs nothing but itself.
  StreamDecoder decoder;
  std::vector<uint8_t> delimited = {0x00, 0x13, 0x77, 0x00};
  const auto more = Frames(3, 1);
  delimited.insert(delimited.end(), more.begin(), more.end());
  EXPECT_EQ(DecodeFrames(decoder, delimited), (std::vector<uint16_t>{3}));
  EXPECT_EQ(decoder.stats().corrupt(), 1u);
  EXPECT_EQ(decoder.last_error(), PacketError::kCobs);  // code 0x13 promises 18 bytes
}

TEST_F(DecoderResync, OverLongPacketIsDiscardedToTheNextDelimiter) {
  std::vector<uint8_t> bytes(5000, 0x42);  // no delimiter for 5000 bytes
  bytes.push_back(0x00);
  const auto next = Frames(9, 1);
  bytes.insert(bytes.end(), next.begin(), next.end());
  EXPECT_EQ(DecodeFrames(decoder_, bytes), (std::vector<uint16_t>{9}));
  EXPECT_EQ(decoder_.stats().too_long, 1u);
  EXPECT_EQ(decoder_.stats().corrupt(), 1u);
}

TEST_F(DecoderResync, EmptyPacketsAreNotErrors) {
  std::vector<uint8_t> bytes = {0, 0, 0};
  const auto next = Frames(1, 1);
  bytes.insert(bytes.end(), next.begin(), next.end());
  EXPECT_EQ(DecodeFrames(decoder_, bytes), (std::vector<uint16_t>{1}));
  EXPECT_EQ(decoder_.stats().corrupt(), 0u);
}

// Builds a correctly framed packet from an arbitrary body (valid CRC).
std::vector<uint8_t> RawPacket(std::vector<uint8_t> body) {
  const uint16_t crc = Crc16CcittFalse(body);
  body.push_back(static_cast<uint8_t>(crc));
  body.push_back(static_cast<uint8_t>(crc >> 8));
  std::vector<uint8_t> out(CobsMaxEncodedSize(body.size()) + 1);
  const auto size = CobsEncode(body, out);
  out.resize(*size);
  out.push_back(0);
  return out;
}

TEST_F(DecoderResync, UnknownTypeCountedUnknownVersionRejectedBadLengthCorrupt) {
  std::vector<uint8_t> bytes = RawPacket({0x33, 0x01, 0x00, 0x00, 0xAA});  // unknown type
  auto add = [&](const std::vector<uint8_t>& more) { bytes.insert(bytes.end(), more.begin(), more.end()); };
  add(RawPacket({0x01, 0x03, 0x05, 0x00}));        // version 3
  add(RawPacket({0x02, 0x01, 0x00, 0x00, 0x01}));  // HELLO of 5 bytes
  std::vector<uint8_t> frame_body(10 + 8 * 3, 0x11);
  frame_body[0] = 0x01;
  frame_body[1] = 0x01;
  frame_body[8] = 4;  // says 4 units, carries 3
  add(RawPacket(frame_body));
  frame_body[8] = 0;  // zero units
  add(RawPacket(frame_body));
  add(Frames(5, 1));
  EXPECT_EQ(DecodeFrames(decoder_, bytes), (std::vector<uint16_t>{5}));
  EXPECT_EQ(decoder_.stats().unknown_type, 1u);
  EXPECT_EQ(decoder_.stats().unknown_version, 1u);
  EXPECT_EQ(decoder_.stats().length_errors, 3u);
  EXPECT_EQ(decoder_.stats().corrupt(), 3u);
  EXPECT_EQ(decoder_.stats().unknown(), 2u);
}

// After Reset() (a port just opened) the tail of a packet sent before we listened is junk, not a
// fault; but a packet with a good CRC proves the stream is in step, so what follows it counts, even
// when that first packet is of a type or version this host does not speak.
TEST_F(DecoderResync, AfterResetJunkIsUncountedButTheFirstGoodCrcSyncs) {
  decoder_.Reset();
  std::vector<uint8_t> bytes = Frames(1, 1);
  bytes.erase(bytes.begin(), bytes.begin() + 30);  // tail of a frame: junk
  auto add = [&](const std::vector<uint8_t>& more) { bytes.insert(bytes.end(), more.begin(), more.end()); };
  add(RawPacket({0x33, 0x01, 0x00, 0x00, 0xAA}));  // unknown type, good CRC
  auto broken = Frames(2, 1);
  uint8_t& hit = broken[broken.size() / 2];
  hit = static_cast<uint8_t>(hit == 0x40 ? 0x41 : hit ^ 0x40);  // a real error after sync (no 0x00)
  add(broken);
  add(Frames(3, 1));
  EXPECT_EQ(DecodeFrames(decoder_, bytes), (std::vector<uint16_t>{3}));
  EXPECT_EQ(decoder_.stats().unknown_type, 1u);
  EXPECT_EQ(decoder_.stats().corrupt(), 1u);
}

TEST_F(DecoderResync, NeverConsumesPastAPacketsEnd) {
  const auto bytes = Frames(0, 3);
  const size_t first = Wire(MakeFrame(0, 20)).size();
  DecodedPacket packet;
  const FeedResult r = decoder_.Feed(bytes, &packet);
  EXPECT_TRUE(r.packet);
  EXPECT_EQ(r.consumed, first);
}

TEST_F(DecoderResync, ByteByByteFeedingMatchesBulk) {
  std::mt19937 rng(3);
  std::vector<uint8_t> bytes;
  for (uint16_t s = 0; s < 50; ++s) {
    auto w = Wire(MakeFrame(s, 1 + s % kMaxUnitsOnWire));
    if (s % 7 == 3) w[rng() % (w.size() - 1)] ^= 0x01;
    if (w[0] == 0) w[0] = 1;
    bytes.insert(bytes.end(), w.begin(), w.end());
  }
  StreamDecoder bulk;
  const auto expected = DecodeFrames(bulk, bytes);
  StreamDecoder single;
  std::vector<uint16_t> got;
  DecodedPacket packet;
  for (uint8_t b : bytes) {
    if (single.Feed(std::span<const uint8_t>(&b, 1), &packet).packet) got.push_back(packet.frame.sequence);
  }
  EXPECT_EQ(got, expected);
  EXPECT_EQ(single.stats().corrupt(), bulk.stats().corrupt());
  EXPECT_GE(expected.size(), 40u);
}

// ---- HAND and PROTOCOL_SELECT (protocol version 2) ----

hand::HandState ExampleHand() {
  hand::HandState state;
  state.digit_count = 2;
  hand::DigitState& index = state.digits[0];
  index.joint_count = 2;
  index.position_known = index.velocity_known = index.current_known = index.stops_known = true;
  index.joint_position = {0.612, 0.305};  // [rad]
  index.joint_velocity = {-0.0015, 0.00004};
  index.motor_current_a = 0.412;
  index.stall_current_a = 1.0;
  hand::DigitState& thumb = state.digits[1];
  thumb.joint_count = 1;
  thumb.current_known = true;  // its encoder failed: position unknown, never 0
  thumb.encoder_fault = true;
  thumb.motor_current_a = -0.02;
  return state;
}

TEST(ProtocolHand, HandRoundTripsWithinTheWiresResolution) {
  constexpr double kMicroTol = 0.5e-6;  // positions [rad], velocities [rad/s], currents [A]: 1e-6 steps
  HandPacket packet;
  FromHandState(ExampleHand(), 0x1234, 0xABCDEF01u, &packet);
  const auto wire = Wire(packet);
  StreamDecoder decoder;
  DecodedPacket decoded;
  const FeedResult fed = decoder.Feed(wire, &decoded);
  ASSERT_TRUE(fed.packet);
  EXPECT_EQ(fed.consumed, wire.size());
  ASSERT_EQ(decoded.type, PacketType::kHand);
  EXPECT_EQ(decoded.hand.sequence, 0x1234);
  EXPECT_EQ(decoded.hand.device_time_us, 0xABCDEF01u);
  hand::HandState state;
  ToHandState(decoded.hand, &state);
  ASSERT_EQ(state.digit_count, 2);
  const hand::DigitState& index = state.digits[0];
  EXPECT_TRUE(index.position_known && index.velocity_known && index.current_known && index.stops_known);
  EXPECT_EQ(index.joint_count, 2);
  EXPECT_NEAR(index.joint_position[0], 0.612, kMicroTol);
  EXPECT_NEAR(index.joint_position[1], 0.305, kMicroTol);
  EXPECT_NEAR(index.joint_velocity[0], -0.0015, kMicroTol);
  EXPECT_NEAR(index.motor_current_a, 0.412, kMicroTol);
  EXPECT_NEAR(index.stall_current_a, 1.0, kMicroTol);
  const hand::DigitState& thumb = state.digits[1];
  EXPECT_FALSE(thumb.position_known);
  EXPECT_FALSE(thumb.velocity_known);
  EXPECT_FALSE(thumb.stops_known);
  EXPECT_TRUE(thumb.encoder_fault);
  EXPECT_NEAR(thumb.motor_current_a, -0.02, kMicroTol);
  EXPECT_EQ(thumb.stall_current_a, 0.0);  // 0 on the wire: unknown
  // 66 body bytes + 2 CRC, one COBS code byte (no run of 254) and the delimiter: docs/protocol.md's
  // 70 bytes on the wire per HAND.
  EXPECT_EQ(HandBodySize(2), 66u);
  EXPECT_EQ(wire.size(), 70u);
}

TEST(ProtocolHand, ACorruptedHandIsOneCrcErrorAndTheNextDecodes) {
  HandPacket packet;
  FromHandState(ExampleHand(), 1, 1000, &packet);
  std::vector<uint8_t> bytes = Wire(packet);
  bytes[bytes.size() / 2] ^= 0x5A;
  if (bytes[bytes.size() / 2] == 0) bytes[bytes.size() / 2] = 0x11;
  packet.sequence = 2;
  const auto next = Wire(packet);
  bytes.insert(bytes.end(), next.begin(), next.end());
  StreamDecoder decoder;
  DecodedPacket decoded;
  std::vector<uint16_t> hands;
  std::span<const uint8_t> rest(bytes);
  while (!rest.empty()) {
    const FeedResult fed = decoder.Feed(rest, &decoded);
    rest = rest.subspan(fed.consumed);
    if (fed.packet && decoded.type == PacketType::kHand) hands.push_back(decoded.hand.sequence);
  }
  EXPECT_EQ(hands, (std::vector<uint16_t>{2}));
  EXPECT_EQ(decoder.stats().corrupt(), 1u);
  EXPECT_EQ(decoder.stats().crc_errors + decoder.stats().cobs_errors, 1u);
}

TEST(ProtocolHand, MalformedHandsAreCorruptAndCountedAsHandErrors) {
  std::vector<uint8_t> three_digits(HandBodySize(3), 0);
  three_digits[0] = 0x03;
  three_digits[1] = 2;
  three_digits[8] = 3;  // digit count 3: more than the wire carries
  std::vector<uint8_t> three_joints(HandBodySize(1), 0);
  three_joints[0] = 0x03;
  three_joints[1] = 2;
  three_joints[8] = 1;
  three_joints[10] = 3;  // joint count 3
  std::vector<uint8_t> short_body(HandBodySize(2) - 1, 0);
  short_body[0] = 0x03;
  short_body[1] = 2;
  short_body[8] = 2;  // says 2 digits, carries one byte less
  std::vector<uint8_t> version_1(HandBodySize(1), 0);
  version_1[0] = 0x03;
  version_1[1] = 1;  // HAND is not a type of version 1
  version_1[8] = 1;
  std::vector<uint8_t> bytes;
  for (const auto& body : {three_digits, three_joints, short_body, version_1}) {
    const auto packet = RawPacket(body);
    bytes.insert(bytes.end(), packet.begin(), packet.end());
  }
  StreamDecoder decoder;
  DecodedPacket decoded;
  std::span<const uint8_t> rest(bytes);
  int delivered = 0;
  while (!rest.empty()) {
    const FeedResult fed = decoder.Feed(rest, &decoded);
    rest = rest.subspan(fed.consumed);
    delivered += fed.packet ? 1 : 0;
  }
  EXPECT_EQ(delivered, 0);
  EXPECT_EQ(decoder.stats().length_errors, 3u);
  EXPECT_EQ(decoder.stats().hand_errors, 3u);
  EXPECT_EQ(decoder.stats().unknown_type, 1u);
  EXPECT_EQ(ParseBody(three_digits, &decoded), PacketError::kBadHandCount);
  EXPECT_STREQ(ToString(PacketError::kBadHandCount), "bad digit or joint count");
}

TEST(ProtocolHand, EncoderRefusesWhatTheWireCannotCarry) {
  std::array<uint8_t, kMaxWirePacketSize> out{};
  HandPacket packet;
  packet.digit_count = 0;
  EXPECT_EQ(EncodePacket(packet, out), 0u);
  packet.digit_count = 3;
  EXPECT_EQ(EncodePacket(packet, out), 0u);
  packet.digit_count = 1;
  packet.digits[0].joint_count = 3;
  EXPECT_EQ(EncodePacket(packet, out), 0u);
  // Unknown and non-finite values go as 0 with their flag clear.
  hand::HandState state = ExampleHand();
  state.digits[0].joint_position[0] = std::nan("");
  state.digits[0].position_known = false;
  FromHandState(state, 0, 0, &packet);
  EXPECT_EQ(packet.digits[0].position[0], 0);
  EXPECT_EQ(packet.digits[0].flags & kHandPositionKnown, 0);
}

// docs/protocol.md, "Check values for implementers": the version-2 examples, byte for byte.
TEST(ProtocolHand, DocumentedExamplePacketsOnTheWire) {
  std::array<uint8_t, kMaxWirePacketSize> out{};
  size_t size = EncodePacket(ProtocolSelectPacket{.sequence = 0, .version = 2}, out);
  EXPECT_EQ(std::vector<uint8_t>(out.begin(), out.begin() + size),
            (std::vector<uint8_t>{0x03, 0x83, 0x02, 0x01, 0x02, 0x02, 0x03, 0x31, 0x36, 0x00}));
  HandPacket hand;
  hand.sequence = 5;
  hand.device_time_us = 5000;
  hand.digit_count = 1;
  hand.digits[0] = {.joint_count = 2,
                    .flags = kHandPositionKnown | kHandVelocityKnown | kHandCurrentKnown | kHandStopsKnown,
                    .position = {500'000, 250'000},
                    .velocity = {0, 0},
                    .motor_current_ua = 300'000,
                    .stall_current_ua = 1'000'000};
  size = EncodePacket(hand, out);
  EXPECT_EQ(std::vector<uint8_t>(out.begin(), out.begin() + size),
            (std::vector<uint8_t>{0x04, 0x03, 0x02, 0x05, 0x03, 0x88, 0x13, 0x01, 0x02, 0x01, 0x03,
                                  0x02, 0x1E, 0x01, 0x04, 0x20, 0xA1, 0x07, 0x04, 0x90, 0xD0, 0x03,
                                  0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x01, 0x04, 0xE0, 0x93,
                                  0x04, 0x04, 0x40, 0x42, 0x0F, 0x03, 0xAC, 0x4F, 0x00}));
}

TEST(ProtocolHand, HelloCarriesTheDevicesVersionAndAVersionOneHelloReadsAsOne) {
  HelloPacket hello{.sequence = 1,
                    .firmware_version = 0x0200,
                    .unit_count = 20,
                    .max_version = 2,
                    .nominal_rate_hz = 1000,
                    .nominal_r0_milliohm = 3'400'000};
  StreamDecoder decoder;
  DecodedPacket decoded;
  ASSERT_TRUE(decoder.Feed(Wire(hello), &decoded).packet);
  EXPECT_EQ(decoded.hello.max_version, 2);
  EXPECT_EQ(DeviceVersion(decoded.hello), 2);
  hello.max_version = 0;  // a version-1 device: reserved byte 7
  ASSERT_TRUE(decoder.Feed(Wire(hello), &decoded).packet);
  EXPECT_EQ(DeviceVersion(decoded.hello), 1);
  ASSERT_TRUE(decoder.Feed(Wire(ProtocolSelectPacket{.sequence = 9, .version = 2}), &decoded).packet);
  ASSERT_EQ(decoded.type, PacketType::kProtocolSelect);
  EXPECT_EQ(decoded.select.version, 2);
  EXPECT_EQ(decoded.select.sequence, 9);
}

}  // namespace
}  // namespace graspbed::hardware

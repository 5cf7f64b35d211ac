// Writes a seed corpus of valid wire packets for decoder_fuzz (docs/hardware.md "Fuzzing"), encoded by
// the project's own codec. Each seed is one fuzz input: a first byte that picks the chunk size the
// target feeds the decoder in, then bytes as they come off the port. Valid packets let the fuzzer
// start past the CRC check instead of having to find a matching CRC by chance.
//   Usage: make_seed_corpus DIR
#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "hardware/protocol.h"

namespace {

using graspbed::hardware::EncodeBody;
using graspbed::hardware::EncodePacket;
using Bytes = std::vector<uint8_t>;

template <typename Packet>
Bytes Wire(const Packet& packet) {
  std::array<uint8_t, graspbed::hardware::kMaxWirePacketSize> out{};
  const size_t size = EncodePacket(packet, out);
  return Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(size));
}

/// A body this protocol version does not define (unknown type, foreign version), framed validly.
Bytes WireBody(const Bytes& body) {
  std::array<uint8_t, graspbed::hardware::kMaxWirePacketSize> out{};
  const size_t size = EncodeBody(body, out);
  return Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(size));
}

/// A frame of `units` units: unit 0 open, unit 1 shorted, the rest near 3.4 kOhm.
Bytes Frame(uint16_t sequence, int units, uint32_t time_us, uint8_t flags = 0) {
  graspbed::hardware::TactileFramePacket packet;
  packet.sequence = sequence;
  packet.device_time_us = time_us;
  packet.unit_count = static_cast<uint8_t>(units);
  packet.flags = flags;
  for (int k = 0; k < units; ++k) {
    const auto index = static_cast<size_t>(k);
    packet.r1_milliohm[index] = k == 0 ? graspbed::hardware::kOpenCircuitMilliohm
                                       : (k == 1 ? 0u : 3'400'000u + 1000u * static_cast<uint32_t>(k));
    packet.r2_milliohm[index] = 3'400'000u - 1000u * static_cast<uint32_t>(k);
  }
  return Wire(packet);
}

Bytes Hello(uint16_t sequence, int units, uint8_t max_version = 0) {
  graspbed::hardware::HelloPacket packet;
  packet.sequence = sequence;
  packet.firmware_version = 0x0100;
  packet.unit_count = static_cast<uint8_t>(units);
  packet.max_version = max_version;
  packet.nominal_rate_hz = 1000;
  packet.nominal_r0_milliohm = 3'400'000;
  return Wire(packet);
}

/// A HAND (protocol version 2) of the prosthetic hand: index (2 hinges) and thumb (1 hinge), known
/// fields and flags varied.
Bytes Hand(uint16_t sequence, uint32_t time_us, int digits) {
  using namespace graspbed::hardware;
  HandPacket packet;
  packet.sequence = sequence;
  packet.device_time_us = time_us;
  packet.digit_count = static_cast<uint8_t>(digits);
  packet.digits[0] = {.joint_count = 2,
                      .flags = kHandPositionKnown | kHandVelocityKnown | kHandCurrentKnown | kHandStopsKnown,
                      .position = {612'000, 305'000},
                      .velocity = {-1'500, 40},
                      .motor_current_ua = 412'000,
                      .stall_current_ua = 1'000'000};
  packet.digits[1] = {.joint_count = 1,
                      .flags = kHandCurrentKnown | kHandEncoderFault | kHandLinear,
                      .position = {},
                      .velocity = {},
                      .motor_current_ua = -20'000,
                      .stall_current_ua = 0};
  return Wire(packet);
}

Bytes Join(std::initializer_list<Bytes> parts) {
  Bytes all;
  for (const Bytes& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DIR\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = argv[1];
  std::filesystem::create_directories(dir);

  graspbed::hardware::MotorCommandPacket motor;
  motor.sequence = 5;
  motor.effort = -12345;
  motor.flags = graspbed::hardware::kMotorEnable | graspbed::hardware::kMotorBrake;
  graspbed::hardware::StreamControlPacket stream;
  stream.sequence = 1;
  stream.start = true;
  Bytes foreign_version(16, 0);
  foreign_version[0] = 0x02;
  foreign_version[1] = 3;
  graspbed::hardware::ProtocolSelectPacket select;
  select.sequence = 2;
  select.version = 2;
  // A HAND of 3 digits (refused) and a HAND claiming version 1 (a type version 1 does not define).
  Bytes three_digits(graspbed::hardware::HandBodySize(3), 0);
  three_digits[0] = 0x03;
  three_digits[1] = 2;
  three_digits[8] = 3;
  Bytes hand_v1(graspbed::hardware::HandBodySize(1), 0);
  hand_v1[0] = 0x03;
  hand_v1[1] = 1;
  hand_v1[8] = 1;

  const std::map<std::string, Bytes> seeds = {
      {"hello_then_frames_20", Join({Hello(0, 20), Frame(0, 20, 0), Frame(1, 20, 1000), Frame(2, 20, 2000)})},
      {"frame_1_unit", Frame(7, 1, 7000, graspbed::hardware::kFlagAdcOverrun)},
      {"frame_62_units",
       Frame(9, 62, 9000, graspbed::hardware::kFlagAdcOverrun | graspbed::hardware::kFlagSupplyFault)},
      {"frames_9_units_gap", Join({Frame(1, 9, 1000), Frame(3, 9, 3000), Frame(2, 9, 2000)})},
      {"motor_and_stream", Join({Wire(motor), Wire(stream)})},
      {"unknown_type_and_version", Join({WireBody({0x33, 1, 0, 0, 0xab, 0xcd}), WireBody(foreign_version)})},
      {"garbage_between",
       Join({Bytes{0x13, 0x37, 0x42}, Frame(4, 20, 4000), Bytes(40, 0xff), Bytes{0x00}, Frame(5, 20, 5000)})},
      {"wrapping_sequence", Join({Frame(65535, 4, 0xFFFFFC18u), Frame(0, 4, 0)})},
      {"v2_hello_select_hand_frames", Join({Hello(0, 20, 2), Wire(select), Hand(0, 0, 2), Frame(0, 20, 0),
                                            Hand(1, 1000, 2), Frame(1, 20, 1000)})},
      {"hand_one_digit", Hand(7, 7000, 1)},
      {"hand_malformed", Join({WireBody(three_digits), WireBody(hand_v1), Hand(8, 8000, 2)})},
  };
  int index = 0;
  for (const auto& [name, bytes] : seeds) {
    std::ofstream out(dir / name, std::ios::binary);
    const auto chunk_selector = static_cast<char>((37 * index++ + 5) % 256);  // various chunk sizes
    out.put(chunk_selector);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    if (!out) {
      std::fprintf(stderr, "make_seed_corpus: cannot write %s\n", (dir / name).c_str());
      return 1;
    }
  }
  std::printf("%zu seeds in %s\n", seeds.size(), dir.c_str());
  return 0;
}

#include "hardware/framing.h"

#include <array>

namespace graspbed::hardware {
namespace {

// Table-driven CRC (one lookup per byte): the decoder checks ~175 bytes per frame at up to 100 kHz.
constexpr std::array<uint16_t, 256> MakeCrcTable() {
  std::array<uint16_t, 256> table{};
  for (int i = 0; i < 256; ++i) {
    uint16_t crc = static_cast<uint16_t>(i << 8);
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000u) ? static_cast<uint16_t>((crc << 1) ^ 0x1021u) : static_cast<uint16_t>(crc << 1);
    }
    table[i] = crc;
  }
  return table;
}
constexpr std::array<uint16_t, 256> kCrcTable = MakeCrcTable();

}  // namespace

uint16_t Crc16CcittFalse(std::span<const uint8_t> data) {
  uint16_t crc = 0xFFFF;
  for (const uint8_t byte : data) {
    crc = static_cast<uint16_t>((crc << 8) ^ kCrcTable[((crc >> 8) ^ byte) & 0xFFu]);
  }
  return crc;
}

std::optional<size_t> CobsEncode(std::span<const uint8_t> input, std::span<uint8_t> output) {
  if (output.size() < CobsMaxEncodedSize(input.size())) {
    // Exact size may still fit, but callers size buffers with CobsMaxEncodedSize; refuse early.
    return std::nullopt;
  }
  size_t code_index = 0;
  size_t out = 1;
  uint8_t code = 1;
  for (const uint8_t byte : input) {
    if (byte == 0) {
      output[code_index] = code;
      code_index = out++;
      code = 1;
      continue;
    }
    output[out++] = byte;
    if (++code == 0xFF) {
      output[code_index] = code;
      code_index = out++;
      code = 1;
    }
  }
  output[code_index] = code;
  return out;
}

std::optional<size_t> CobsDecode(std::span<const uint8_t> input, std::span<uint8_t> output) {
  size_t in = 0;
  size_t out = 0;
  while (in < input.size()) {
    const uint8_t code = input[in++];
    if (code == 0) return std::nullopt;
    for (int i = 1; i < code; ++i) {
      if (in >= input.size() || input[in] == 0 || out >= output.size()) return std::nullopt;
      output[out++] = input[in++];
    }
    // A block shorter than 254 data bytes stands for a zero, except at the very end.
    if (code != 0xFF && in < input.size()) {
      if (out >= output.size()) return std::nullopt;
      output[out++] = 0;
    }
  }
  return out;
}

}  // namespace graspbed::hardware

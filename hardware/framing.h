#pragma once
/// Byte-level framing of the wire protocol (docs/protocol.md, "Framing"): COBS encoding with a 0x00
/// delimiter, and the CRC-16/CCITT-FALSE that guards every packet body.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>

namespace graspbed::hardware {

/// CRC-16/CCITT-FALSE: polynomial 0x1021, init 0xFFFF, no reflection, no final xor.
/// Check value: Crc16CcittFalse("123456789") == 0x29B1.
uint16_t Crc16CcittFalse(std::span<const uint8_t> data);

/// Largest COBS encoding of `decoded_size` bytes (one code byte per started 254-byte block, plus one),
/// without the delimiter.
constexpr size_t CobsMaxEncodedSize(size_t decoded_size) { return decoded_size + decoded_size / 254 + 1; }

/// COBS-encodes `input` into `output` (no delimiter is appended). Returns the encoded length, or
/// std::nullopt when `output` is too small. Never writes a 0x00 byte.
std::optional<size_t> CobsEncode(std::span<const uint8_t> input, std::span<uint8_t> output);

/// Decodes one COBS block sequence `input` (without its delimiter; it must contain no 0x00) into
/// `output`. Returns the decoded length, or std::nullopt on a COBS error (a 0x00 inside, a code
/// that runs past the end) or when `output` is too small.
std::optional<size_t> CobsDecode(std::span<const uint8_t> input, std::span<uint8_t> output);

}  // namespace graspbed::hardware

#pragma once
/// StreamDecoder: turns a byte stream from the port into packets. COBS is undone byte by byte into a
/// fixed buffer; at each 0x00 delimiter the packet is CRC-checked and parsed. Any error drops the
/// packet, is counted, and the decoder resynchronises at the next 0x00. Nothing allocates.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "hardware/protocol.h"

namespace graspbed::hardware {

/// What the decoder has seen since construction (or Reset()).
struct DecoderStats {
  uint64_t bytes = 0;            ///< bytes fed
  uint64_t packets = 0;          ///< packets delivered (valid CRC, known type and version)
  uint64_t cobs_errors = 0;      ///< delimiter in the middle of a COBS block (bytes lost)
  uint64_t crc_errors = 0;       ///< CRC mismatch
  uint64_t length_errors = 0;    ///< too short, wrong body length for the type, bad unit or digit count
  /// Of length_errors, HAND packets (valid CRC, refused for their length or digit/joint count).
  uint64_t hand_errors = 0;
  uint64_t too_long = 0;         ///< over kMaxPacketSize before a delimiter (discarded to the next 0x00)
  uint64_t unknown_version = 0;  ///< valid CRC, a protocol version this host does not speak (rejected)
  uint64_t unknown_type = 0;     ///< valid CRC, a type its version does not define (ignored)

  /// Packets dropped for CRC, COBS or length errors (BackendCounters::corrupt).
  uint64_t corrupt() const { return cobs_errors + crc_errors + length_errors + too_long; }
  /// Packets ignored because this host does not understand them (BackendCounters::unknown_packets).
  uint64_t unknown() const { return unknown_version + unknown_type; }
};

/// Result of one Feed() call.
struct FeedResult {
  size_t consumed = 0;  ///< bytes of the input used; feed the rest again
  bool packet = false;  ///< true: a complete valid packet was written to the output
};

class StreamDecoder {
 public:
  StreamDecoder() = default;

  /// Consumes `input` up to and including the delimiter of the first complete valid packet (which
  /// goes to `*packet`), or all of it. Never looks past that delimiter, never allocates.
  FeedResult Feed(std::span<const uint8_t> input, DecodedPacket* packet);

  /// Forgets any partial packet (after opening a port). Until a packet passes its CRC, refused bytes
  /// are start-up junk (the tail of a packet sent before we listened) and are dropped uncounted.
  void Reset();

  const DecoderStats& stats() const { return stats_; }
  /// Why the most recent refused packet was refused.
  PacketError last_error() const { return last_error_; }

 private:
  void StartPacket();
  void Fail(PacketError error);
  bool Append(uint8_t byte);
  bool Complete(DecodedPacket* packet);

  std::array<uint8_t, kMaxPacketSize> buffer_{};
  size_t size_ = 0;
  int block_remaining_ = 0;  // data bytes still due in the current COBS block
  uint8_t block_code_ = 0;   // code byte of the current block (0: none yet in this packet)
  bool discarding_ = false;  // skipping to the next delimiter after an error
  bool synced_ = true;       // false after Reset() until a packet passes its CRC: errors are not counted
  DecoderStats stats_;
  PacketError last_error_ = PacketError::kNone;
};

}  // namespace graspbed::hardware

// libFuzzer target for the wire decoder: arbitrary bytes, fed in chunks whose sizes the input picks,
// must never crash, read out of bounds (ASan), overflow (UBSan) or deliver an inconsistent packet.
// Build and run: docs/hardware.md "Fuzzing".
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <span>

#include "sensor/raw_frame.h"
#include "sensor/serial/framing.h"
#include "sensor/serial/protocol.h"
#include "sensor/serial/stream_decoder.h"

using namespace graspbed::serial;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  // First byte: chunk length (1..256) so split reads across packet boundaries are exercised.
  const size_t chunk = static_cast<size_t>(data[0]) + 1;
  std::span<const uint8_t> input(data + 1, size - 1);
  StreamDecoder decoder;
  DecodedPacket packet;
  graspbed::sensor::RawFrame raw;
  uint64_t packets = 0;
  while (!input.empty()) {
    std::span<const uint8_t> piece = input.first(std::min(chunk, input.size()));
    while (!piece.empty()) {
      const FeedResult fed = decoder.Feed(piece, &packet);
      if (fed.consumed == 0 || fed.consumed > piece.size()) abort();  // must make progress, stay inside
      piece = piece.subspan(fed.consumed);
      input = input.subspan(fed.consumed);
      if (!fed.packet) continue;
      ++packets;
      if (packet.type == PacketType::kTactileFrame) {
        if (packet.frame.unit_count < 1 || packet.frame.unit_count > kMaxFrameUnits) abort();
        ToRawFrame(packet.frame, &raw);
      }
    }
  }
  if (decoder.stats().packets != packets) abort();
  // The one-shot COBS decoder on the same bytes must not misbehave either.
  std::array<uint8_t, kMaxPacketSize> out;
  (void)CobsDecode(std::span<const uint8_t>(data, std::min<size_t>(size, 600)), out);
  return 0;
}

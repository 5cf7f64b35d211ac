// Decoder throughput: 20-unit TACTILE_FRAMEs through StreamDecoder (COBS undo, CRC, parse) and on to
// RawFrame, on one core. Budget (DESIGN.md): 100x the nominal 1 kHz, i.e. >= 100k frames/s.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <vector>

#include "sensor/raw_frame.h"
#include "hardware/protocol.h"
#include "hardware/stream_decoder.h"

namespace {

using namespace graspbed::hardware;

// A stream of `count` frames of `units` units with realistic resistances (~3.4 kOhm in mOhm).
std::vector<uint8_t> MakeStream(int count, int units) {
  std::vector<uint8_t> stream;
  std::array<uint8_t, kMaxWirePacketSize> out;
  TactileFramePacket frame;
  frame.unit_count = static_cast<uint8_t>(units);
  for (int i = 0; i < count; ++i) {
    frame.sequence = static_cast<uint16_t>(i);
    frame.device_time_us = static_cast<uint32_t>(i * 1000);
    for (int k = 0; k < units; ++k) {
      frame.r1_milliohm[k] = 3'400'000u + static_cast<uint32_t>((i * 37 + k * 101) % 50'000);
      frame.r2_milliohm[k] = 3'400'000u - static_cast<uint32_t>((i * 53 + k * 71) % 50'000);
    }
    const size_t size = EncodePacket(frame, out);
    stream.insert(stream.end(), out.begin(), out.begin() + static_cast<long>(size));
  }
  return stream;
}

void BM_DecodeFrames(benchmark::State& state) {
  const int units = static_cast<int>(state.range(0));
  constexpr int kFrames = 1000;
  const std::vector<uint8_t> stream = MakeStream(kFrames, units);
  StreamDecoder decoder;
  DecodedPacket packet;
  graspbed::sensor::RawFrame raw;
  int64_t frames = 0;
  for (auto _ : state) {
    std::span<const uint8_t> rest(stream);
    while (!rest.empty()) {
      const FeedResult fed = decoder.Feed(rest, &packet);
      rest = rest.subspan(fed.consumed);
      if (fed.packet) {
        ToRawFrame(packet.frame, &raw);
        ++frames;
      }
    }
    benchmark::DoNotOptimize(raw);
  }
  if (decoder.stats().corrupt() != 0) state.SkipWithError("corrupt packets in a clean stream");
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
  state.counters["x_nominal_1kHz"] =
      benchmark::Counter(static_cast<double>(frames) / 1000.0, benchmark::Counter::kIsRate);
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(stream.size()));
}
BENCHMARK(BM_DecodeFrames)->Arg(20)->Arg(9)->Arg(kMaxUnitsOnWire);

void BM_EncodeFrame(benchmark::State& state) {
  TactileFramePacket frame;
  frame.unit_count = 20;
  for (int k = 0; k < 20; ++k) frame.r1_milliohm[k] = frame.r2_milliohm[k] = 3'400'000u + k;
  std::array<uint8_t, kMaxWirePacketSize> out;
  for (auto _ : state) {
    ++frame.sequence;
    benchmark::DoNotOptimize(EncodePacket(frame, out));
  }
  state.counters["frames_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_EncodeFrame);

}  // namespace

BENCHMARK_MAIN();

// The hardware loop's latency over a pseudo-terminal: the device emulator streams 20-unit frames at
// 1 kHz (a fingertip pressed on four units after 0.3 s, no simulation behind it), and the host runs the
// one loop of `graspbed run --backend serial` with the reference controller closing; each frame's
// decode on the link thread to the write() of the command that answers it is recorded
// (docs/hardware.md, "Loop latency"). One iteration of --benchmark_filter=BM_LoopLatency/100000 is
// 100 s of real time. Counters: p50_us, p99_us, p999_us, max_us, frames answered, over 1 ms and 5 ms,
// frames the host dropped. For the loaded figure, run it beside two busy loops:
//   for i in 1 2; do (timeout 120 sh -c 'while :; do :; done' &); done; build/bench/loop_latency_bench
// With GRASPBED_BENCH_RT_PRIORITY=N the host runs under SCHED_FIFO at N, as `hw --realtime-priority`.
#include <benchmark/benchmark.h>

#include <sched.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <filesystem>
#include <string>

#include "hardware/device_emulator.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace {

using graspbed::hardware::DeviceEmulator;
using graspbed::hardware::EmulatorConfig;

constexpr int kUnits = 20;
constexpr double kR0Ohm = 3400.0;
/// A unit pressed with 2 N on the paper's gauge: R0 (1 + G kn Fn) = 3400 x (1 + 100 x 5.5e-4 x 2).
constexpr double kPressedOhm = kR0Ohm * (1.0 + 100.0 * 5.5e-4 * 2.0);
constexpr double kPressAtS = 0.3;

void BM_LoopLatency(benchmark::State& state) {
  const int64_t frames = state.range(0);
  if (const char* priority = std::getenv("GRASPBED_BENCH_RT_PRIORITY")) {
    // The host's threads (started below) inherit it; the emulator's thread too.
    sched_param parameters{};
    parameters.sched_priority = std::atoi(priority);
    if (::sched_setscheduler(0, SCHED_FIFO, &parameters) != 0) {
      state.SkipWithError("GRASPBED_BENCH_RT_PRIORITY: SCHED_FIFO refused");
      return;
    }
  }
  const std::string link = "/tmp/graspbed-latency-bench-" + std::to_string(::getpid());
  for (auto _ : state) {
    EmulatorConfig device;
    device.link_path = link;
    device.unit_count = kUnits;
    DeviceEmulator emulator(device, [](double device_time_s, bool, graspbed::sensor::RawFrame* frame) {
      for (int u = 0; u < kUnits; ++u) {
        const bool pressed = device_time_s >= kPressAtS && u < 4;
        frame->r1_ohm[u] = frame->r2_ohm[u] = pressed ? kPressedOhm : kR0Ohm;
      }
    });
    emulator.Start();

    graspbed::testbed::ScenarioConfig host;
    host.name = "loop_latency_bench";
    host.backend = graspbed::testbed::Backend::kSerial;
    host.serial.port = link;
    host.sensor.layout = "default_20";
    host.controller.name = "grip_slip";
    host.duration_s = static_cast<double>(frames) / 1000.0;
    graspbed::testbed::Action close;
    close.kind = graspbed::testbed::ActionKind::kClose;
    close.at_s = 0.2;  // after the 100-frame tare
    host.script = {close};
    host.Validate();
    graspbed::testbed::RunOptions run;
    run.latency_frames = static_cast<size_t>(frames) + 1000;
    const graspbed::testbed::RunResult result = graspbed::testbed::RunScenario(host, run);
    emulator.Stop();

    const auto& latency = result.bench.at("latency");
    state.counters["p50_us"] = latency.at("p50_us").get<double>();
    state.counters["p99_us"] = latency.at("p99_us").get<double>();
    state.counters["p999_us"] = latency.at("p999_us").get<double>();
    state.counters["max_us"] = latency.at("max_us").get<double>();
    state.counters["answered"] = static_cast<double>(latency.at("frames_answered").get<uint64_t>());
    state.counters["over_1ms"] = static_cast<double>(latency.at("over_1ms").get<uint64_t>());
    state.counters["over_5ms"] = static_cast<double>(latency.at("over_5ms").get<uint64_t>());
    state.counters["frames"] = static_cast<double>(result.bench.at("frames").get<uint64_t>());
    state.counters["dropped"] = static_cast<double>(result.bench.at("dropped").get<uint64_t>());
  }
}
// 100k frames (100 s) as the measurement; 5k (5 s) as a quick look.
BENCHMARK(BM_LoopLatency)->Arg(100000)->Arg(5000)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();

#pragma once
// Helpers shared by the serial tests: unique link paths, waiting on conditions (never bare sleeps),
// and a frame source with known resistances.

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include "sensor/raw_frame.h"

namespace graspbed::hardware::test_support {

/// Generous: tests must pass on a machine with both cores busy.
inline constexpr double kWaitTimeoutS = 10.0;

/// A fresh symlink path for one emulator.
inline std::string UniqueLinkPath(const std::string& tag) {
  static std::atomic<int> counter{0};
  return "/tmp/graspbed_test_" + std::to_string(getpid()) + "_" + tag + "_" + std::to_string(counter++);
}

/// Polls `condition` every millisecond until it holds or `timeout_s` passes; returns the last value.
inline bool WaitFor(const std::function<bool()>& condition, double timeout_s = kWaitTimeoutS) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return condition();
}

/// Frame source: unit k reads R1 = 3400 + k Ohm, R2 = 3400 - k Ohm, plus 0.001 Ohm per ms of device
/// time on R1 (so frames differ).
inline void TestFrameSource(double device_time_s, bool /*streaming*/, sensor::RawFrame* frame) {
  for (int k = 0; k < frame->unit_count; ++k) {
    frame->r1_ohm[k] = 3400.0 + k + device_time_s;
    frame->r2_ohm[k] = 3400.0 - k;
  }
}

}  // namespace graspbed::hardware::test_support

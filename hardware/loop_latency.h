#pragma once
/// The hardware loop's latency, frame by frame: from a tactile frame's decode on the serial link's
/// thread (its last byte just read) to the write() of the first motor command the control loop
/// computed after taking it (docs/hardware.md, "Loop latency"). Recorded into storage allocated
/// before the session, by the one thread that writes commands; summarised after the session.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace graspbed::hardware {

/// Percentiles of the recorded latencies (nearest rank) [us].
struct LatencySummary {
  uint64_t frames = 0;    ///< frames answered by a command and recorded
  uint64_t not_kept = 0;  ///< frames answered beyond the storage (counted, not in the figures)
  double p50_us = 0.0;
  double p99_us = 0.0;
  double p999_us = 0.0;
  double max_us = 0.0;
  uint64_t over_1ms = 0;  ///< recorded frames answered later than 1 ms
  uint64_t over_5ms = 0;  ///< ... later than 5 ms
};

class LatencyRecorder {
 public:
  /// Allocates room for `capacity` samples (0: recording off). Call before the writer starts.
  void Reserve(size_t capacity) {
    samples_.assign(capacity, 0);
    count_.store(0, std::memory_order_relaxed);
    not_kept_ = 0;
  }
  bool enabled() const { return !samples_.empty(); }
  /// One frame's latency [ns]; allocates nothing. One writer thread.
  void Record(int64_t latency_ns) {
    const size_t index = count_.load(std::memory_order_relaxed);
    if (index >= samples_.size()) {
      ++not_kept_;
      return;
    }
    samples_[index] = latency_ns;
    count_.store(index + 1, std::memory_order_release);
  }
  /// The figures so far (sorts a copy: call after the session, not in the loop).
  LatencySummary Summary() const {
    LatencySummary summary;
    const size_t count = count_.load(std::memory_order_acquire);
    summary.frames = count;
    summary.not_kept = not_kept_;
    if (count == 0) return summary;
    std::vector<int64_t> sorted(samples_.begin(), samples_.begin() + static_cast<std::ptrdiff_t>(count));
    std::sort(sorted.begin(), sorted.end());
    const auto rank = [&](double fraction) {
      const size_t index = static_cast<size_t>(fraction * static_cast<double>(count - 1) + 0.5);
      return static_cast<double>(sorted[std::min(index, count - 1)]) * 1e-3;
    };
    summary.p50_us = rank(0.5);
    summary.p99_us = rank(0.99);
    summary.p999_us = rank(0.999);
    summary.max_us = static_cast<double>(sorted.back()) * 1e-3;
    for (const int64_t ns : sorted) {
      summary.over_1ms += ns > 1'000'000 ? 1 : 0;
      summary.over_5ms += ns > 5'000'000 ? 1 : 0;
    }
    return summary;
  }

 private:
  std::vector<int64_t> samples_;
  std::atomic<size_t> count_{0};
  uint64_t not_kept_ = 0;
};

}  // namespace graspbed::hardware

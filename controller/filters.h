#pragma once
/// Small fixed-size discrete-time filters for the controllers: first-order low-pass, second-order
/// Butterworth high-pass and a fixed-capacity delay line. None of them allocates; all run at a
/// fixed sample rate set at construction.

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace graspbed::controller {

/// First-order low-pass (exponential moving average) y += a (x - y), a = 1 - exp(-dt / tau).
class LowPassFilter {
 public:
  LowPassFilter() = default;
  /// `time_constant_s` [s] (0 = pass-through), `sample_period_s` [s] > 0.
  LowPassFilter(double time_constant_s, double sample_period_s)
      : alpha_(time_constant_s > 0.0 ? 1.0 - std::exp(-sample_period_s / time_constant_s) : 1.0) {}

  /// Starts the output at `value` (no transient from zero).
  void Reset(double value) {
    value_ = value;
    primed_ = true;
  }
  /// Forgets the state; the next Update() output equals its input.
  void Clear() { primed_ = false; }
  /// Feeds one sample, returns the new output.
  double Update(double input) {
    if (!primed_) {
      Reset(input);
    } else {
      value_ += alpha_ * (input - value_);
    }
    return value_;
  }
  double value() const { return value_; }
  bool primed() const { return primed_; }

 private:
  double alpha_ = 1.0;
  double value_ = 0.0;
  bool primed_ = false;
};

/// Second-order Butterworth high-pass (RBJ biquad, bilinear transform), transposed direct form II.
/// A constant input gives exactly zero output once primed, so smooth (slow) signals such as an
/// inertial load from arm motion are rejected at 40 dB/decade below the cutoff.
class HighPassBiquad {
 public:
  HighPassBiquad() = default;
  /// `cutoff_hz` [Hz] must be below half of `sample_rate_hz` [Hz].
  HighPassBiquad(double cutoff_hz, double sample_rate_hz) {
    const double w0 = 2.0 * std::numbers::pi * cutoff_hz / sample_rate_hz;
    const double cos_w0 = std::cos(w0);
    const double alpha = std::sin(w0) / std::numbers::sqrt2;  // sin(w0) / (2 Q), Q = 1/sqrt(2)
    const double a0 = 1.0 + alpha;
    b0_ = (1.0 + cos_w0) / 2.0 / a0;
    b1_ = -(1.0 + cos_w0) / a0;
    b2_ = b0_;
    a1_ = -2.0 * cos_w0 / a0;
    a2_ = (1.0 - alpha) / a0;
  }

  /// Puts the filter in steady state for a constant input `value` (output 0, no step transient).
  void Reset(double value) {
    z2_ = b2_ * value;
    z1_ = (b1_ + b2_) * value;
  }
  /// Feeds one sample, returns the high-passed output.
  double Update(double input) {
    const double output = b0_ * input + z1_;
    z1_ = b1_ * input - a1_ * output + z2_;
    z2_ = b2_ * input - a2_ * output;
    return output;
  }

 private:
  double b0_ = 0.0, b1_ = 0.0, b2_ = 0.0, a1_ = 0.0, a2_ = 0.0;
  double z1_ = 0.0, z2_ = 0.0;
};

/// Fixed-capacity delay line: Push() one sample per tick, Delayed(n) reads the sample n ticks ago.
template <typename T, int kCapacity>
class DelayLine {
 public:
  void Clear() { size_ = 0; }
  void Push(const T& value) {
    head_ = (head_ + 1) % kCapacity;
    buffer_[static_cast<size_t>(head_)] = value;
    size_ = std::min(size_ + 1, kCapacity);
  }
  /// Samples held (at most kCapacity).
  int size() const { return size_; }
  /// The sample pushed `delay` pushes ago (0 = newest); requires delay < size().
  const T& Delayed(int delay) const {
    return buffer_[static_cast<size_t>((head_ - delay + kCapacity) % kCapacity)];
  }

 private:
  std::array<T, kCapacity> buffer_{};
  int head_ = 0;
  int size_ = 0;
};

}  // namespace graspbed::controller

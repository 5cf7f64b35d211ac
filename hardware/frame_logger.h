#pragma once
/// FrameLogger: one CSV row per decoded frame of a serial session, written off the control loop's
/// thread. The loop takes only the newest frame at each tick; the logger drains every frame the
/// link tapped (SerialLink::EnableTap / PopTap) and runs its own readout and inversion on each, with
/// the same configuration and the same re-tare on a new device session, so the log misses no frame.
/// Columns (docs/hardware.md, "The frame log"): seq, device_time_s, then per unit k r1_k, r2_k [Ohm],
/// fn_k, ft_k [N, unit frame] and valid_k (0/1), then, when the caller names them (HandLogColumns),
/// the hand state the link held with the frame (its newest HAND; time on the device's clock), an
/// unknown value `nan` as in signals.csv.
/// The file is written as PATH.partial and renamed to PATH by Finish(); a log that was not finished
/// (a crash, an exception) stays PATH.partial and never looks complete.

#include <atomic>
#include <cstdint>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "hardware/serial_link.h"
#include "sensor/calibration.h"
#include "sensor/inversion.h"
#include "sensor/layout.h"
#include "sensor/readout.h"
#include "sensor/tactile_state.h"

namespace graspbed::hardware {

/// Where the logger takes frames from: writes the oldest untaken frame into its argument and returns
/// true, or returns false when there is none (SerialLink::PopTap; a queue in tests). Called from the
/// logger's thread only.
using TapSource = std::function<bool(TappedFrame*)>;

/// The hand columns of a frame log: their names, and how to fill one cell per name from a hand state
/// (NaN: unknown). The caller's, so the frame log's hand columns are signals.csv's. Empty: none.
struct HandLogColumns {
  std::vector<std::string> names;
  std::function<void(const hand::HandState& hand, double* cells)> write;
};

class FrameLogger {
 public:
  /// Opens PATH.partial, writes the header and starts the writer thread. `nominal_r0_ohm` as the
  /// backend reports it (the readout's starting baseline). Throws std::invalid_argument naming the
  /// path when it cannot be written.
  FrameLogger(std::string path, TapSource source, const sensor::Layout& layout,
              const sensor::Calibration& calibration, const sensor::ReadoutConfig& readout,
              const sensor::InversionConfig& inversion, double nominal_r0_ohm, HandLogColumns hand = {});
  /// Stops the writer thread; an unfinished log stays PATH.partial.
  ~FrameLogger();
  FrameLogger(const FrameLogger&) = delete;
  FrameLogger& operator=(const FrameLogger&) = delete;

  /// Drains what is left in the source, closes and renames the file. Call after the source has
  /// stopped producing (the link has stopped). On a write or rename failure the file stays
  /// PATH.partial and error() says why. Safe to call twice.
  void Finish();
  /// Rows written so far.
  uint64_t rows() const { return rows_.load(); }
  /// Empty unless Finish() could not complete the file.
  const std::string& error() const { return error_; }

 private:
  bool StopThread();
  void Run();
  void Write();

  std::string path_;
  TapSource source_;
  int unit_count_;
  sensor::Readout readout_;
  sensor::Inversion inversion_;
  TappedFrame entry_;
  sensor::ReadoutFrame readout_frame_;
  sensor::TactileState state_;
  uint64_t session_ = 1;  ///< SerialLink sessions start at 1
  HandLogColumns hand_;
  std::vector<double> hand_cells_;  ///< one per hand column, allocated once
  std::ofstream out_;
  std::thread thread_;
  std::atomic<bool> done_{false};
  std::atomic<uint64_t> rows_{0};
  std::string error_;
};

}  // namespace graspbed::hardware

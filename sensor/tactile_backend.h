#pragma once
/// TactileBackend: the boundary between a frame source (simulation, serial hardware, replay) and
/// the shared readout path. Modelled on ros2_control's SystemInterface: read() returns a status.

#include <cstdint>
#include <string>

#include "sensor/raw_frame.h"

namespace graspbed::sensor {

/// Outcome of one Read(); errors in the loop are values, never exceptions.
enum class ReadStatus {
  kOk,            ///< a new frame was written
  kNoNewFrame,    ///< nothing new since the last read (normal between samples)
  kStale,         ///< no valid frame for longer than the stale timeout
  kDisconnected,  ///< the source is gone (device unplugged); the backend may be reconnecting
};

/// Fault and traffic counters every backend keeps; reported at the end of a run.
struct BackendCounters {
  uint64_t frames = 0;           ///< frames delivered
  uint64_t corrupt = 0;          ///< packets dropped for CRC, COBS or length errors
  uint64_t dropped = 0;          ///< frames missing from the sequence (gaps)
  uint64_t unknown_packets = 0;  ///< packets of an unknown type, ignored
  uint64_t reconnects = 0;       ///< times the link was re-established
  uint64_t stale_periods = 0;    ///< times the stream went stale
  uint64_t sessions = 0;         ///< device sessions (a reboot starts a new one; readout re-tares)
};

/// A source of RawFrames. Owners of devices: not copyable, not movable.
class TactileBackend {
 public:
  TactileBackend() = default;
  TactileBackend(const TactileBackend&) = delete;
  TactileBackend& operator=(const TactileBackend&) = delete;
  virtual ~TactileBackend() = default;

  /// Connects and starts streaming. Throws std::runtime_error on a fault the user must fix
  /// (missing port, unit-count mismatch); default: nothing to do.
  virtual void Start() {}
  /// Stops streaming and releases the source; must be safe to call twice.
  virtual void Stop() {}

  /// Copies the newest complete frame into `frame` when there is one newer than the last read.
  /// Never blocks and never allocates.
  virtual ReadStatus Read(RawFrame* frame) = 0;

  /// Units per frame (must equal the layout's).
  virtual int unit_count() const = 0;
  /// Nominal resistance of the gauges [Ohm] (for taring before a baseline exists).
  virtual double nominal_r0_ohm() const = 0;
  /// Increments when the source starts a new session (device reboot): the readout re-tares.
  virtual uint64_t session() const { return 0; }
  virtual BackendCounters counters() const { return {}; }
  /// Short name for reports ("sim", "serial", "replay").
  virtual std::string name() const = 0;
};

}  // namespace graspbed::sensor

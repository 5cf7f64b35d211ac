#pragma once
/// A recorded bench or simulated session, and ReplayBackend, the TactileBackend that serves it again
/// tick by tick at its recorded times (`backend: replay`, docs/hardware.md "Replay").
/// Two recordings are read:
///  - a run's signals.csv (`graspbed run`, any backend): one row per control tick with the frame the
///    loop took (r1_ohm_K, r2_ohm_K), and, from this version on, the tick's read status, frame
///    sequence, time, flags and device session, the intent and the commands written. Replaying such
///    a file with the controller that recorded it reproduces its commands bit for bit (the numbers
///    are written to round-trip). An older signals.csv without read_status counts a row as a new
///    frame when its resistances differ from the row before.
///  - a frame log (`graspbed hw --log`, `graspbed run --backend serial --log`): one row per decoded
///    frame (seq, device_time_s, r1_K, r2_K, ...); each frame is one tick at its device time, counted
///    from the first frame. It carries no intent and no commands.
/// Both may carry the hand state the loop held (signals.csv's hand columns; a frame log's from a link
/// that received HANDs), read when the caller names the columns; a recording without them replays
/// with the hand unknown.
/// Loading reads the whole file (allocates); serving allocates nothing.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "hand/hand_command.h"
#include "sensor/raw_frame.h"
#include "sensor/tactile_backend.h"

namespace graspbed::hardware {

struct RecordedSession {
  enum class Kind { kRunSignals, kFrameLog };
  Kind kind = Kind::kRunSignals;
  std::string path;
  int unit_count = 0;
  std::vector<double> time_s;              ///< per tick: the loop's clock [s]
  std::vector<sensor::ReadStatus> status;  ///< per tick: what the backend returned
  std::vector<uint64_t> session;           ///< per tick: device session (re-tare on change)
  std::vector<uint32_t> sequence;          ///< per tick: frame sequence number
  std::vector<double> frame_time_s;        ///< per tick: the frame's own sample time [s]
  std::vector<uint8_t> flags;              ///< per tick: frame flags
  std::vector<double> r1_ohm;              ///< ticks x unit_count, row-major [Ohm]
  std::vector<double> r2_ohm;              ///< ticks x unit_count, row-major [Ohm]
  /// Per tick: the intent then ("close", "open", "idle"); empty when the recording has none.
  std::vector<std::string> intent;
  /// Per tick: the command written and the controller's phase; empty when not recorded.
  std::vector<hand::HandCommand> commands;
  std::vector<std::string> phase;
  /// Per tick: the hand columns named at loading, hand_column_count cells each (NaN, written `nan`
  /// or left empty: unknown); the first, a time, on the loop's clock (a frame log's shifted like its ticks).
  /// Empty when the recording lacks any of them (made before they existed, or a version-1 device's log).
  std::vector<double> hand_cells;
  size_t hand_column_count = 0;

  size_t ticks() const { return time_s.size(); }
  bool has_hand() const { return !hand_cells.empty(); }
  const char* kind_name() const { return kind == Kind::kRunSignals ? "signals.csv" : "frame log"; }
};

/// Reads a recording, and its `hand_columns` when it has every one of them (the first a time [s] on
/// the recording's clock). Throws common::ConfigError "PATH:LINE: ..." naming the column and value
/// for a file that is neither kind, a malformed number, a row of the wrong length, or a unit count
/// other than `expected_units`.
RecordedSession LoadRecordedSession(const std::string& path, int expected_units,
                                    std::span<const char* const> hand_columns = {});

/// Serves a RecordedSession: Seek(k) before the loop's k-th tick, then Read() returns that tick's
/// status, with its frame when the status is kOk. The session must outlive the backend.
class ReplayBackend : public sensor::TactileBackend {
 public:
  ReplayBackend(const RecordedSession& recording, double nominal_r0_ohm);

  /// Selects tick `tick` (< recording.ticks()). Never allocates.
  void Seek(size_t tick);
  sensor::ReadStatus Read(sensor::RawFrame* frame) override;
  int unit_count() const override { return recording_.unit_count; }
  double nominal_r0_ohm() const override { return nominal_r0_ohm_; }
  uint64_t session() const override { return recording_.session[tick_]; }
  sensor::BackendCounters counters() const override { return counters_; }
  std::string name() const override { return "replay"; }

 private:
  const RecordedSession& recording_;
  double nominal_r0_ohm_;
  size_t tick_ = 0;
  bool served_ = false;
  sensor::BackendCounters counters_;
};

}  // namespace graspbed::hardware

#pragma once
/// Pieces every backend's run shares (the run loop, RunScenario, and the backends of run_backend.h):
/// the output directory, the columns of the control loop and of the units in signals.csv, and the
/// plots drawn from them. Internal to graspbed_testbed_run.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/plot.h"
#include "common/signal_log.h"
#include "controller/control_loop.h"
#include "controller/grasp_controller.h"
#include "sensor/layout.h"
#include "sensor/strain_model.h"
#include "testbed/runner.h"

namespace graspbed::testbed::internal {

/// `value` printed with `format` (one printf conversion), "-" when absent: tables' empty cells.
std::string OptionalText(const std::optional<double>& value, const char* format);
/// `value`, or JSON null when absent.
nlohmann::json OptionalJson(const std::optional<double>& value);

/// Name of the file that marks a run in progress or interrupted.
inline constexpr const char* kIncompleteMarker = "INCOMPLETE";

/// Creates `dir` (std::invalid_argument naming --out when it cannot), removes the files an earlier
/// run left there, and marks it INCOMPLETE.
void PrepareOutputDir(const std::string& dir);

/// The columns of signals.csv every backend writes, in this order from time_s on: the command
/// written, the controller's telemetry, the estimate's totals, and the tick's read: read_status
/// (sensor::ReadStatus as 0..3), frame_seq, frame_time_s [s], frame_flags and session of the frame
/// the loop holds; then the hand state the controller saw (hand::HandState): its sample time [s],
/// stale flag and joint kind (hand_linear: 1 slides [m], 0 hinges [rad]), and per digit (finger, then
/// thumb) joint positions q1, q2 [rad or m], velocities dq1, dq2 [rad/s or m/s], motor current and
/// stall current [A], the end-stop flags and the encoder fault. An unknown value is NaN (written
/// `nan`), never 0. Everything a replay needs to feed the loop the same input again.
enum LoopColumn : size_t {
  kTime,
  kGripEffort,
  kEnable,
  kBrake,
  kGripTarget,
  kFrictionEstimate,
  kSlipFlag,
  kSafeHold,
  kStale,
  kValidUnits,
  kContactUnits,
  kEstTotalFn,
  kEstShearAxial,
  kEstShearCirc,
  kReadStatus,
  kFrameSeq,
  kFrameTime,
  kFrameFlags,
  kSession,
  kHandTime,
  kHandStale,
  kHandLinear,
  kHandDigits,  ///< first of kHandDigitColumnCount columns per digit, finger then thumb
  kLoopColumnCount = kHandDigits + 2 * 9
};
/// The hand columns of one digit, from kHandDigits + digit x kHandDigitColumnCount on.
enum HandDigitColumn : size_t {
  kDigitQ1,
  kDigitQ2,
  kDigitDq1,
  kDigitDq2,
  kDigitCurrent,
  kDigitStallCurrent,
  kDigitAtOpenStop,
  kDigitAtClosedStop,
  kDigitEncoderFault,
  kHandDigitColumnCount
};
static_assert(kLoopColumnCount == kHandDigits + hand::kMaxDigits * kHandDigitColumnCount);
extern const char* const kLoopColumnNames[kLoopColumnCount];

/// Fills the kLoopColumnCount loop cells of `row` for the tick at `time_s` [s] that just ran.
void WriteLoopCells(double* row, double time_s, const controller::ControlLoop& loop,
                    const controller::ControllerTelemetry& telemetry);
/// Fills the hand columns of `row` (loop columns first: row[kHandTime] on) from `hand`, unknown
/// fields NaN (what WriteLoopCells writes for the loop's hand state; the frame log's too).
void WriteHandCells(double* row, const hand::HandState& hand);
/// The names of the hand columns, kHandTime to kLoopColumnCount (hand_time_s first).
inline std::span<const char* const> HandColumnNames() {
  return std::span<const char* const>(kLoopColumnNames + kHandTime, kLoopColumnCount - kHandTime);
}
/// The hand state the hand columns of `row` (a signals.csv row, loop columns first) hold: what
/// WriteLoopCells wrote, NaN cells unknown. A row without them (`has_columns` false: a recording
/// made before they existed) gives a hand with no proprioception.
hand::HandState ReadHandCells(const double* row, bool has_columns);

/// The per-unit columns of signals.csv, declared once for every backend: r1_ohm, r2_ohm, fn_est_n,
/// ft_est_n, then (`with_truth`: the simulation only) fn_true_n and ft_true_n, then validity; "_K"
/// after each for unit K, unit by unit.
std::vector<std::string> UnitColumns(int units, bool with_truth);
/// The simulation's ground-truth columns of signals.csv, after the loop's and before the units', in
/// the order the simulation backend fills them (testbed/sim_run.cc). A bench backend has none of them.
inline constexpr std::array<const char*, 28> kGroundTruthColumnNames = {
    "true_sensed_fn_n",   "true_finger_fn_n",   "true_thumb_fn_n",     "true_squeeze_n",
    "true_links_fn_n",    "true_palm_fn_n",
    "slip_speed_mm_s",    "sliding_speed_mm_s", "finger_sliding_mm_s", "thumb_sliding_mm_s",
    "sliding_load_share", "load_bound_grip_n",  "object_x_m",          "object_y_m",
    "object_z_m",         "object_height_m",    "wrist_x_m",           "wrist_y_m",
    "wrist_z_m",          "wrist_target_z_m",   "grip_closure_m",      "object_mass_kg",
    "external_force_x_n", "external_force_y_n", "external_force_z_n",  "holding",
    "slip_event",         "slip_distance_mm"};
/// Every column only the simulation writes for `units` units: kGroundTruthColumnNames, then each
/// unit's truth columns (UnitColumns with_truth less without).
std::vector<std::string> GroundTruthColumns(int units);
/// Fills the UnitColumns of `units` units for the tick `loop` just ran into `cells`: its frame and
/// estimate, and `true_loads` (one per unit) when not empty.
void WriteUnitCells(double* cells, int units, const controller::ControlLoop& loop,
                    std::span<const sensor::UnitLoad> true_loads);

/// The signals.csv columns of `controller`'s diagnostic channels, "ctl_<name>" each, after the
/// backend's own. @throws std::invalid_argument naming the controller when it declares more than
/// controller::kMaxDiagnosticChannels, a name that is empty, repeated or not lower-case letters,
/// digits and '_'.
std::vector<std::string> DiagnosticColumns(const controller::GraspController& controller);
/// Fills `count` cells of `row` from `first` on with the controller's diagnostics.
inline void WriteDiagnosticCells(double* row, size_t first, size_t count,
                                 const controller::GraspController& controller) {
  if (count > 0) controller.ReadDiagnostics(std::span<double>(row + first, count));
}

/// A chart with its labels.
plot::Chart MakeChart(const std::string& title, const std::string& x_label, const std::string& y_label);
/// A dashed horizontal line from x0 to x1 at y.
plot::Series HorizontalLine(const std::string& name, double x0, double x1, double y);
/// Column `column` of `log` against `time`, scaled.
plot::Series Line(const common::SignalLog& log, const std::vector<double>& time, const std::string& column,
                  const std::string& name, double scale = 1.0, bool dashed = false);
/// Unit `unit` of `layout` named as the layout picture (`graspbed sensor layout --picture`) names it:
/// its number in layout order, its row and its column, e.g. "unit 7 (row 1, column 2)".
std::string UnitName(const sensor::Layout& layout, int unit);
/// A unit carried load when its peak estimated Fn is at least this share of the most loaded unit's [-].
inline constexpr double kCarriedLoadShare = 0.1;
/// The estimated Fn against time (columns fn_est_n_K) of every unit of `layout`: those that carried
/// load (kCarriedLoadShare; at most plot::kPaletteSize, the most loaded) each in a colour of its own
/// (plot::PaletteColour(0), (1), ... in unit order) and named by UnitName; the others as grey lines
/// under them with one legend entry for all, so no colour repeats.
plot::Chart PerUnitFnChart(const common::SignalLog& log, const std::vector<double>& time,
                           const sensor::Layout& layout);
/// One marker per script action that fired, at the time it fired.
std::vector<plot::Marker> ScriptMarkers(const RunResult& result);
/// taxels_fn.png and taxels_ft.png: units x time maps of the estimated Fn and Ft (columns
/// fn_est_n_K, ft_est_n_K, validity_K).
void WriteTaxelMaps(const RunResult& result, const common::SignalLog& log, const sensor::Layout& layout,
                    const std::vector<double>& time, const std::string& title, const std::string& dir);

/// SummaryTable for backend serial and replay (bench_run.cc).
std::string BenchSummaryTable(const RunResult& result);

}  // namespace graspbed::testbed::internal

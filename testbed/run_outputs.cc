#include "testbed/run_outputs.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>

namespace graspbed::testbed {
namespace internal {
namespace {

namespace fs = std::filesystem;

// Files a run writes; removed at the start so an old result never sits next to a new run.
constexpr const char* kOutputFiles[] = {
    "config.yaml", "signals.csv", "summary.json",   "forces.png",    "estimate_vs_truth.png",
    "grip.png",    "slip.png",    "height.png",     "taxels_fn.png", "taxels_ft.png",
    "states.csv",  "video.mp4",   "video_strip.png"};
// Smallest colour-scale end of the taxel maps [N]: an unloaded run shows its noise pale, not as load.
constexpr double kTaxelScaleFloorN = 0.5;

}  // namespace

const char* const kLoopColumnNames[kLoopColumnCount] = {"time_s",
                                                        "grip_effort",
                                                        "motor_enable",
                                                        "brake",
                                                        "grip_target_n",
                                                        "friction_estimate",
                                                        "slip_flag",
                                                        "safe_hold",
                                                        "stale",
                                                        "valid_units",
                                                        "contact_units",
                                                        "est_total_fn_n",
                                                        "est_shear_axial_n",
                                                        "est_shear_circumferential_n",
                                                        "read_status",
                                                        "frame_seq",
                                                        "frame_time_s",
                                                        "frame_flags",
                                                        "session",
                                                        "hand_time_s",
                                                        "hand_stale",
                                                        "hand_linear",
                                                        "finger_q1",
                                                        "finger_q2",
                                                        "finger_dq1",
                                                        "finger_dq2",
                                                        "finger_current_a",
                                                        "finger_stall_current_a",
                                                        "finger_at_open_stop",
                                                        "finger_at_closed_stop",
                                                        "finger_encoder_fault",
                                                        "thumb_q1",
                                                        "thumb_q2",
                                                        "thumb_dq1",
                                                        "thumb_dq2",
                                                        "thumb_current_a",
                                                        "thumb_stall_current_a",
                                                        "thumb_at_open_stop",
                                                        "thumb_at_closed_stop",
                                                        "thumb_encoder_fault"};

std::vector<std::string> DiagnosticColumns(const controller::GraspController& controller) {
  const std::span<const controller::DiagnosticChannel> channels = controller.diagnostic_channels();
  const auto refuse = [&controller](const std::string& what) {
    throw std::invalid_argument("controller '" + controller.name() + "': " + what);
  };
  if (channels.size() > controller::kMaxDiagnosticChannels) {
    refuse("declares " + std::to_string(channels.size()) + " diagnostic channels (at most " +
           std::to_string(controller::kMaxDiagnosticChannels) + ")");
  }
  std::vector<std::string> columns;
  for (const controller::DiagnosticChannel& channel : channels) {
    const std::string name = channel.name != nullptr ? channel.name : "";
    const bool valid = !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
      return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
    });
    if (!valid) refuse("diagnostic channel '" + name + "': a name is lower-case letters, digits and '_'");
    const std::string column = "ctl_" + name;
    if (std::find(columns.begin(), columns.end(), column) != columns.end())
      refuse("diagnostic channel '" + name + "' declared twice");
    columns.push_back(column);
  }
  return columns;
}

namespace {

constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();

double Flag(bool known, bool value) { return known ? (value ? 1.0 : 0.0) : kUnknown; }

}  // namespace

void WriteHandCells(double* row, const hand::HandState& hand) {
  const bool any = hand.digit_count > 0 && hand.time_s >= 0.0;
  row[kHandTime] = any ? hand.time_s : kUnknown;
  row[kHandStale] = Flag(any, hand.stale);
  row[kHandLinear] = Flag(any, hand.digits[0].linear);
  for (int d = 0; d < hand::kMaxDigits; ++d) {
    double* cells = row + kHandDigits + d * kHandDigitColumnCount;
    const hand::DigitState& digit = hand.digits[d];
    const bool present = any && d < hand.digit_count;
    for (int j = 0; j < hand::kMaxDigitJoints; ++j) {
      const bool joint = present && j < digit.joint_count;
      cells[kDigitQ1 + j] = joint && digit.position_known ? digit.joint_position[j] : kUnknown;
      cells[kDigitDq1 + j] = joint && digit.velocity_known ? digit.joint_velocity[j] : kUnknown;
    }
    cells[kDigitCurrent] = present && digit.current_known ? digit.motor_current_a : kUnknown;
    cells[kDigitStallCurrent] = present && digit.stall_current_a > 0.0 ? digit.stall_current_a : kUnknown;
    cells[kDigitAtOpenStop] = Flag(present && digit.stops_known, digit.at_open_stop);
    cells[kDigitAtClosedStop] = Flag(present && digit.stops_known, digit.at_closed_stop);
    cells[kDigitEncoderFault] = Flag(present, digit.encoder_fault);
  }
}

void WriteLoopCells(double* row, double time_s, const controller::ControlLoop& loop,
                    const controller::ControllerTelemetry& telemetry) {
  const hand::HandCommand& command = loop.command();
  const sensor::TactileState& state = loop.state();
  const sensor::RawFrame& frame = loop.frame();
  row[kTime] = time_s;
  row[kGripEffort] = command.grip_effort;
  row[kEnable] = command.enable ? 1.0 : 0.0;
  row[kBrake] = command.brake ? 1.0 : 0.0;
  row[kGripTarget] = telemetry.grip_target_n;
  row[kFrictionEstimate] = telemetry.friction_estimate;
  row[kSlipFlag] = telemetry.slip_detected ? 1.0 : 0.0;
  row[kSafeHold] = telemetry.safe_hold ? 1.0 : 0.0;
  row[kStale] = state.stale ? 1.0 : 0.0;
  row[kValidUnits] = state.valid_count;
  row[kContactUnits] = state.contact_count;
  row[kEstTotalFn] = state.total_fn_n;
  row[kEstShearAxial] = state.total_shear_axial_n;
  row[kEstShearCirc] = state.total_shear_circumferential_n;
  row[kReadStatus] = static_cast<double>(loop.last_status());
  row[kFrameSeq] = frame.sequence;
  row[kFrameTime] = frame.time_s;
  row[kFrameFlags] = frame.flags;
  row[kSession] = static_cast<double>(loop.session());
  WriteHandCells(row, loop.hand_state());
}

hand::HandState ReadHandCells(const double* row, bool has_columns) {
  hand::HandState hand;
  if (!has_columns || std::isnan(row[kHandTime])) return hand;
  hand.time_s = row[kHandTime];
  hand.stale = row[kHandStale] != 0.0;
  hand.digit_count = hand::kMaxDigits;
  for (int d = 0; d < hand::kMaxDigits; ++d) {
    const double* cells = row + kHandDigits + d * kHandDigitColumnCount;
    hand::DigitState& digit = hand.digits[d];
    digit.linear = row[kHandLinear] == 1.0;
    digit.joint_count = std::isnan(cells[kDigitQ2]) ? 1 : 2;
    digit.position_known = !std::isnan(cells[kDigitQ1]);
    digit.velocity_known = !std::isnan(cells[kDigitDq1]);
    digit.current_known = !std::isnan(cells[kDigitCurrent]);
    digit.stops_known = !std::isnan(cells[kDigitAtOpenStop]);
    digit.encoder_fault = cells[kDigitEncoderFault] == 1.0;
    for (int j = 0; j < digit.joint_count; ++j) {
      digit.joint_position[j] = digit.position_known ? cells[kDigitQ1 + j] : 0.0;
      digit.joint_velocity[j] = digit.velocity_known ? cells[kDigitDq1 + j] : 0.0;
    }
    digit.motor_current_a = digit.current_known ? cells[kDigitCurrent] : 0.0;
    digit.stall_current_a = std::isnan(cells[kDigitStallCurrent]) ? 0.0 : cells[kDigitStallCurrent];
    digit.at_open_stop = digit.stops_known && cells[kDigitAtOpenStop] == 1.0;
    digit.at_closed_stop = digit.stops_known && cells[kDigitAtClosedStop] == 1.0;
  }
  return hand;
}

namespace {
// Per-unit columns, in this order per unit; the truth's only on the simulation.
struct UnitColumn {
  const char* name;
  bool truth;
};
constexpr UnitColumn kUnitColumns[] = {{"r1_ohm", false},   {"r2_ohm", false},   {"fn_est_n", false},
                                       {"ft_est_n", false}, {"fn_true_n", true}, {"ft_true_n", true},
                                       {"validity", false}};
static_assert(std::size(kUnitColumns) <= kSignalBoundColumnsPerUnit,
              "the loader's bound on signal memory must count every column");
}  // namespace

std::vector<std::string> UnitColumns(int units, bool with_truth) {
  std::vector<std::string> names;
  for (int u = 0; u < units; ++u) {
    for (const UnitColumn& column : kUnitColumns) {
      if (with_truth || !column.truth) names.push_back(std::string(column.name) + "_" + std::to_string(u));
    }
  }
  return names;
}

std::vector<std::string> GroundTruthColumns(int units) {
  std::vector<std::string> names(kGroundTruthColumnNames.begin(), kGroundTruthColumnNames.end());
  const std::vector<std::string> without = UnitColumns(units, /*with_truth=*/false);
  for (const std::string& name : UnitColumns(units, /*with_truth=*/true)) {
    if (std::find(without.begin(), without.end(), name) == without.end()) names.push_back(name);
  }
  return names;
}

void WriteUnitCells(double* cells, int units, const controller::ControlLoop& loop,
                    std::span<const sensor::UnitLoad> true_loads) {
  const sensor::RawFrame& frame = loop.frame();
  const sensor::TactileState& state = loop.state();
  const bool truth = !true_loads.empty();
  for (int u = 0; u < units; ++u) {
    *cells++ = frame.r1_ohm[u];
    *cells++ = frame.r2_ohm[u];
    *cells++ = state.fn_n[u];
    *cells++ = state.ft_n[u];
    if (truth) {
      *cells++ = true_loads[static_cast<size_t>(u)].fn_n;
      *cells++ = true_loads[static_cast<size_t>(u)].ft_n;
    }
    *cells++ = static_cast<double>(state.validity[u]);
  }
}

std::string OptionalText(const std::optional<double>& value, const char* format) {
  if (!value) return "-";
  char text[48];
  std::snprintf(text, sizeof(text), format, *value);
  return text;
}

nlohmann::json OptionalJson(const std::optional<double>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json(nullptr);
}


plot::Chart MakeChart(const std::string& title, const std::string& x_label, const std::string& y_label) {
  plot::Chart chart;
  chart.title = title;
  chart.x_label = x_label;
  chart.y_label = y_label;
  return chart;
}

plot::Series HorizontalLine(const std::string& name, double x0, double x1, double y) {
  plot::Series series;
  series.name = name;
  series.x = {x0, x1};
  series.y = {y, y};
  series.dashed = true;
  return series;
}

plot::Series Line(const common::SignalLog& log, const std::vector<double>& time, const std::string& column,
                  const std::string& name, double scale, bool dashed) {
  plot::Series series;
  series.name = name;
  series.x = time;
  series.y = log.ColumnValues(column);
  for (double& value : series.y) value *= scale;
  series.dashed = dashed;
  return series;
}

std::string UnitName(const sensor::Layout& layout, int unit) {
  const sensor::UnitPose& pose = layout.units.at(static_cast<size_t>(unit));
  return "unit " + std::to_string(unit) + " (row " + std::to_string(pose.row) + ", column " +
         std::to_string(pose.column) + ")";
}

plot::Chart PerUnitFnChart(const common::SignalLog& log, const std::vector<double>& time,
                           const sensor::Layout& layout) {
  // Twenty lines in eight colours cannot show which unit carries the load: colour only the units
  // that did, grey for the rest.
  constexpr plot::Colour kUnloadedGrey{0.78, 0.78, 0.78};
  const int units = layout.unit_count();
  std::vector<plot::Series> lines;
  std::vector<std::pair<double, int>> peaks;  // (peak estimated Fn [N], unit)
  for (int u = 0; u < units; ++u) {
    lines.push_back(Line(log, time, "fn_est_n_" + std::to_string(u), UnitName(layout, u)));
    double peak = 0.0;
    for (double value : lines.back().y) {
      if (std::isfinite(value)) peak = std::max(peak, value);
    }
    peaks.emplace_back(peak, u);
  }
  std::sort(peaks.begin(), peaks.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<bool> loaded(static_cast<size_t>(units), false);
  int loaded_count = 0;
  for (const auto& [peak, unit] : peaks) {
    if (loaded_count == plot::kPaletteSize ||
        !(peak > 0.0 && peak >= kCarriedLoadShare * peaks.front().first))
      break;
    loaded[static_cast<size_t>(unit)] = true;
    ++loaded_count;
  }
  plot::Chart chart =
      MakeChart("Estimated normal force per unit (numbers as in the layout picture)", "time [s]", "Fn [N]");
  bool grey_named = false;
  for (int u = 0; u < units; ++u) {
    if (loaded[static_cast<size_t>(u)]) continue;
    plot::Series& line = lines[static_cast<size_t>(u)];
    line.colour = kUnloadedGrey;
    line.name = grey_named ? "" : std::to_string(units - loaded_count) + " other units";
    grey_named = true;
    chart.series.push_back(std::move(line));
  }
  int colour = 0;
  for (int u = 0; u < units; ++u) {
    if (!loaded[static_cast<size_t>(u)]) continue;
    plot::Series& line = lines[static_cast<size_t>(u)];
    line.colour = plot::PaletteColour(colour++);
    chart.series.push_back(std::move(line));
  }
  chart.include_zero_y = true;
  return chart;
}

// One marker per action that fired, at the time it fired (an event action's time is the run's).
std::vector<plot::Marker> ScriptMarkers(const RunResult& result) {
  std::vector<plot::Marker> markers;
  for (size_t i = 0; i < result.config.script.size(); ++i) {
    const double fired_s = i < result.script_timings.size() ? result.script_timings[i].fired_s : -1.0;
    if (fired_s >= 0.0) markers.push_back({fired_s, ActionName(result.config.script[i].kind)});
  }
  return markers;
}

// Units x time colour maps of the estimated Fn and Ft ("which units were loaded when"): one row per
// unit in layout order, labelled with its index, row and column and beam axis; an invalid estimate
// (dead, shorted, saturated, not yet tared) is grey.
void WriteTaxelMaps(const RunResult& result, const common::SignalLog& log, const sensor::Layout& layout,
                    const std::vector<double>& time, const std::string& title, const std::string& dir) {
  plot::Heatmap fn;
  fn.x_label = "time [s]";
  fn.row_label = "unit (row, column, beam axis)";
  fn.x = time;
  fn.markers = ScriptMarkers(result);
  plot::Heatmap ft = fn;
  double fn_max = kTaxelScaleFloorN;
  double ft_max = kTaxelScaleFloorN;
  for (int u = 0; u < layout.unit_count(); ++u) {
    const sensor::UnitPose& pose = layout.units[static_cast<size_t>(u)];
    const std::string label = std::to_string(u) + " (r" + std::to_string(pose.row) + " c" +
                              std::to_string(pose.column) +
                              (pose.orientation == sensor::BeamOrientation::kAxial ? ", ax)" : ", circ)");
    fn.row_labels.push_back(label);
    ft.row_labels.push_back(label);
    std::vector<double> fn_row = log.ColumnValues("fn_est_n_" + std::to_string(u));
    std::vector<double> ft_row = log.ColumnValues("ft_est_n_" + std::to_string(u));
    const std::vector<double> validity = log.ColumnValues("validity_" + std::to_string(u));
    for (size_t i = 0; i < validity.size(); ++i) {
      if (validity[i] != static_cast<double>(sensor::UnitValidity::kValid)) {
        fn_row[i] = ft_row[i] = std::numeric_limits<double>::quiet_NaN();
        continue;
      }
      if (std::isfinite(fn_row[i])) fn_max = std::max(fn_max, fn_row[i]);
      if (std::isfinite(ft_row[i])) ft_max = std::max(ft_max, std::abs(ft_row[i]));
    }
    fn.values.push_back(std::move(fn_row));
    ft.values.push_back(std::move(ft_row));
  }
  fn.title = title + ": estimated Fn per unit";
  fn.value_label = "Fn [N], estimated";
  fn.value_max = fn_max;
  ft.title = title + ": estimated Ft per unit (along its beam)";
  ft.value_label = "Ft [N], estimated";
  ft.signed_scale = true;
  ft.value_max = ft_max;
  plot::WritePng(fn, dir + "/taxels_fn.png");
  plot::WritePng(ft, dir + "/taxels_ft.png");
}

void PrepareOutputDir(const std::string& dir) {
  std::error_code error;
  fs::create_directories(dir, error);
  // A place the user named that cannot hold results is bad input (exit 2), not a failed expectation.
  if (error || !fs::is_directory(dir)) {
    throw std::invalid_argument("--out " + dir + ": cannot create the output directory" +
                                (error ? " (" + error.message() + ")" : ""));
  }
  for (const char* name : kOutputFiles) fs::remove(fs::path(dir) / name, error);
  common::WriteFileAtomic(dir + "/" + kIncompleteMarker,
                  "This run is in progress or was interrupted; its results are not complete.\n");
}

}  // namespace internal


}  // namespace graspbed::testbed

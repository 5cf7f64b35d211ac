#pragma once
/// Sim versus real (`graspbed compare RUN_A RUN_B`): two runs' signals.csv -- typically a session on
/// the hand (backend serial) and the simulated scenario it followed -- aligned piecewise on their
/// intent events (each stretch of A from one intent change to the next against B's stretch after the
/// same change, so a person pressing close or open later than the script does not misalign the rest)
/// and compared: per-unit estimate residuals, the grip, and the timing of controller phases after
/// each intent. docs/hardware.md, "Sim versus real".

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/plot.h"

namespace graspbed::testbed {

/// Per-unit residual of B's estimate against A's over the aligned overlap [N].
struct UnitResidual {
  int unit = 0;
  double fn_rms_n = 0.0;
  double fn_max_abs_n = 0.0;
  double ft_rms_n = 0.0;
  double ft_max_abs_n = 0.0;
};

/// One event (an intent change or a controller phase change) in A and its counterpart in B.
struct EventTiming {
  std::string kind;           ///< "intent" or "phase"
  std::string name;           ///< the intent or phase entered
  double a_s = 0.0;           ///< time in A [s]
  double b_s = 0.0;           ///< time in B on A's clock (B's time minus its stretch's shift) [s]
  double difference_s = 0.0;  ///< b_s - a_s [s]
};

/// An intent change both runs have, where a stretch of the alignment starts.
struct AlignmentAnchor {
  std::string intent;    ///< the intent entered, e.g. "close"
  double a_s = 0.0;      ///< its time in A [s]
  double b_s = 0.0;      ///< its time in B, B's own clock [s]
  double shift_s = 0.0;  ///< b_s - a_s: B's clock minus A's from here to the next anchor [s]
};

struct RunComparison {
  std::string run_a;
  std::string run_b;
  /// B's clock minus A's at the first anchor (the first intent change both share) [s]; 0 when
  /// they share none. A's time before the first anchor uses it too.
  double shift_s = 0.0;
  std::string aligned_on;  ///< the first anchor's intent, e.g. "close", or "start"
  /// The matched intent changes in order (A's and B's times both increasing), each starting a
  /// stretch with its own shift; empty when they share none (one stretch, shift 0).
  std::vector<AlignmentAnchor> anchors;
  double overlap_s = 0.0;  ///< length of the compared span on A's clock [s]
  size_t samples = 0;      ///< rows of A compared
  std::vector<UnitResidual> units;
  double fn_rms_n = 0.0;    ///< over all units and samples [N]
  double grip_rms_n = 0.0;  ///< est_total_fn_n, B - A [N]
  double grip_max_abs_n = 0.0;
  double peak_grip_a_n = 0.0;  ///< peak est_total_fn_n in the overlap [N]
  double peak_grip_b_n = 0.0;
  double effort_rms = 0.0;  ///< grip_effort, B - A [-]
  /// Intent events, then phase changes, matched in order. An intent event that is an anchor has
  /// difference 0 by construction; the anchors keep its shift.
  std::vector<EventTiming> events;
  int unmatched_events = 0;  ///< events of one run with no counterpart in the other
  /// Aligned series for the plot (A's time, A's and B's sensed total, B - A).
  std::vector<double> time_s, grip_a_n, grip_b_n;
};

/// Compares the runs in directories `run_a` and `run_b` (each with a signals.csv of any backend).
/// Throws common::ConfigError naming the file for a missing or malformed signals.csv, runs with
/// different unit counts, or runs that do not overlap once aligned.
RunComparison CompareRuns(const std::string& run_a, const std::string& run_b);

/// The comparison as JSON (the keys of RunComparison, without the plot series).
nlohmann::json ComparisonJson(const RunComparison& comparison);
/// A short table for the terminal.
std::string ComparisonTable(const RunComparison& comparison);
/// The figure of compare.png: the sensed grip of both runs on A's clock, their difference, and the
/// per-unit RMS residuals of Fn as one bar per unit (panel 2; bar k is c.units[k]).
plot::Figure ComparisonFigure(const RunComparison& comparison);
/// Writes ComparisonFigure(comparison) as a PNG at `path`.
void WriteComparisonPlot(const RunComparison& comparison, const std::string& path);

}  // namespace graspbed::testbed

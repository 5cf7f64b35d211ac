#include "testbed/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "common/plot.h"
#include "common/yaml_map.h"

namespace graspbed::testbed {
namespace {

using common::ConfigError;

/// A run's signals.csv: numeric columns by name, the text columns intent and phase.
struct RunSignals {
  std::string path;
  std::map<std::string, std::vector<double>> numeric;
  std::vector<std::string> intent;
  std::vector<std::string> phase;
  int units = 0;

  const std::vector<double>& Column(const std::string& name) const {
    const auto it = numeric.find(name);
    if (it == numeric.end()) throw ConfigError(path + ":1: no column " + name);
    return it->second;
  }
};

RunSignals ReadRunSignals(const std::string& dir) {
  RunSignals run;
  run.path = dir + "/signals.csv";
  std::ifstream in(run.path);
  if (!in) throw ConfigError(run.path + ": cannot read (is " + dir + " a run's output directory?)");
  std::string line;
  if (!std::getline(in, line)) throw ConfigError(run.path + ":1: empty file");
  std::vector<std::string> names;
  {
    std::stringstream header(line);
    for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  }
  if (names.empty() || names[0] != "time_s")
    throw ConfigError(run.path + ":1: expected a run's signals.csv (time_s first)");
  std::vector<std::vector<double>*> targets(names.size(), nullptr);
  for (size_t c = 0; c < names.size(); ++c) {
    // Text columns of a run's signals.csv (intent, controller phase, slip cues, a replay's recorded phase).
    const bool text = names[c] == "intent" || names[c] == "phase" || names[c] == "slip_cues" ||
                      names[c] == "recorded_phase";
    if (!text) targets[c] = &run.numeric[names[c]];
  }
  int line_number = 1;
  while (std::getline(in, line)) {
    ++line_number;
    std::vector<std::string> cells;
    std::stringstream split(line);
    for (std::string cell; std::getline(split, cell, ',');) cells.push_back(cell);
    if (cells.size() != names.size()) {
      throw ConfigError(run.path + ":" + std::to_string(line_number) + ": " + std::to_string(cells.size()) +
                        " cells, the header has " + std::to_string(names.size()));
    }
    for (size_t c = 0; c < names.size(); ++c) {
      if (names[c] == "intent") run.intent.push_back(cells[c]);
      if (names[c] == "phase") run.phase.push_back(cells[c]);
      if (targets[c] == nullptr) continue;
      char* end = nullptr;
      const double value = std::strtod(cells[c].c_str(), &end);
      if (end != cells[c].c_str() + cells[c].size() || cells[c].empty()) {
        throw ConfigError(run.path + ":" + std::to_string(line_number) + ": " + names[c] + " = '" + cells[c] +
                          "': expected a number");
      }
      targets[c]->push_back(value);
    }
  }
  if (run.Column("time_s").size() < 2)
    throw ConfigError(run.path + ": fewer than 2 rows: nothing to compare");
  while (run.numeric.count("fn_est_n_" + std::to_string(run.units)) > 0) ++run.units;
  return run;
}

struct Change {
  std::string name;
  double time_s = 0.0;
};

/// Where a text column changes value (the first row counts as a change into its value).
std::vector<Change> Changes(const std::vector<std::string>& text, const std::vector<double>& time) {
  std::vector<Change> changes;
  for (size_t i = 0; i < text.size(); ++i) {
    if (i == 0 || text[i] != text[i - 1]) changes.push_back({text[i], time[i]});
  }
  return changes;
}

/// Linear interpolation of (x, y) at `at` (x increasing); clamped at the ends.
double Interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  if (at <= x.front()) return y.front();
  if (at >= x.back()) return y.back();
  const size_t hi = static_cast<size_t>(std::upper_bound(x.begin(), x.end(), at) - x.begin());
  const size_t lo = hi - 1;
  const double span = x[hi] - x[lo];
  if (span <= 0.0) return y[hi];
  const double w = (at - x[lo]) / span;
  return y[lo] + w * (y[hi] - y[lo]);
}

/// B's clock minus A's at an instant of one run's clock (`anchor_time` picks which: &AlignmentAnchor::a_s
/// or ::b_s): the shift of the last anchor at or before it, the first anchor's before any; 0 without.
double ShiftAt(const std::vector<AlignmentAnchor>& anchors, double AlignmentAnchor::*anchor_time,
               double at_s) {
  if (anchors.empty()) return 0.0;
  double shift = anchors.front().shift_s;
  for (const AlignmentAnchor& anchor : anchors) {
    if (anchor.*anchor_time > at_s) break;
    shift = anchor.shift_s;
  }
  return shift;
}

/// B's time of an instant of A, and A's of an instant of B.
double BTimeOf(const std::vector<AlignmentAnchor>& anchors, double a_s) {
  return a_s + ShiftAt(anchors, &AlignmentAnchor::a_s, a_s);
}
double ATimeOf(const std::vector<AlignmentAnchor>& anchors, double b_s) {
  return b_s - ShiftAt(anchors, &AlignmentAnchor::b_s, b_s);
}

/// The k-th change into each intent in A against the k-th in B, kept where both clocks advance.
std::vector<AlignmentAnchor> Anchors(const std::vector<Change>& a, const std::vector<Change>& b) {
  std::map<std::string, std::vector<double>> b_times;
  for (size_t i = 1; i < b.size(); ++i) b_times[b[i].name].push_back(b[i].time_s);
  std::map<std::string, size_t> used;
  std::vector<AlignmentAnchor> anchors;
  for (size_t i = 1; i < a.size(); ++i) {
    const std::vector<double>& candidates = b_times[a[i].name];
    size_t& next = used[a[i].name];
    if (next >= candidates.size()) continue;
    const double b_s = candidates[next++];
    if (!anchors.empty() && b_s <= anchors.back().b_s) continue;  // out of order in B: no anchor
    anchors.push_back({a[i].name, a[i].time_s, b_s, b_s - a[i].time_s});
  }
  return anchors;
}

void MatchInOrder(const std::vector<Change>& a, const std::vector<Change>& b, const std::string& kind,
                  const std::vector<AlignmentAnchor>& anchors, RunComparison* out) {
  // Skip the initial state (row 0); match the k-th change into NAME in A with the k-th in B.
  std::map<std::string, std::vector<double>> b_times;
  for (size_t i = 1; i < b.size(); ++i) b_times[b[i].name].push_back(b[i].time_s);
  std::map<std::string, size_t> used;
  int a_count = 0;
  for (size_t i = 1; i < a.size(); ++i) {
    ++a_count;
    std::vector<double>& candidates = b_times[a[i].name];
    size_t& next = used[a[i].name];
    if (next >= candidates.size()) {
      ++out->unmatched_events;
      continue;
    }
    const double b_s = ATimeOf(anchors, candidates[next++]);
    out->events.push_back({kind, a[i].name, a[i].time_s, b_s, b_s - a[i].time_s});
  }
  int b_count = 0;
  for (size_t i = 1; i < b.size(); ++i) ++b_count;
  int matched = 0;
  for (const auto& [name, count] : used) matched += static_cast<int>(std::min(count, b_times[name].size()));
  out->unmatched_events += b_count - matched;
  (void)a_count;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

}  // namespace

RunComparison CompareRuns(const std::string& run_a, const std::string& run_b) {
  const RunSignals a = ReadRunSignals(run_a);
  const RunSignals b = ReadRunSignals(run_b);
  if (a.units != b.units) {
    throw ConfigError(run_b + "/signals.csv:1: " + std::to_string(b.units) + " units, but " + run_a +
                      " has " + std::to_string(a.units) + ": not the same sensor");
  }
  RunComparison out;
  out.run_a = run_a;
  out.run_b = run_b;
  const std::vector<double>& time_a = a.Column("time_s");
  const std::vector<double>& time_b = b.Column("time_s");
  const std::vector<Change> intents_a = Changes(a.intent, time_a);
  const std::vector<Change> intents_b = Changes(b.intent, time_b);
  // Align piecewise on the intent changes both runs have (normally close, then open, ...).
  out.anchors = Anchors(intents_a, intents_b);
  out.aligned_on = "start";
  if (!out.anchors.empty()) {
    out.shift_s = out.anchors.front().shift_s;
    out.aligned_on = out.anchors.front().intent;
  }
  MatchInOrder(intents_a, intents_b, "intent", out.anchors, &out);
  MatchInOrder(Changes(a.phase, time_a), Changes(b.phase, time_b), "phase", out.anchors, &out);

  const double begin_s = std::max(time_a.front(), ATimeOf(out.anchors, time_b.front()));
  const double end_s = std::min(time_a.back(), ATimeOf(out.anchors, time_b.back()));
  if (!(end_s > begin_s)) {
    throw ConfigError(run_b + ": does not overlap " + run_a + " once aligned on " + out.aligned_on +
                      " (shift " + Format("%.3f", out.shift_s) + " s)");
  }
  out.overlap_s = end_s - begin_s;
  const std::vector<double>& grip_a = a.Column("est_total_fn_n");
  const std::vector<double>& grip_b = b.Column("est_total_fn_n");
  const std::vector<double>& effort_a = a.Column("grip_effort");
  const std::vector<double>& effort_b = b.Column("grip_effort");
  out.units.resize(static_cast<size_t>(a.units));
  std::vector<double> fn_sq(out.units.size(), 0.0), ft_sq(out.units.size(), 0.0);
  double grip_sq = 0.0, effort_sq = 0.0;
  for (size_t i = 0; i < time_a.size(); ++i) {
    const double t = time_a[i];
    if (t < begin_s || t > end_s) continue;
    const double tb = BTimeOf(out.anchors, t);
    ++out.samples;
    const double gb = Interpolate(time_b, grip_b, tb);
    const double grip_diff = gb - grip_a[i];
    grip_sq += grip_diff * grip_diff;
    out.grip_max_abs_n = std::max(out.grip_max_abs_n, std::abs(grip_diff));
    out.peak_grip_a_n = std::max(out.peak_grip_a_n, grip_a[i]);
    out.peak_grip_b_n = std::max(out.peak_grip_b_n, gb);
    const double effort_diff = Interpolate(time_b, effort_b, tb) - effort_a[i];
    effort_sq += effort_diff * effort_diff;
    out.time_s.push_back(t);
    out.grip_a_n.push_back(grip_a[i]);
    out.grip_b_n.push_back(gb);
    for (size_t u = 0; u < out.units.size(); ++u) {
      const std::string k = std::to_string(u);
      // An invalid unit's estimate is not a reading: it counts as 0 N in both runs.
      const auto value = [&](const RunSignals& run, const std::string& column, size_t row) {
        return run.Column("validity_" + k)[row] == 0.0 ? run.Column(column + k)[row] : 0.0;
      };
      const auto value_b = [&](const std::string& column) {
        const double fn = Interpolate(time_b, b.Column(column + k), tb);
        const double validity = b.Column("validity_" + k)[std::min(
            static_cast<size_t>(std::lower_bound(time_b.begin(), time_b.end(), tb) - time_b.begin()),
            time_b.size() - 1)];
        return validity == 0.0 ? fn : 0.0;
      };
      const double fn_diff = value_b("fn_est_n_") - value(a, "fn_est_n_", i);
      const double ft_diff = value_b("ft_est_n_") - value(a, "ft_est_n_", i);
      UnitResidual& unit = out.units[u];
      unit.unit = static_cast<int>(u);
      fn_sq[u] += fn_diff * fn_diff;
      ft_sq[u] += ft_diff * ft_diff;
      unit.fn_max_abs_n = std::max(unit.fn_max_abs_n, std::abs(fn_diff));
      unit.ft_max_abs_n = std::max(unit.ft_max_abs_n, std::abs(ft_diff));
    }
  }
  const double n = static_cast<double>(std::max<size_t>(out.samples, 1));
  double all_fn_sq = 0.0;
  for (size_t u = 0; u < out.units.size(); ++u) {
    out.units[u].fn_rms_n = std::sqrt(fn_sq[u] / n);
    out.units[u].ft_rms_n = std::sqrt(ft_sq[u] / n);
    all_fn_sq += fn_sq[u];
  }
  out.fn_rms_n = std::sqrt(all_fn_sq / (n * static_cast<double>(std::max<size_t>(out.units.size(), 1))));
  out.grip_rms_n = std::sqrt(grip_sq / n);
  out.effort_rms = std::sqrt(effort_sq / n);
  return out;
}

nlohmann::json ComparisonJson(const RunComparison& c) {
  nlohmann::json units = nlohmann::json::array();
  for (const UnitResidual& u : c.units) {
    units.push_back({{"unit", u.unit},
                     {"fn_rms_n", u.fn_rms_n},
                     {"fn_max_abs_n", u.fn_max_abs_n},
                     {"ft_rms_n", u.ft_rms_n},
                     {"ft_max_abs_n", u.ft_max_abs_n}});
  }
  nlohmann::json events = nlohmann::json::array();
  for (const EventTiming& e : c.events) {
    events.push_back({{"kind", e.kind},
                      {"name", e.name},
                      {"a_s", e.a_s},
                      {"b_s", e.b_s},
                      {"difference_s", e.difference_s}});
  }
  nlohmann::json anchors = nlohmann::json::array();
  for (const AlignmentAnchor& anchor : c.anchors) {
    anchors.push_back(
        {{"intent", anchor.intent}, {"a_s", anchor.a_s}, {"b_s", anchor.b_s}, {"shift_s", anchor.shift_s}});
  }
  return {{"run_a", c.run_a},
          {"run_b", c.run_b},
          {"aligned_on", c.aligned_on},
          {"shift_s", c.shift_s},
          {"anchors", anchors},
          {"overlap_s", c.overlap_s},
          {"samples", c.samples},
          {"fn_rms_n", c.fn_rms_n},
          {"grip_rms_n", c.grip_rms_n},
          {"grip_max_abs_n", c.grip_max_abs_n},
          {"peak_grip_a_n", c.peak_grip_a_n},
          {"peak_grip_b_n", c.peak_grip_b_n},
          {"effort_rms", c.effort_rms},
          {"units", units},
          {"events", events},
          {"unmatched_events", c.unmatched_events}};
}

std::string ComparisonTable(const RunComparison& c) {
  std::ostringstream out;
  out << "compare " << c.run_a << " (A) with " << c.run_b << " (B), aligned on " << c.aligned_on
      << " (B - A shift " << Format("%.4f", c.shift_s) << " s), " << Format("%.2f", c.overlap_s)
      << " s overlap, " << c.samples << " samples\n";
  if (c.anchors.size() > 1) {
    out << "  aligned piecewise on " << c.anchors.size() << " intent changes, B - A shift:";
    for (const AlignmentAnchor& anchor : c.anchors) {
      out << " " << anchor.intent << " at " << Format("%.3f", anchor.a_s) << " s "
          << Format("%+.4f", anchor.shift_s) << " s;";
    }
    out << "\n";
  }
  out << "  sensed grip: peak A " << Format("%.3f", c.peak_grip_a_n) << " N, B "
      << Format("%.3f", c.peak_grip_b_n) << " N; B - A RMS " << Format("%.3g", c.grip_rms_n) << " N, max "
      << Format("%.3g", c.grip_max_abs_n) << " N; effort RMS " << Format("%.3g", c.effort_rms) << "\n";
  out << "  per-unit Fn residual RMS over all units " << Format("%.3g", c.fn_rms_n) << " N; largest:";
  std::vector<UnitResidual> sorted = c.units;
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& x, const auto& y) { return x.fn_rms_n > y.fn_rms_n; });
  for (size_t i = 0; i < std::min<size_t>(3, sorted.size()); ++i) {
    out << " unit " << sorted[i].unit << " " << Format("%.3g", sorted[i].fn_rms_n) << " N";
  }
  out << "\n";
  for (const EventTiming& e : c.events) {
    out << "  " << e.kind << " " << e.name << ": A " << Format("%.3f", e.a_s) << " s, B "
        << Format("%.3f", e.b_s) << " s (" << Format("%+.1f", 1e3 * e.difference_s) << " ms)\n";
  }
  if (c.unmatched_events > 0)
    out << "  " << c.unmatched_events << " events without a counterpart in the other run\n";
  return out.str();
}

plot::Figure ComparisonFigure(const RunComparison& c) {
  plot::Figure figure;
  // The run directories' own names: whole paths do not fit a title.
  const auto name = [](const std::string& dir) {
    const std::string stem = std::filesystem::path(dir).lexically_normal().filename().string();
    return stem.empty() ? std::filesystem::path(dir).lexically_normal().parent_path().filename().string()
                        : stem;
  };
  figure.title =
      "compare: A = " + name(c.run_a) + ", B = " + name(c.run_b) + " (aligned on " + c.aligned_on + ")";
  plot::Chart grip;
  grip.title = "Sensed grip (est_total_fn_n) on A's clock";
  grip.x_label = "time [s]";
  grip.y_label = "force [N]";
  plot::Series sa{"A", c.time_s, c.grip_a_n};
  plot::Series sb{"B", c.time_s, c.grip_b_n};
  sb.dashed = true;
  grip.series = {sa, sb};
  for (const EventTiming& e : c.events) {
    if (e.kind == "intent") grip.markers.push_back({e.a_s, e.name});
  }
  grip.include_zero_y = true;
  plot::Chart diff;
  diff.title = "B - A";
  diff.x_label = "time [s]";
  diff.y_label = "force [N]";
  plot::Series d{"B - A", c.time_s, {}};
  for (size_t i = 0; i < c.time_s.size(); ++i) d.y.push_back(c.grip_b_n[i] - c.grip_a_n[i]);
  diff.series = {d};
  diff.include_zero_y = true;
  // One bar per unit: units are categories, and a line from one to the next would join unrelated units.
  plot::Chart units;
  units.title = "Per-unit Fn residual (RMS)";
  units.x_label = "unit (numbers as in the layout picture)";
  units.y_label = "RMS [N]";
  units.bar_value_format = "%.2g";
  units.bar_colour = plot::PaletteColour(0);  // one colour: a colour per unit would repeat every eight
  for (const UnitResidual& u : c.units) units.bars.push_back({std::to_string(u.unit), u.fn_rms_n});
  figure.panels = {grip, diff, units};
  return figure;
}

void WriteComparisonPlot(const RunComparison& c, const std::string& path) {
  plot::WritePng(ComparisonFigure(c), path);
}

}  // namespace graspbed::testbed

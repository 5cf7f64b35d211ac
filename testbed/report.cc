#include "testbed/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/signal_log.h"
#include "testbed/sweep_columns.h"

namespace graspbed::testbed {

namespace fs = std::filesystem;
using nlohmann::json;

namespace internal {

std::string EscapeHtml(const std::string& text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&':
        escaped += "&amp;";
        break;
      case '<':
        escaped += "&lt;";
        break;
      case '>':
        escaped += "&gt;";
        break;
      case '"':
        escaped += "&quot;";
        break;
      case '\'':
        escaped += "&#39;";
        break;
      default:
        escaped += c;
    }
  }
  return escaped;
}

std::string Base64(const std::string& bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string encoded;
  encoded.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t left = bytes.size() - i;
    uint32_t group = static_cast<uint8_t>(bytes[i]) << 16;
    if (left > 1) group |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    if (left > 2) group |= static_cast<uint8_t>(bytes[i + 2]);
    encoded += kAlphabet[(group >> 18) & 63];
    encoded += kAlphabet[(group >> 12) & 63];
    encoded += left > 1 ? kAlphabet[(group >> 6) & 63] : '=';
    encoded += left > 2 ? kAlphabet[group & 63] : '=';
  }
  return encoded;
}

}  // namespace internal

const char* ReportKindName(ReportKind kind) {
  switch (kind) {
    case ReportKind::kScorecard:
      return "scorecard";
    case ReportKind::kSuite:
      return "suite";
    case ReportKind::kSweep:
      return "sweep";
  }
  return "?";
}

namespace {

using internal::EscapeHtml;

// ---- reading ---------------------------------------------------------------------------------------

std::string ReadFile(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw std::invalid_argument(path + ": cannot read");
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

json ParseJson(const std::string& path) {
  try {
    return json::parse(ReadFile(path));
  } catch (const json::parse_error& error) {
    throw std::invalid_argument(path + ": malformed JSON: " + error.what());
  }
}

// One object per line (results.jsonl); errors name the line.
std::vector<json> ParseJsonLines(const std::string& path) {
  std::istringstream lines(ReadFile(path));
  std::vector<json> rows;
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    if (line.empty()) continue;
    try {
      rows.push_back(json::parse(line));
    } catch (const json::parse_error& error) {
      throw std::invalid_argument(path + ":" + std::to_string(number) + ": malformed JSON: " + error.what());
    }
    if (!rows.back().is_object())
      throw std::invalid_argument(path + ":" + std::to_string(number) + ": not a JSON object");
  }
  return rows;
}

// ---- the page's model ------------------------------------------------------------------------------

// One column of the runs table. `numeric` cells sort by their number, the others by their text.
struct Column {
  std::string key;  // the fragment's sort=<key>
  std::string label;
  bool numeric = false;
  std::string title;  // the header's tooltip
};

// One cell: its HTML and, for a numeric column, the number it sorts by (none sorts last).
struct Cell {
  std::string html;
  std::optional<double> sort_value;
};

// One run: the values it filters by, and its cells in the order of the page's columns.
struct Row {
  std::string run;
  std::string scenario;
  std::string controller;
  std::string sensor;
  std::string verdict;                // passed, failed, error, interrupted, skipped
  std::string oracle;                 // found, none, not computed, n/a
  std::map<std::string, Cell> cells;  // by column key
};

struct Page {
  ReportKind kind = ReportKind::kSuite;
  std::string title;
  std::string source;        // the file the page was made from
  std::string summary_html;  // the kind's own totals
  std::vector<std::string> figures_html;
  std::vector<Column> columns;
  std::vector<Row> rows;
};

const std::vector<std::string>& Verdicts() {
  static const std::vector<std::string> verdicts = {"passed", "failed", "error", "interrupted", "skipped"};
  return verdicts;
}

std::string Format(double value, const char* format) {
  char text[64];
  std::snprintf(text, sizeof(text), format, value);
  return text;
}

// A metric of a summary or sweep row: "-" (and no sort value) when absent or null.
Cell NumberCell(const json& object, const char* key, const char* format) {
  const auto found = object.find(key);
  if (found == object.end() || !found->is_number()) return {"-", std::nullopt};
  const double value = found->get<double>();
  return {EscapeHtml(Format(value, format)), value};
}

Cell TextCell(const std::string& text) { return {EscapeHtml(text.empty() ? "-" : text), std::nullopt}; }

std::string StringOr(const json& object, const char* key, const std::string& fallback) {
  const auto found = object.find(key);
  return found != object.end() && found->is_string() ? found->get<std::string>() : fallback;
}

// The standard columns every kind fills (a sweep adds its swept keys before "pictures").
std::vector<Column> RunColumns() {
  return {
      {"run", "run", false, "the run's name (a scorecard's <scenario>.v<k>, a sweep's index)"},
      {"scenario", "scenario", false, ""},
      {"controller", "controller", false, ""},
      {"sensor", "sensor", false, "sensor profile / sensitivities"},
      {"verdict", "verdict", false,
       "passed, failed (an expectation), error (the run threw), interrupted, skipped (not started)"},
      {"first_failure", "first failed expectation", false, "what the run got against the limit it missed"},
      {"oracle", "oracle grip", true, "the lightest constant grip that holds, or why there is none"},
      {"peak_grip_n", "peak grip [N]", true, ""},
      {"grip_efficiency", "grip efficiency", true, "mean grip held / oracle grip"},
      {"max_slip_mm", "max slip [mm]", true, ""},
      {"gross", "gross slips flagged", true, "gross slip events flagged / all"},
      {"false_slip_per_min", "false flags [1/min]", true, ""},
      {"wall_s", "wall [s]", true, ""},
  };
}

// The verdict and its first reason from a summary.json (or an entry that only has an error).
void FillVerdict(const json& entry, Row& row) {
  const std::string error = StringOr(entry, "error", "");
  const json expectations = entry.value("expectations", json::array());
  std::string reason;
  if (!error.empty()) {
    row.verdict = error == "not run (interrupted)" ? "skipped" : "error";
    reason = error;
  } else if (!entry.value("completed", false)) {
    row.verdict = "interrupted";
    reason = "interrupted before the end of its script";
  } else if (entry.value("passed", false)) {
    row.verdict = "passed";
  } else {
    row.verdict = "failed";
    for (const json& outcome : expectations) {
      if (outcome.value("passed", true)) continue;
      reason = outcome.value("name", std::string("?")) + ": got " +
               outcome.value("value_text", std::string("?")) + ", limit " +
               outcome.value("limit", std::string("?"));
      const std::string note = outcome.value("note", std::string());
      if (!note.empty()) reason += " (" + note + ")";
      break;
    }
  }
  row.cells["verdict"] = {
      "<span class=\"verdict " + EscapeHtml(row.verdict) + "\">" + EscapeHtml(row.verdict) + "</span>",
      std::nullopt};
  row.cells["first_failure"] = TextCell(reason);
}

// The oracle grip, or why there is none (metrics.oracle_grip_n, metrics.oracle_note).
void FillOracle(const json& metrics, Row& row) {
  const auto grip = metrics.find("oracle_grip_n");
  if (grip != metrics.end() && grip->is_number()) {
    row.oracle = "found";
    row.cells["oracle"] = NumberCell(metrics, "oracle_grip_n", "%.2f N");
    return;
  }
  const std::string note = StringOr(metrics, "oracle_note", "");
  if (note.empty()) {
    row.oracle = "n/a";
    row.cells["oracle"] = TextCell("");
    return;
  }
  row.oracle = note.rfind("not computed", 0) == 0 ? "not computed" : "none";
  row.cells["oracle"] = {
      "<span class=\"no-oracle\">" + EscapeHtml(row.oracle == "none" ? "none: " + note : note) + "</span>",
      std::nullopt};
}

void FillMetrics(const json& metrics, Row& row) {
  row.cells["peak_grip_n"] = NumberCell(metrics, "peak_grip_n", "%.2f");
  row.cells["grip_efficiency"] = NumberCell(metrics, "grip_efficiency", "%.2f");
  row.cells["max_slip_mm"] = NumberCell(metrics, "max_slip_mm", "%.2f");
  row.cells["false_slip_per_min"] = NumberCell(metrics, "false_slip_per_min", "%.1f");
  row.cells["wall_s"] = NumberCell(metrics, "wall_s", "%.2f");
  const auto events = metrics.find("gross_slip_events");
  if (events != metrics.end() && events->is_number()) {
    const int all = events->get<int>();
    const int flagged = metrics.value("gross_slip_detected", 0);
    row.cells["gross"] = {std::to_string(flagged) + "/" + std::to_string(all),
                          all > 0 ? std::optional<double>(static_cast<double>(flagged) / all) : std::nullopt};
  }
}

// Path of `target` as the page links it: relative to the page's folder when it can be.
std::string LinkTo(const fs::path& target, const fs::path& page_dir) {
  std::error_code error;
  const fs::path relative = fs::relative(target, page_dir, error);
  return (error || relative.empty() ? fs::absolute(target) : relative).generic_string();
}

// The folder a run wrote and the pictures in it, by file stem ("-" when it wrote none).
Cell PicturesCell(const fs::path& run_dir, const fs::path& page_dir) {
  std::error_code error;
  if (!fs::is_directory(run_dir, error)) return TextCell("");
  std::vector<fs::path> pictures;
  for (const auto& entry : fs::directory_iterator(run_dir, error)) {
    if (entry.path().extension() == ".png" || entry.path().extension() == ".mp4")
      pictures.push_back(entry.path());
  }
  std::sort(pictures.begin(), pictures.end());
  std::string html = "<a href=\"" + EscapeHtml(LinkTo(run_dir, page_dir)) + "/\">folder</a>";
  for (const fs::path& picture : pictures) {
    html += " <a href=\"" + EscapeHtml(LinkTo(picture, page_dir)) + "\">" +
            EscapeHtml(picture.stem().string()) + "</a>";
  }
  return {"<span class=\"pictures\">" + html + "</span>", static_cast<double>(pictures.size())};
}

// A row of a suite.json or scorecard.json entry: its summary (or its error alone).
Row RunRow(const std::string& run, const std::string& scenario, const json& entry, const json& summary) {
  Row row;
  row.run = run;
  row.scenario = scenario;
  row.controller = StringOr(summary, "controller", StringOr(entry, "controller", "-"));
  row.sensor = StringOr(summary, "sensor", "-");
  row.cells["run"] = TextCell(run);
  row.cells["scenario"] = TextCell(scenario);
  row.cells["controller"] = TextCell(row.controller);
  row.cells["sensor"] = TextCell(row.sensor);
  // A run that threw has its error alone, and no summary.
  FillVerdict(summary.is_object() ? summary : entry, row);
  const json metrics = summary.is_object() ? summary.value("metrics", json::object()) : json::object();
  FillOracle(metrics, row);
  FillMetrics(metrics, row);
  return row;
}

// ---- figures ---------------------------------------------------------------------------------------

struct Bar {
  std::string label;
  double value = 0.0;
  std::optional<double> marker;  // a tick across the bar (e.g. the oracle grip)
  std::string css_class;         // the bar's colour: a verdict
};

// Horizontal bars as inline SVG, one line per bar, with its value printed after it.
std::string BarChart(const std::string& title, const std::string& unit, const std::vector<Bar>& bars,
                     const std::string& marker_name) {
  constexpr double kLabelWidth = 160.0, kPlotWidth = 270.0, kLineHeight = 18.0, kTop = 8.0;
  double top = 0.0;
  for (const Bar& bar : bars) top = std::max({top, bar.value, bar.marker.value_or(0.0)});
  if (top <= 0.0) top = 1.0;
  const double height = kTop + kLineHeight * static_cast<double>(bars.size()) + 24.0;
  std::ostringstream svg;
  svg << "<figure class=\"chart\"><svg xmlns=\"http://www.w3.org/2000/svg\" width=\""
      << kLabelWidth + kPlotWidth + 70 << "\" height=\"" << height << "\" role=\"img\" aria-label=\""
      << EscapeHtml(title) << "\">";
  for (size_t i = 0; i < bars.size(); ++i) {
    const Bar& bar = bars[i];
    const double y = kTop + kLineHeight * static_cast<double>(i);
    const double width = kPlotWidth * std::max(0.0, bar.value) / top;
    svg << "<text x=\"" << kLabelWidth - 6 << "\" y=\"" << y + 12 << "\" text-anchor=\"end\">"
        << EscapeHtml(bar.label) << "</text>";
    svg << "<rect class=\"" << EscapeHtml(bar.css_class) << "\" x=\"" << kLabelWidth << "\" y=\"" << y + 2
        << "\" width=\"" << width << "\" height=\"" << kLineHeight - 5 << "\"/>";
    svg << "<text x=\"" << kLabelWidth + width + 4 << "\" y=\"" << y + 12 << "\">"
        << Format(bar.value, "%.3g") << "</text>";
    if (bar.marker) {
      const double x = kLabelWidth + kPlotWidth * *bar.marker / top;
      svg << "<line class=\"marker\" x1=\"" << x << "\" x2=\"" << x << "\" y1=\"" << y << "\" y2=\""
          << y + kLineHeight - 1 << "\"/>";
    }
  }
  const double axis_y = kTop + kLineHeight * static_cast<double>(bars.size()) + 4;
  svg << "<line class=\"axis\" x1=\"" << kLabelWidth << "\" x2=\"" << kLabelWidth + kPlotWidth << "\" y1=\""
      << axis_y << "\" y2=\"" << axis_y << "\"/><text x=\"" << kLabelWidth << "\" y=\"" << axis_y + 14
      << "\">0</text><text x=\"" << kLabelWidth + kPlotWidth << "\" y=\"" << axis_y + 14
      << "\" text-anchor=\"end\">" << Format(top, "%.3g") << " " << EscapeHtml(unit) << "</text></svg>";
  svg << "<figcaption>" << EscapeHtml(title);
  if (!marker_name.empty()) svg << "; the black tick: " << EscapeHtml(marker_name);
  svg << "; colour: the run's verdict</figcaption></figure>";
  return svg.str();
}

// Runs per controller and verdict, as one bar per (controller, verdict) that has runs.
std::string VerdictChart(const Page& page) {
  std::map<std::string, std::map<std::string, int>> counts;
  for (const Row& row : page.rows) ++counts[row.controller][row.verdict];
  std::vector<Bar> bars;
  for (const auto& [controller, by_verdict] : counts) {
    for (const std::string& verdict : Verdicts()) {
      const auto found = by_verdict.find(verdict);
      if (found != by_verdict.end())
        bars.push_back(
            {controller + " " + verdict, static_cast<double>(found->second), std::nullopt, verdict});
    }
  }
  return BarChart("runs per controller and verdict", "runs", bars, "");
}

// Per run: peak grip against the oracle grip, and the largest slip (a page of at most kMaxBars runs).
void AddPerRunCharts(Page& page) {
  constexpr size_t kMaxBars = 60;  // beyond this a per-run bar chart is a wall of bars: the table sorts
  if (page.rows.empty() || page.rows.size() > kMaxBars) return;
  std::vector<Bar> grip, slip;
  for (const Row& row : page.rows) {
    const std::string& label = row.run;
    const std::optional<double> peak = row.cells.at("peak_grip_n").sort_value;
    const auto oracle = row.cells.find("oracle");
    const std::optional<double> oracle_n =
        oracle != row.cells.end() ? oracle->second.sort_value : std::nullopt;
    if (peak) grip.push_back({label, *peak, oracle_n, row.verdict});
    const std::optional<double> slip_mm = row.cells.at("max_slip_mm").sort_value;
    if (slip_mm) slip.push_back({label, *slip_mm, std::nullopt, row.verdict});
  }
  if (!grip.empty()) page.figures_html.push_back(BarChart("peak grip per run", "N", grip, "its oracle grip"));
  if (!slip.empty()) page.figures_html.push_back(BarChart("largest slip per run", "mm", slip, ""));
}

std::string PngFigure(const std::string& path, const std::string& caption) {
  return "<figure class=\"png\"><img alt=\"" + EscapeHtml(caption) + "\" src=\"data:image/png;base64," +
         internal::Base64(ReadFile(path)) + "\"><figcaption>" + EscapeHtml(caption) +
         "</figcaption></figure>";
}

// ---- the three kinds -------------------------------------------------------------------------------

std::string KeyValueTable(const std::vector<std::pair<std::string, std::string>>& pairs) {
  std::string html = "<table class=\"totals\">";
  for (const auto& [key, value] : pairs)
    html += "<tr><th>" + EscapeHtml(key) + "</th><td>" + EscapeHtml(value) + "</td></tr>";
  return html + "</table>";
}

std::string JsonText(const json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_number_float()) return Format(value.get<double>(), "%.4g");
  return value.dump();
}

Page ScorecardPage(const std::string& dir, const ReportOptions& options, const fs::path& page_dir) {
  const std::string file = dir + "/scorecard.json";
  const json scorecard = ParseJson(file);
  Page page;
  page.kind = ReportKind::kScorecard;
  page.source = file;
  const json& set = scorecard.at("set");
  page.title =
      "scorecard " + set.value("name", std::string("?")) + " v" + JsonText(set.value("version", json(0)));
  page.summary_html =
      KeyValueTable({{"set file", JsonText(set.value("file", json("?")))},
                     {"seed", JsonText(set.value("seed", json(nullptr)))},
                     {"runs per controller", JsonText(set.value("runs_per_controller", json(0)))},
                     {"completed", scorecard.value("completed", false) ? "yes" : "NO (interrupted)"},
                     {"wall", Format(scorecard.value("wall_s", 0.0), "%.1f s")},
                     {"jobs", JsonText(scorecard.value("jobs", json(1)))}});
  // The controllers' pooled figures, one column per controller, as scorecard.csv has them.
  const json& controllers = scorecard.at("controllers");
  if (!controllers.empty()) {
    std::string html = "<table class=\"figures\"><thead><tr><th>figure</th>";
    for (const json& controller : controllers)
      html += "<th>" + EscapeHtml(controller.value("controller", std::string("?"))) + "</th>";
    html += "</tr></thead><tbody>";
    for (const auto& [key, ignored] : controllers.front().items()) {
      if (key == "controller" || key == "by_sensor" || key == "false_flags_by_cue") continue;
      html += "<tr><th>" + EscapeHtml(key) + "</th>";
      for (const json& controller : controllers) {
        const json value = controller.value(key, json(nullptr));
        html += "<td>" + EscapeHtml(value.is_null() ? "-" : JsonText(value)) + "</td>";
      }
      html += "</tr>";
    }
    page.summary_html += html + "</tbody></table>";
  }
  if (fs::exists(dir + "/scorecard.png"))
    page.figures_html.push_back(
        PngFigure(dir + "/scorecard.png", "scorecard.png: the headline figures per controller"));
  page.columns = RunColumns();
  page.columns.push_back({"pictures", "outputs", false, "the run's folder and pictures (score --runs-out)"});
  for (const json& entry : scorecard.at("runs")) {
    const std::string run = entry.at("run").get<std::string>();
    // A run <base>.v<k> counts for its base scenario, as the scorecard's by-scenario table does.
    const size_t dot = run.rfind(".v");
    Row row = RunRow(run, dot == std::string::npos ? run : run.substr(0, dot), entry,
                     entry.value("summary", json(nullptr)));
    if (row.sensor == "-") {
      const json overrides = entry.value("overrides", json::object());
      row.sensor = StringOr(overrides, "sensor.profile", "-");
      row.cells["sensor"] = TextCell(row.sensor);
    }
    row.cells["pictures"] =
        options.runs_dir.empty()
            ? TextCell("")
            : PicturesCell(fs::path(options.runs_dir) / (run + "@" + row.controller), page_dir);
    page.rows.push_back(std::move(row));
  }
  return page;
}

Page SuitePage(const std::string& dir, const fs::path& page_dir) {
  const std::string file = dir + "/suite.json";
  const json suite = ParseJson(file);
  Page page;
  page.kind = ReportKind::kSuite;
  page.source = file;
  page.title = "suite " + dir;
  page.summary_html =
      KeyValueTable({{"scenarios", JsonText(suite.value("scenarios", json(0)))},
                     {"passed", JsonText(suite.value("passed_count", json(0)))},
                     {"failed", JsonText(suite.value("failed_count", json(0)))},
                     {"completed", suite.value("completed", false) ? "yes" : "NO (interrupted)"},
                     {"wall", Format(suite.value("wall_s", 0.0), "%.1f s")},
                     {"jobs", JsonText(suite.value("jobs", json(1)))}});
  page.columns = RunColumns();
  page.columns.erase(page.columns.begin());  // a suite's run is its scenario
  page.columns.push_back({"pictures", "outputs", false, "the scenario's folder and its plots"});
  for (const json& entry : suite.at("runs")) {
    const std::string scenario = entry.at("scenario").get<std::string>();
    const bool has_summary = entry.contains("metrics") || entry.contains("expectations");
    Row row = RunRow(scenario, scenario, entry, has_summary ? entry : json(nullptr));
    row.cells["pictures"] = PicturesCell(fs::path(dir) / scenario, page_dir);
    page.rows.push_back(std::move(row));
  }
  AddPerRunCharts(page);
  return page;
}

Page SweepPage(const std::string& dir) {
  const std::string file = dir + "/results.jsonl";
  const std::vector<json> results = ParseJsonLines(file);
  Page page;
  page.kind = ReportKind::kSweep;
  page.source = file;
  json manifest = json::object();
  if (fs::exists(dir + "/manifest.json")) manifest = ParseJson(dir + "/manifest.json");
  page.title = "sweep " + fs::path(StringOr(manifest, "spec", dir)).filename().string();
  page.summary_html = KeyValueTable(
      {{"spec", StringOr(manifest, "spec", "-")},
       {"scenario", StringOr(manifest, "scenario", "-")},
       {"runs", std::to_string(results.size()) + " of " + JsonText(manifest.value("total_runs", json("?")))},
       {"shard", StringOr(manifest, "shard", "-")},
       {"completed", manifest.value("completed", false) ? "yes" : "no"}});
  // Swept keys: every column of a row that is not one of the sweep's own (docs/scenarios.md, "Sweeps").
  static const std::set<std::string> kOwn = [] {
    std::set<std::string> own(kSweepMetricColumns.begin(), kSweepMetricColumns.end());
    own.insert(kSweepRowColumns.begin(), kSweepRowColumns.end());
    own.insert(kSweepErrorKey);
    return own;
  }();
  std::vector<std::string> swept;
  if (!results.empty()) {
    for (const auto& [key, value] : results.front().items())
      if (!kOwn.count(key)) swept.push_back(key);
  }
  page.columns = RunColumns();
  for (const std::string& key : swept) page.columns.push_back({key, key, true, "swept"});
  for (const json& result : results) {
    Row row;
    const std::string run = "run " + JsonText(result.value("run", json("?")));
    row.run = run;
    row.scenario = StringOr(result, "scenario", "-");
    row.controller =
        result.contains("controller.name") ? JsonText(result["controller.name"]) : "(scenario's)";
    row.sensor = result.contains("sensor.profile") ? JsonText(result["sensor.profile"]) : "(scenario's)";
    row.cells["run"] = {EscapeHtml(run), result.value("run", 0.0)};
    row.cells["scenario"] = TextCell(row.scenario);
    row.cells["controller"] = TextCell(row.controller);
    row.cells["sensor"] = TextCell(row.sensor);
    json verdict = {{"completed", result.value("completed", false)},
                    {"passed", result.value("passed", false)}};
    if (result.contains("error")) verdict["error"] = result["error"];
    FillVerdict(verdict, row);
    // A sweep's rows keep the failed expectations' names only.
    const std::string failed = StringOr(result, "failed_expectations", "");
    if (row.verdict == "failed" && !failed.empty())
      row.cells["first_failure"] = TextCell(failed + " (names only: the sweep keeps no values)");
    row.oracle = "n/a";
    row.cells["oracle"] = TextCell("not in a sweep's rows");
    FillMetrics(result, row);
    for (const std::string& key : swept) {
      const json value = result.value(key, json(nullptr));
      row.cells[key] = {EscapeHtml(JsonText(value)),
                        value.is_number() ? std::optional<double>(value.get<double>()) : std::nullopt};
    }
    page.rows.push_back(std::move(row));
  }
  AddPerRunCharts(page);
  return page;
}

// ---- the page --------------------------------------------------------------------------------------

// Per controller: runs, and of them passed, failed, errored and without an oracle grip, each count a
// link to the rows it counts (the fragment the runs table reads).
std::string ControllerCounts(const Page& page) {
  struct Counts {
    int runs = 0, passed = 0, failed = 0, errors = 0, no_oracle = 0;
  };
  std::map<std::string, Counts> by_controller;
  for (const Row& row : page.rows) {
    Counts& counts = by_controller[row.controller];
    ++counts.runs;
    if (row.verdict == "passed") ++counts.passed;
    if (row.verdict == "failed") ++counts.failed;
    if (row.verdict == "error" || row.verdict == "interrupted" || row.verdict == "skipped") ++counts.errors;
    if (row.oracle == "none") ++counts.no_oracle;
  }
  const auto link = [](const std::string& controller, const std::string& filter, int count) {
    if (count == 0) return std::string("0");
    return "<a href=\"#controller=" + EscapeHtml(controller) + "&amp;" + filter + "\">" +
           std::to_string(count) + "</a>";
  };
  std::string html =
      "<table class=\"counts\"><thead><tr><th>controller</th><th>runs</th><th>passed</th><th>failed</th>"
      "<th>errors, interrupted</th><th>no oracle grip</th></tr></thead><tbody>";
  for (const auto& [controller, counts] : by_controller) {
    html += "<tr><th>" + EscapeHtml(controller) + "</th><td>" + link(controller, "", counts.runs) +
            "</td><td>" + link(controller, "verdict=passed", counts.passed) + "</td><td>" +
            link(controller, "verdict=failed", counts.failed) + "</td><td>" + std::to_string(counts.errors) +
            "</td><td>" + link(controller, "oracle=none", counts.no_oracle) + "</td></tr>";
  }
  return html + "</tbody></table>";
}

std::string FilterSelect(const std::string& dimension, const std::set<std::string>& values) {
  std::string html = "<label>" + EscapeHtml(dimension) + " <select id=\"filter-" + dimension +
                     "\" data-dim=\"" + dimension + "\"><option value=\"\">all</option>";
  for (const std::string& value : values)
    html += "<option value=\"" + EscapeHtml(value) + "\">" + EscapeHtml(value) + "</option>";
  return html + "</select></label>";
}

std::string RunsTable(const Page& page) {
  std::map<std::string, std::set<std::string>> values;
  for (const Row& row : page.rows) {
    values["scenario"].insert(row.scenario);
    values["controller"].insert(row.controller);
    values["sensor"].insert(row.sensor);
    values["oracle"].insert(row.oracle);
  }
  // Every verdict is offered, so that #verdict=failed hides every row of a page with no failure.
  values["verdict"] = {Verdicts().begin(), Verdicts().end()};
  std::string html = "<form id=\"filters\" onsubmit=\"return false\">";
  for (const char* dimension : {"scenario", "controller", "sensor", "verdict", "oracle"})
    html += FilterSelect(dimension, values[dimension]);
  html +=
      "<label>text <input id=\"filter-text\" type=\"search\" placeholder=\"any cell\"></label>"
      "<button type=\"button\" id=\"filter-clear\">clear</button></form>"
      "<p id=\"shown\">" +
      std::to_string(page.rows.size()) + " runs</p>";
  html += "<div id=\"runs-wrap\"><table id=\"runs\"><thead><tr>";
  for (const Column& column : page.columns) {
    html += "<th data-key=\"" + EscapeHtml(column.key) + "\"" +
            (column.numeric ? " data-numeric" : std::string()) +
            (column.title.empty() ? std::string() : " title=\"" + EscapeHtml(column.title) + "\"") + ">" +
            EscapeHtml(column.label) + "</th>";
  }
  html += "</tr></thead><tbody>";
  for (const Row& row : page.rows) {
    html += "<tr class=\"run " + EscapeHtml(row.verdict) + "\" data-scenario=\"" + EscapeHtml(row.scenario) +
            "\" data-controller=\"" + EscapeHtml(row.controller) + "\" data-sensor=\"" +
            EscapeHtml(row.sensor) + "\" data-verdict=\"" + EscapeHtml(row.verdict) + "\" data-oracle=\"" +
            EscapeHtml(row.oracle) + "\">";
    for (const Column& column : page.columns) {
      const auto found = row.cells.find(column.key);
      const Cell cell = found != row.cells.end() ? found->second : Cell{"-", std::nullopt};
      html += std::string(column.numeric ? "<td class=\"n\"" : "<td");
      if (cell.sort_value && std::isfinite(*cell.sort_value))
        html += " data-v=\"" + Format(*cell.sort_value, "%.17g") + "\"";
      html += ">";
      html += cell.html + "</td>";
    }
    html += "</tr>";
  }
  return html + "</tbody></table></div>";
}

constexpr const char* kStyle = R"css(
body{font:14px/1.4 system-ui,sans-serif;margin:1.5em;color:#222}
h1{font-size:1.4em;margin:0 0 .2em}#summary{display:flex;flex-wrap:wrap;gap:0 3em}h2{font-size:1.15em;margin:1.4em 0 .4em}
.meta{color:#666;margin:0}
table{border-collapse:collapse}th,td{padding:2px 8px;border-bottom:1px solid #ddd;text-align:left;vertical-align:top}
table.totals th,table.figures tbody th,table.counts tbody th{font-weight:normal;color:#555}
table.figures td,table.counts td{text-align:right}
#runs thead th{position:sticky;top:0;background:#f4f4f4;cursor:pointer;user-select:none;white-space:nowrap}
#runs th[aria-sort=ascending]::after{content:" \25B2"}#runs th[aria-sort=descending]::after{content:" \25BC"}
#runs td.n{text-align:right;font-variant-numeric:tabular-nums}
#runs tr.run:hover{background:#f8f8ff}
.verdict{font-weight:600}.verdict.passed{color:#1a7f37}.verdict.failed{color:#c62828}
.verdict.error,.verdict.interrupted,.verdict.skipped{color:#8a5a00}
.no-oracle{color:#8a5a00}
.pictures{display:block;min-width:16em;max-width:26em}.pictures a{margin-right:.4em}
#runs td{max-width:24em}#runs-wrap{overflow-x:auto}
#filters{display:flex;flex-wrap:wrap;gap:.4em 1em;margin:.4em 0}
#shown{color:#555;margin:.2em 0 .6em}
figure{display:inline-block;margin:0 1.5em 1em 0;vertical-align:top}
figure img{max-width:100%;border:1px solid #ddd}figcaption{color:#555;font-size:.9em;max-width:500px}
svg text{font:11px system-ui,sans-serif;fill:#333}
svg rect{fill:#999}svg rect.passed{fill:#4caf50}svg rect.failed{fill:#e53935}svg rect.error{fill:#f9a825}
svg line.marker{stroke:#000;stroke-width:2}svg line.axis{stroke:#888}
)css";

// Filters (from the form and the URL fragment) and sorting (by a header click or the fragment).
constexpr const char* kScript = R"js(
(function () {
  const table = document.getElementById('runs');
  const body = table.tBodies[0];
  const rows = Array.from(body.rows);
  const headers = Array.from(table.tHead.rows[0].cells);
  const selects = Array.from(document.querySelectorAll('#filters select'));
  const text = document.getElementById('filter-text');
  let sortKey = '', descending = false;

  function readFragment() {
    const params = new URLSearchParams(location.hash.slice(1));
    for (const select of selects) {
      const value = params.get(select.dataset.dim) || '';
      // A value no row has still filters (and then hides every row).
      if (value && !Array.from(select.options).some(o => o.value === value)) select.add(new Option(value, value));
      select.value = value;
    }
    text.value = params.get('q') || '';
    sortKey = params.get('sort') || '';
    descending = params.get('order') === 'desc';
  }
  function writeFragment() {
    const params = new URLSearchParams();
    for (const select of selects) if (select.value) params.set(select.dataset.dim, select.value);
    if (text.value) params.set('q', text.value);
    if (sortKey) { params.set('sort', sortKey); if (descending) params.set('order', 'desc'); }
    const fragment = params.toString();
    history.replaceState(null, '', fragment ? '#' + fragment : location.pathname + location.search);
  }
  function filter() {
    const query = text.value.toLowerCase();
    let shown = 0;
    for (const row of rows) {
      const keep = selects.every(s => !s.value || row.dataset[s.dataset.dim] === s.value) &&
                   (!query || row.textContent.toLowerCase().includes(query));
      row.hidden = !keep;
      if (keep) ++shown;
    }
    document.getElementById('shown').textContent = shown + ' of ' + rows.length + ' runs shown';
  }
  function sort() {
    const index = headers.findIndex(h => h.dataset.key === sortKey);
    headers.forEach(h => h.removeAttribute('aria-sort'));
    if (index < 0) return;
    const numeric = headers[index].hasAttribute('data-numeric');
    const key = row => {
      const cell = row.cells[index];
      if (!numeric) return cell.textContent;
      return cell.dataset.v === undefined ? null : parseFloat(cell.dataset.v);
    };
    const sign = descending ? -1 : 1;
    const ordered = rows.slice().sort((a, b) => {
      const x = key(a), y = key(b);
      if (x === null || y === null) return (x === null) - (y === null);  // no value: last either way
      return sign * (numeric ? x - y : x.localeCompare(y, undefined, {numeric: true}));
    });
    for (const row of ordered) body.appendChild(row);
    headers[index].setAttribute('aria-sort', descending ? 'descending' : 'ascending');
  }
  function update() { filter(); sort(); writeFragment(); }

  for (const select of selects) select.addEventListener('change', update);
  text.addEventListener('input', update);
  document.getElementById('filter-clear').addEventListener('click', () => {
    for (const select of selects) select.value = '';
    text.value = '';
    update();
  });
  for (const header of headers) {
    header.addEventListener('click', () => {
      descending = sortKey === header.dataset.key ? !descending : false;
      sortKey = header.dataset.key;
      update();
    });
  }
  window.addEventListener('hashchange', () => { readFragment(); filter(); sort(); });
  readFragment();
  filter();
  sort();
  // For tests and measurements: when the page had its rows filtered and sorted [ms after navigation].
  document.documentElement.dataset.readyMs = Math.round(performance.now());
})();
)js";

std::string PageHtml(const Page& page) {
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
       << "<meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">"
       << "<title>graspbed report: " << EscapeHtml(page.title) << "</title><style>" << kStyle
       << "</style></head>\n"
       << "<body data-kind=\"" << ReportKindName(page.kind)
       << "\"><header><h1>graspbed report: " << EscapeHtml(page.title)
       << "</h1><p class=\"meta\">made by <code>graspbed report</code> from " << EscapeHtml(page.source)
       << "</p></header>\n";
  html << "<section id=\"summary\"><div><h2>Summary</h2>" << page.summary_html
       << "</div><div><h2>Runs per controller</h2>" << ControllerCounts(page) << "</div></section>\n";
  html << "<section id=\"figures\"><h2>Comparison figures</h2>" << VerdictChart(page);
  for (const std::string& figure : page.figures_html) html << figure;
  html << "</section>\n<section id=\"runs-section\"><h2>Runs</h2>" << RunsTable(page) << "</section>\n";
  html << "<script>" << kScript << "</script></body></html>\n";
  return html.str();
}

fs::path PagePath(const std::string& dir, const ReportOptions& options) {
  return options.out_path.empty() ? fs::path(dir) / "report.html" : fs::path(options.out_path);
}

// The page's model from whichever output `dir` holds.
Page LoadPage(const std::string& dir, const ReportOptions& options) {
  std::error_code error;
  if (!fs::is_directory(dir, error))
    throw std::invalid_argument(dir +
                                ": no such directory (expected the output directory of graspbed suite, "
                                "score or sweep)");
  const fs::path page_dir = fs::absolute(PagePath(dir, options)).parent_path();
  std::string source;
  try {
    if (fs::exists(fs::path(dir) / "scorecard.json")) {
      source = dir + "/scorecard.json";
      return ScorecardPage(dir, options, page_dir);
    }
    if (fs::exists(fs::path(dir) / "suite.json")) {
      source = dir + "/suite.json";
      return SuitePage(dir, page_dir);
    }
    if (fs::exists(fs::path(dir) / "results.jsonl")) {
      source = dir + "/results.jsonl";
      return SweepPage(dir);
    }
  } catch (const json::exception& json_error) {
    // Valid JSON of another shape: a key missing or of the wrong type.
    throw std::invalid_argument(source + ": not what graspbed writes there: " + json_error.what());
  }
  throw std::invalid_argument(dir +
                              ": holds no scorecard.json, suite.json or results.jsonl (the outputs of "
                              "graspbed score, suite and sweep)");
}

}  // namespace

std::string ReportHtml(const std::string& dir, const ReportOptions& options) {
  return PageHtml(LoadPage(dir, options));
}

ReportWritten WriteReport(const std::string& dir, const ReportOptions& options) {
  const Page page = LoadPage(dir, options);
  const std::string html = PageHtml(page);
  ReportWritten written;
  written.path = PagePath(dir, options).string();
  written.kind = page.kind;
  written.runs = static_cast<int>(page.rows.size());
  written.bytes = html.size();
  common::WriteFileAtomic(written.path, html);
  return written;
}

std::string DescribeReport(const ReportWritten& written) {
  char size[32];
  std::snprintf(size, sizeof(size), written.bytes >= 1000000 ? "%.1f MB" : "%.0f kB",
                written.bytes >= 1000000 ? written.bytes / 1e6 : written.bytes / 1e3);
  return "report: " + written.path + " (" + ReportKindName(written.kind) + ", " +
         std::to_string(written.runs) + " runs, " + size + ")";
}

}  // namespace graspbed::testbed

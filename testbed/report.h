#pragma once
/// HTML reports: one self-contained page (styles, script and pictures inline, nothing fetched) for the
/// output directory of a suite, a scorecard or a sweep, read back from the JSON they wrote, so a
/// report can be made again from any finished output directory. Sections: a summary table (the
/// totals, and per controller the runs passed, failed, errored and without an oracle grip, each count
/// a link to the rows it counts), the comparison figures, and one row per run with its verdict, its
/// first failed expectation in words, its oracle grip or why there is none, its headline metrics and
/// links to its own pictures where they were written. The runs table sorts by any column and filters
/// by scenario, controller, sensor, verdict, oracle and free text; the filter and the sort live in
/// the URL fragment (report.html#verdict=failed&controller=grip_slip&sort=peak_grip_n&order=desc), so
/// a filtered view is a link. Format and the command: docs/controller.md ("Scorecard report").

#include <cstddef>
#include <string>

namespace graspbed::testbed {

/// What wrote the directory a report reads, by the file found in it.
enum class ReportKind {
  kScorecard,  ///< scorecard.json (and scorecard.png) of `graspbed score`
  kSuite,      ///< suite.json and one folder per scenario of `graspbed suite`
  kSweep,      ///< results.jsonl and manifest.json of `graspbed sweep` (or of a merge)
};

/// "scorecard", "suite" or "sweep".
const char* ReportKindName(ReportKind kind);

/// Settings of a report.
struct ReportOptions {
  /// Where a scorecard's runs kept their outputs (`graspbed score --runs-out`): each run's row links
  /// its folder <runs_dir>/<run>@<controller>/ and the pictures in it. "" = not kept. A suite's runs
  /// are always looked for in DIR/<scenario>/.
  std::string runs_dir;
  /// The page's path; "" = DIR/report.html. Links to runs' pictures are relative to its folder.
  std::string out_path;
};

/// What WriteReport wrote.
struct ReportWritten {
  std::string path;
  ReportKind kind = ReportKind::kSuite;
  int runs = 0;      ///< rows of the runs table
  size_t bytes = 0;  ///< size of the page
};

/// The page for the output directory `dir`, which holds scorecard.json, suite.json or results.jsonl
/// (looked for in that order).
/// @throws std::invalid_argument naming the directory or file: no such directory, none of those
///         files in it, a file that cannot be read, malformed JSON, or JSON of another shape
std::string ReportHtml(const std::string& dir, const ReportOptions& options = {});

/// Writes ReportHtml(dir, options) to options.out_path (default DIR/report.html) through a temporary
/// file and a rename, so the path never holds a half-written page.
/// @throws std::invalid_argument as ReportHtml; std::runtime_error naming the path it cannot write
ReportWritten WriteReport(const std::string& dir, const ReportOptions& options = {});

/// One line for the terminal: "report: PATH (suite, 4 runs, 61 kB)".
std::string DescribeReport(const ReportWritten& written);

namespace internal {

/// `text` with & < > " ' replaced by their character references (text and attribute values).
std::string EscapeHtml(const std::string& text);
/// Standard base64 (RFC 4648, with padding) of `bytes`, for data: URLs.
std::string Base64(const std::string& bytes);

}  // namespace internal

}  // namespace graspbed::testbed

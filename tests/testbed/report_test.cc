// The HTML report (testbed/report.h) from hand-written suite, scorecard and sweep outputs: one row per
// run with its verdict, first failed expectation in words and oracle grip or why there is none; the
// figures inline; the bad-input messages; and `graspbed report`'s exit codes. The page in a real
// browser: report_browser_test.py.
#include "testbed/report.h"

#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/cli_runner.h"
#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::testbed {
namespace {

using test_support::CliResult;
using test_support::ErrorOf;
using test_support::ReadText;
using test_support::RunCli;
using test_support::TempDir;

// A summary.json as a simulated run writes it, with the fields the report reads.
nlohmann::json Summary(const std::string& scenario, const std::string& controller, bool passed,
                       const nlohmann::json& oracle_grip_n, const std::string& oracle_note) {
  nlohmann::json expectations = nlohmann::json::array();
  expectations.push_back(
      {{"name", "not_dropped"}, {"limit", "true"}, {"value_text", "held"}, {"passed", true}, {"note", ""}});
  if (!passed) {
    expectations.push_back({{"name", "max_slip_mm"},
                            {"limit", "<= 3 mm"},
                            {"value_text", "4.20 mm"},
                            {"passed", false},
                            {"note", ""}});
    expectations.push_back({{"name", "max_peak_grip_n"},
                            {"limit", "<= 15 N"},
                            {"value_text", "16 N"},
                            {"passed", false},
                            {"note", ""}});
  }
  return {{"scenario", scenario},
          {"controller", controller},
          {"sensor", "inamp_16bit/paper"},
          {"completed", true},
          {"passed", passed},
          {"expectations", expectations},
          {"metrics",
           {{"peak_grip_n", 6.5},
            {"grip_efficiency", oracle_grip_n.is_null() ? nlohmann::json() : nlohmann::json(1.25)},
            {"max_slip_mm", passed ? 0.5 : 4.2},
            {"gross_slip_events", 2},
            {"gross_slip_detected", 1},
            {"false_slip_per_min", 0.0},
            {"wall_s", 0.4},
            {"oracle_grip_n", oracle_grip_n},
            {"oracle_note", oracle_note.empty() ? nlohmann::json() : nlohmann::json(oracle_note)}}}};
}

// A suite of three: passed, failed (two expectations), and one that threw; the first has plots.
std::string WriteSuite(const TempDir& dir) {
  nlohmann::json runs = nlohmann::json::array();
  runs.push_back(Summary("lift <cup>", "grip_slip", true, 4.5, ""));
  runs.push_back(Summary("pull_ramp", "open_loop", false, nullptr, "not holdable at the stall pinch (12 N)"));
  runs.push_back(
      {{"scenario", "broken"}, {"completed", false}, {"passed", false}, {"error", "boom: MuJoCo said no"}});
  dir.Write("suite/suite.json", nlohmann::json({{"completed", true},
                                                {"passed", false},
                                                {"scenarios", 3},
                                                {"passed_count", 1},
                                                {"failed_count", 2},
                                                {"jobs", 2},
                                                {"wall_s", 1.5},
                                                {"runs", runs}})
                                    .dump());
  dir.Write("suite/lift <cup>/grip.png", "not really a PNG");
  return dir.Path("suite");
}

TEST(ReportTest, SuiteRowsSayTheVerdictTheFirstFailureAndWhyThereIsNoOracle) {
  TempDir dir("report");
  const std::string html = ReportHtml(WriteSuite(dir));
  EXPECT_NE(html.find("data-verdict=\"passed\""), std::string::npos);
  EXPECT_NE(html.find("data-verdict=\"failed\""), std::string::npos);
  EXPECT_NE(html.find("data-verdict=\"error\""), std::string::npos);
  // The first failed expectation only, in words: what the run got against which limit.
  EXPECT_NE(html.find("max_slip_mm: got 4.20 mm, limit &lt;= 3 mm"), std::string::npos);
  EXPECT_EQ(html.find("max_peak_grip_n: got"), std::string::npos);
  EXPECT_NE(html.find("boom: MuJoCo said no"), std::string::npos);
  EXPECT_NE(html.find("none: not holdable at the stall pinch (12 N)"), std::string::npos);
  EXPECT_NE(html.find("data-oracle=\"none\""), std::string::npos);
  EXPECT_NE(html.find("4.50 N"), std::string::npos);
  // Names are escaped, and the run's plots linked relative to the page.
  EXPECT_NE(html.find("lift &lt;cup&gt;"), std::string::npos);
  EXPECT_EQ(html.find("lift <cup>"), std::string::npos);
  EXPECT_NE(html.find("href=\"lift &lt;cup&gt;/grip.png\""), std::string::npos);
  // The per-controller counts link to the rows they count.
  EXPECT_NE(html.find("href=\"#controller=open_loop&amp;oracle=none\""), std::string::npos);
  EXPECT_NE(html.find("runs per controller and verdict"), std::string::npos);
  EXPECT_NE(html.find("peak grip per run"), std::string::npos);
}

TEST(ReportTest, WriteReportWritesTheWholePageAtomically) {
  TempDir dir("report");
  const std::string suite = WriteSuite(dir);
  const ReportWritten written = WriteReport(suite);
  EXPECT_EQ(written.path, suite + "/report.html");
  EXPECT_EQ(written.kind, ReportKind::kSuite);
  EXPECT_EQ(written.runs, 3);
  const std::string html = ReadText(written.path);
  EXPECT_EQ(html.size(), written.bytes);
  EXPECT_EQ(html.rfind("</html>\n"), html.size() - 8);
  EXPECT_EQ(DescribeReport(written).rfind("report: " + suite + "/report.html (suite, 3 runs, ", 0), 0u);
}

TEST(ReportTest, ScorecardEmbedsItsFigureAndGroupsRunsByBaseScenario) {
  TempDir dir("report");
  nlohmann::json runs = nlohmann::json::array();
  runs.push_back({{"controller", "grip_slip"},
                  {"run", "pull_ramp.v3"},
                  {"overrides", nlohmann::json::object()},
                  {"summary", Summary("pull_ramp", "grip_slip", true, 4.0, "")}});
  runs.push_back({{"controller", "open_loop"},
                  {"run", "pull_ramp.v3"},
                  {"overrides", {{"sensor.profile", "divider_12bit"}}},
                  {"error", "interrupted"}});
  const nlohmann::json scorecard = {
      {"set",
       {{"name", "benchmark"},
        {"version", 4},
        {"seed", 1},
        {"file", "set.yaml"},
        {"runs_per_controller", 1}}},
      {"completed", true},
      {"wall_s", 3.0},
      {"jobs", 2},
      {"controllers", {{{"controller", "grip_slip"}, {"runs", 1}, {"gross_detected_pct", 50.0}}}},
      {"runs", runs}};
  dir.Write("score/scorecard.json", scorecard.dump());
  dir.Write("score/scorecard.png", "PNG!");
  dir.Write("runs/pull_ramp.v3@grip_slip/summary.json", "{}");
  ReportOptions options;
  options.runs_dir = dir.Path("runs");
  const std::string html = ReportHtml(dir.Path("score"), options);
  EXPECT_NE(html.find("src=\"data:image/png;base64,UE5HIQ==\""), std::string::npos);
  EXPECT_NE(html.find("data-scenario=\"pull_ramp\""), std::string::npos);
  EXPECT_NE(html.find("data-sensor=\"inamp_16bit/paper\""), std::string::npos);
  EXPECT_NE(html.find("data-sensor=\"divider_12bit\""), std::string::npos);  // from its overrides
  EXPECT_NE(html.find("gross_detected_pct"), std::string::npos);
  EXPECT_NE(html.find("href=\"../runs/pull_ramp.v3@grip_slip/\""), std::string::npos);
}

TEST(ReportTest, SweepShowsItsSweptKeys) {
  TempDir dir("report");
  dir.Write("sweep/manifest.json", R"({"spec": "mass.yaml", "total_runs": 2, "completed": true})");
  dir.Write("sweep/results.jsonl",
            R"({"run": 0, "scenario": "default", "object.mass_kg": 0.2, "passed": true, "completed": true, )"
            R"("max_slip_mm": 0.1, "peak_grip_n": 3.0, "failed_expectations": ""})"
            "\n"
            R"({"run": 1, "scenario": "default", "object.mass_kg": 0.9, "passed": false, "completed": true, )"
            R"("max_slip_mm": 9.0, "peak_grip_n": 8.0, "failed_expectations": "not_dropped"})"
            "\n");
  const std::string html = ReportHtml(dir.Path("sweep"));
  EXPECT_NE(html.find("data-key=\"object.mass_kg\""), std::string::npos);
  EXPECT_NE(html.find("not_dropped (names only"), std::string::npos);
  EXPECT_NE(html.find("data-verdict=\"failed\""), std::string::npos);
}

TEST(ReportTest, BadInputNamesTheDirectoryOrFile) {
  TempDir dir("report");
  EXPECT_EQ(ErrorOf<std::invalid_argument>([&] { ReportHtml(dir.Path("nowhere")); }),
            dir.Path("nowhere") +
                ": no such directory (expected the output directory of graspbed suite, score "
                "or sweep)");
  dir.Write("empty/notes.txt", "");
  EXPECT_EQ(ErrorOf<std::invalid_argument>([&] { ReportHtml(dir.Path("empty")); }),
            dir.Path("empty") +
                ": holds no scorecard.json, suite.json or results.jsonl (the outputs of graspbed "
                "score, suite and sweep)");
  dir.Write("bad/suite.json", "{\"runs\": [");
  EXPECT_EQ(ErrorOf<std::invalid_argument>([&] {
              ReportHtml(dir.Path("bad"));
            }).rfind(dir.Path("bad") + "/suite.json: malformed JSON: ", 0),
            0u);
  dir.Write("shape/scorecard.json", "{\"runs\": []}");
  EXPECT_EQ(ErrorOf<std::invalid_argument>([&] {
              ReportHtml(dir.Path("shape"));
            }).rfind(dir.Path("shape") + "/scorecard.json: not what graspbed writes there: ", 0),
            0u);
  dir.Write("lines/results.jsonl", "{\"run\": 0}\nnot json\n");
  EXPECT_EQ(ErrorOf<std::invalid_argument>([&] {
              ReportHtml(dir.Path("lines"));
            }).rfind(dir.Path("lines") + "/results.jsonl:2: malformed JSON: ", 0),
            0u);
  // A refused report leaves no page behind.
  EXPECT_THROW(WriteReport(dir.Path("bad")), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir.Path("bad/report.html")));
}

TEST(ReportTest, CommandExitsTwoOnBadInputAndNamesTheFile) {
  TempDir dir("report");
  dir.Write("bad/suite.json", "{");
  const CliResult bad = RunCli("report " + dir.Path("bad"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("graspbed: error: " + dir.Path("bad") + "/suite.json: malformed JSON"),
            std::string::npos)
      << bad.err;
  const CliResult missing = RunCli("report " + dir.Path("nowhere"));
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find(dir.Path("nowhere") + ": no such directory"), std::string::npos) << missing.err;

  const CliResult good = RunCli("report " + WriteSuite(dir) + " --out " + dir.Path("page.html"));
  EXPECT_EQ(good.exit_code, 0) << good.err;
  EXPECT_NE(good.out.find("report: " + dir.Path("page.html") + " (suite, 3 runs, "), std::string::npos)
      << good.out;
  // Relative to a page outside the suite's folder, the plots' links go into it.
  EXPECT_NE(ReadText(dir.Path("page.html")).find("href=\"suite/lift &lt;cup&gt;/grip.png\""),
            std::string::npos);
}

TEST(ReportTest, EscapesAndEncodes) {
  EXPECT_EQ(internal::EscapeHtml("a<b & \"c\" 'd'>"), "a&lt;b &amp; &quot;c&quot; &#39;d&#39;&gt;");
  EXPECT_EQ(internal::Base64(""), "");
  EXPECT_EQ(internal::Base64("f"), "Zg==");
  EXPECT_EQ(internal::Base64("fo"), "Zm8=");
  EXPECT_EQ(internal::Base64("foo"), "Zm9v");
  EXPECT_EQ(internal::Base64(std::string("\xff\x00\x80", 3)), "/wCA");
}

}  // namespace
}  // namespace graspbed::testbed

// SignalLog, the per-tick signals behind signals.csv and states.csv: rows come zeroed and are counted
// as lost past the capacity; WriteCsv writes every number exactly as std::to_chars does (the shortest
// text strtod reads back to the same double, which `graspbed replay` relies on), whatever its fast
// paths (integers, values cached per column, the 1 MB write buffer) take.
#include <gtest/gtest.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "common/signal_log.h"

namespace graspbed::common {
namespace {

// The text the writer must produce for one number: std::to_chars, and "nan" for every NaN.
std::string Expected(double value) {
  if (std::isnan(value)) return "nan";
  char text[64];
  return std::string(text, std::to_chars(text, text + sizeof(text), value).ptr);
}

std::string Formatted(double value) {
  char text[internal::kMaxNumberChars];
  return std::string(text, internal::FormatShortest(value, text));
}

double FromBits(uint64_t bits) {
  double value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

// The CSV a log must become, cell by cell with std::to_chars (the writer before its fast paths).
std::string ReferenceCsv(const SignalLog& log) {
  std::string csv = log.numeric_columns()[0];
  for (const auto& name : log.text_columns()) csv += "," + name;
  for (size_t c = 1; c < log.numeric_column_count(); ++c) csv += "," + log.numeric_columns()[c];
  csv += "\n";
  for (size_t r = 0; r < log.rows(); ++r) {
    for (size_t c = 0; c < log.numeric_column_count(); ++c) {
      if (c > 0) csv += ",";
      csv += Expected(log.At(r, c));
      if (c == 0) {
        for (size_t t = 0; t < log.text_column_count(); ++t) csv += std::string(",") + log.TextAt(r, t);
      }
    }
    csv += "\n";
  }
  return csv;
}

std::string WrittenCsv(const SignalLog& log) {
  std::FILE* file = std::tmpfile();
  EXPECT_NE(file, nullptr);
  log.WriteCsv(file);
  std::rewind(file);
  std::string csv;
  char chunk[1 << 16];
  for (size_t n; (n = std::fread(chunk, 1, sizeof(chunk), file)) > 0;) csv.append(chunk, n);
  std::fclose(file);
  return csv;
}

// Empty when equal, else the first line that differs (the files are megabytes: no whole dump).
std::string FirstDifference(const std::string& written, const std::string& expected) {
  const auto mismatch = std::mismatch(written.begin(), written.end(), expected.begin(), expected.end());
  if (mismatch.first == written.end() && mismatch.second == expected.end()) return "";
  const size_t at = static_cast<size_t>(mismatch.first - written.begin());
  const size_t start = written.rfind('\n', at == 0 ? 0 : at - 1);
  const size_t line_start = start == std::string::npos ? 0 : start + 1;
  const size_t line =
      static_cast<size_t>(std::count(written.begin(), written.begin() + line_start, '\n')) + 1;
  const auto line_at = [line_start](const std::string& text) {
    return text.substr(line_start, text.find('\n', line_start) - line_start);
  };
  return "line " + std::to_string(line) + ": written '" + line_at(written) + "' expected '" +
         line_at(expected) + "'";
}

TEST(SignalLogTest, RowsComeZeroedAndRowsPastTheCapacityAreCountedLost) {
  SignalLog log({"time_s", "a", "b"}, {"phase"}, 2);
  for (int r = 0; r < 2; ++r) {
    const char** text = nullptr;
    double* row = log.AppendRow(&text);
    ASSERT_NE(row, nullptr);
    EXPECT_EQ(row[0], 0.0);
    EXPECT_EQ(row[2], 0.0);
    EXPECT_STREQ(text[0], "");
    row[1] = r + 0.5;
  }
  const char** text = nullptr;
  EXPECT_EQ(log.AppendRow(&text), nullptr);
  EXPECT_EQ(log.rows(), 2u);
  EXPECT_EQ(log.lost_rows(), 1u);
  EXPECT_EQ(log.At(1, log.Column("a")), 1.5);
}

TEST(SignalLogTest, NumbersAreFormattedExactlyAsToChars) {
  // Every integer of the fast path and either side of its ends.
  for (int i = -100'010; i <= 100'010; ++i) ASSERT_EQ(Formatted(i), Expected(i)) << i;
  const double specials[] = {0.0,
                             -0.0,
                             0.5,
                             -0.25,
                             0.1,
                             1e5,
                             -1e5,
                             99999.5,
                             1e15,
                             1e16,
                             123456789.0,
                             4294967296.0,
                             -2147483648.0,
                             1e300,
                             std::numeric_limits<double>::min(),
                             std::numeric_limits<double>::denorm_min(),
                             -std::numeric_limits<double>::max(),
                             std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity(),
                             std::numeric_limits<double>::quiet_NaN(),
                             -std::numeric_limits<double>::quiet_NaN()};
  for (double value : specials) EXPECT_EQ(Formatted(value), Expected(value)) << value;
  EXPECT_EQ(Formatted(-std::numeric_limits<double>::infinity()), "-inf");
  std::mt19937_64 rng(7);
  for (int i = 0; i < 200'000; ++i) {
    const double value = FromBits(rng());
    ASSERT_EQ(Formatted(value), Expected(value)) << std::hexfloat << value;
  }
}

TEST(SignalLogTest, CsvIsByteIdenticalToFormattingEveryCellAndReadsBackBitForBit) {
  // Columns that stay constant, repeat a few values in turn (an ADC's codes), count, change every row,
  // and hold many more distinct values than the writer keeps per column; over 1 MB of text so the
  // buffer is written out several times.
  const std::vector<std::string> names = {"time_s", "constant", "codes",  "counter",
                                          "noise",  "wide",     "special"};
  const size_t rows = 30'000;
  SignalLog log(names, {"intent", "phase"}, rows);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double codes[] = {3373.7141516138354, 3397.330231022902, 3396.4662281176925, 0.0008416450864245716};
  const double special[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                            -0.0, 1e5, -std::numeric_limits<double>::infinity()};
  const char* phases[] = {"close", "holding", "a much longer phase name than the others", ""};
  for (size_t r = 0; r < rows; ++r) {
    const char** text = nullptr;
    double* row = log.AppendRow(&text);
    ASSERT_NE(row, nullptr);
    row[0] = 0.001 * static_cast<double>(r);
    row[1] = 9.81;
    row[2] = codes[rng() % 4];
    row[3] = static_cast<double>(r);
    row[4] = normal(rng);
    row[5] = static_cast<double>(rng() % 1000) * 0.1;
    row[6] = special[(r / 3) % 5];
    text[0] = r % 2 == 0 ? "lift" : "hold";
    text[1] = phases[(r / 7) % 4];
  }
  const std::string written = WrittenCsv(log);
  ASSERT_GT(written.size(), size_t{1} << 21);
  ASSERT_EQ(FirstDifference(written, ReferenceCsv(log)), "");

  // Every finite cell of a row reads back to the same bits.
  const size_t row_start = written.find('\n', written.size() / 2) + 1;
  const size_t row_end = written.find('\n', row_start);
  std::vector<std::string> cells;
  for (size_t start = row_start; start <= row_end;) {
    const size_t comma = std::min(written.find(',', start), row_end);
    cells.push_back(written.substr(start, comma - start));
    start = comma + 1;
  }
  ASSERT_EQ(cells.size(), names.size() + 2);
  const size_t row = static_cast<size_t>(std::llround(std::strtod(cells[0].c_str(), nullptr) / 0.001));
  for (size_t c = 1; c < names.size(); ++c) {
    const double value = log.At(row, c);
    if (!std::isfinite(value)) continue;
    const double read = std::strtod(cells[c + 2].c_str(), nullptr);
    EXPECT_EQ(std::memcmp(&read, &value, sizeof(value)), 0) << names[c] << " = " << cells[c + 2];
  }
}

TEST(SignalLogTest, EmptyLogWritesTheHeaderOnly) {
  const SignalLog log({"time_s", "x"}, {"phase"}, 0);
  EXPECT_EQ(WrittenCsv(log), "time_s,phase,x\n");
}

}  // namespace
}  // namespace graspbed::common

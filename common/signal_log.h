#pragma once
/// SignalLog: the per-tick signals of a run in storage reserved before the run, so appending a row
/// in the control loop never allocates. Numeric columns in one row-major block; a few text columns
/// (static strings such as the controller phase) stored as pointers.

#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace graspbed::common {

class SignalLog {
 public:
  /// `numeric_columns` and `text_columns` name the columns (text columns are written first after
  /// time in CSV order given by the caller); `capacity_rows` rows are reserved up front.
  /// The numeric storage is zeroed and its pages mapped here, not on first use in the loop.
  /// Throws std::bad_alloc when the memory cannot be had.
  SignalLog(std::vector<std::string> numeric_columns, std::vector<std::string> text_columns,
            size_t capacity_rows);

  /// Starts a new row and returns its numeric cells (numeric_column_count() of them, zeroed) and
  /// text cells; nullptr when the reserved capacity is used up (the row is counted as lost).
  /// Allocates nothing.
  double* AppendRow(const char*** text_cells);

  size_t rows() const { return rows_; }
  size_t lost_rows() const { return lost_rows_; }
  size_t numeric_column_count() const { return numeric_columns_.size(); }
  size_t text_column_count() const { return text_columns_.size(); }
  const std::vector<std::string>& numeric_columns() const { return numeric_columns_; }
  const std::vector<std::string>& text_columns() const { return text_columns_; }
  /// Index of numeric column `name`; throws std::out_of_range when there is none.
  size_t Column(const std::string& name) const;
  /// Cell (row, numeric column).
  double At(size_t row, size_t column) const { return values_[row * numeric_columns_.size() + column]; }
  const char* TextAt(size_t row, size_t column) const { return texts_[row * text_columns_.size() + column]; }
  /// A whole numeric column as a vector (for plots; allocates, not for the loop).
  std::vector<double> ColumnValues(const std::string& name) const;

  /// Writes the log as CSV (header: text columns after the first numeric column "time_s"). Numbers
  /// in the shortest form that reads back (strtod) to the same double (std::to_chars' text);
  /// inf/nan as "inf"/"nan". Allocates its buffers (1 MB, and 3 KB a column) and writes in 1 MB pieces.
  /// Throws std::runtime_error on a write error.
  void WriteCsv(std::FILE* file) const;

 private:
  std::vector<std::string> numeric_columns_;
  std::vector<std::string> text_columns_;
  size_t capacity_rows_ = 0;
  size_t rows_ = 0;
  size_t lost_rows_ = 0;
  /// Unmaps the numeric storage.
  struct Unmap {
    size_t bytes = 0;
    void operator()(double* values) const;
  };
  std::unique_ptr<double[], Unmap> values_;
  std::vector<const char*> texts_;
};

namespace internal {

/// Room FormatShortest() may need: "-2.2250738585072014e-308" is 24 characters.
inline constexpr size_t kMaxNumberChars = 32;

/// Writes `value` to `out` (room for kMaxNumberChars) exactly as std::to_chars(double) does (the
/// shortest text that strtod reads back to the same double), or "nan", "inf", "-inf"; returns the
/// end of the text. Exposed for tests.
char* FormatShortest(double value, char* out);

}  // namespace internal

/// Writes `log` as CSV to `path` through a temporary file in the same directory and rename(), so
/// `path` holds either its old content or the whole new one; std::runtime_error naming the path.
void WriteCsvAtomic(const SignalLog& log, const std::string& path);

/// Writes `content` to `path` the same way. Throws std::runtime_error naming the path.
void WriteFileAtomic(const std::string& path, const std::string& content);

/// A CSV file with a header line, its cells as text (e.g. signals.csv read back for a replay).
struct CsvTable {
  std::string path;
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  ///< each as long as the header
  /// Index of column `name`. Throws std::invalid_argument naming the file and column.
  size_t Column(const std::string& name) const;
  /// Cell (row, column) as a number; NaN when it is not one.
  double Number(size_t row, size_t column) const;
};

/// Reads `path`. Throws std::invalid_argument naming the file (and line) when it is missing, empty or
/// has a row of another length than the header.
CsvTable ReadCsvTable(const std::string& path);

}  // namespace graspbed::common

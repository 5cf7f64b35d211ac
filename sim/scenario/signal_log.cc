#include "sim/scenario/signal_log.h"

#include <charconv>
#include <cmath>

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace graspbed::scenario {

SignalLog::SignalLog(std::vector<std::string> numeric_columns, std::vector<std::string> text_columns,
                     size_t capacity_rows)
    : numeric_columns_(std::move(numeric_columns)),
      text_columns_(std::move(text_columns)),
      capacity_rows_(capacity_rows),
      values_(capacity_rows * numeric_columns_.size(), 0.0),
      texts_(capacity_rows * text_columns_.size(), "") {}

double* SignalLog::AppendRow(const char*** text_cells) {
  if (rows_ >= capacity_rows_) {
    ++lost_rows_;
    return nullptr;
  }
  double* row = values_.data() + rows_ * numeric_columns_.size();
  *text_cells = texts_.data() + rows_ * text_columns_.size();
  ++rows_;
  return row;
}

size_t SignalLog::Column(const std::string& name) const {
  const auto it = std::find(numeric_columns_.begin(), numeric_columns_.end(), name);
  if (it == numeric_columns_.end()) throw std::out_of_range("no signal column '" + name + "'");
  return static_cast<size_t>(it - numeric_columns_.begin());
}

std::vector<double> SignalLog::ColumnValues(const std::string& name) const {
  const size_t column = Column(name);
  std::vector<double> values(rows_);
  for (size_t r = 0; r < rows_; ++r) values[r] = At(r, column);
  return values;
}

void SignalLog::WriteCsv(std::FILE* file) const {
  // Header: time first, then the text columns, then the other numeric columns.
  std::string header = numeric_columns_.empty() ? "" : numeric_columns_[0];
  for (const auto& name : text_columns_) header += "," + name;
  for (size_t c = 1; c < numeric_columns_.size(); ++c) header += "," + numeric_columns_[c];
  header += "\n";
  if (std::fputs(header.c_str(), file) < 0) throw std::runtime_error("write error");
  char cell[64];
  std::string line;
  for (size_t r = 0; r < rows_; ++r) {
    line.clear();
    for (size_t c = 0; c < numeric_columns_.size(); ++c) {
      if (c > 0) line += ',';
      // Shortest text that reads back to the same double: a replay feeds the loop these very numbers.
      const double value = At(r, c);
      if (std::isnan(value)) {
        line += "nan";
      } else if (std::isinf(value)) {
        line += value > 0 ? "inf" : "-inf";
      } else {
        const auto result = std::to_chars(cell, cell + sizeof(cell), value);
        line.append(cell, result.ptr);
      }
      if (c == 0) {
        for (size_t t = 0; t < text_columns_.size(); ++t) {
          line += ',';
          line += TextAt(r, t);
        }
      }
    }
    line += '\n';
    if (std::fputs(line.c_str(), file) < 0) throw std::runtime_error("write error");
  }
}

}  // namespace graspbed::scenario

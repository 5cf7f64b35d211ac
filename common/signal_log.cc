#include "common/signal_log.h"

#include <sys/mman.h>
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <new>
#include <sstream>
#include <stdexcept>
#include <string>

namespace graspbed::common {

namespace {

// Zeroed memory of `bytes` with every page already mapped. Anonymous pages come zeroed from the
// kernel, so unlike std::vector<double>(n, 0.0) nothing is written twice, and asking for all pages in
// one call is 3x cheaper than a page fault each (a 20 s run keeps 28 MB of signals).
double* MapZeroed(size_t bytes) {
  if (bytes == 0) return nullptr;
  void* memory = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (memory == MAP_FAILED) throw std::bad_alloc();
#ifdef MADV_POPULATE_WRITE
  const bool populated = madvise(memory, bytes, MADV_POPULATE_WRITE) == 0;
#else
  const bool populated = false;
#endif
  if (!populated) {  // kernels before 5.14: touch every page
    const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
    for (size_t offset = 0; offset < bytes; offset += page) static_cast<volatile char*>(memory)[offset] = 0;
  }
  return static_cast<double*>(memory);
}

// A temporary name beside `path`, unique in this process and across processes.
std::string TempPath(const std::string& path) {
  static std::atomic<uint64_t> counter{0};
  return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

}  // namespace

void SignalLog::Unmap::operator()(double* values) const {
  if (values != nullptr) munmap(values, bytes);
}

SignalLog::SignalLog(std::vector<std::string> numeric_columns, std::vector<std::string> text_columns,
                     size_t capacity_rows)
    : numeric_columns_(std::move(numeric_columns)),
      text_columns_(std::move(text_columns)),
      capacity_rows_(capacity_rows),
      values_(MapZeroed(capacity_rows * numeric_columns_.size() * sizeof(double)),
              Unmap{capacity_rows * numeric_columns_.size() * sizeof(double)}),
      texts_(capacity_rows * text_columns_.size(), "") {}

double* SignalLog::AppendRow(const char*** text_cells) {
  if (rows_ >= capacity_rows_) {
    ++lost_rows_;
    return nullptr;
  }
  double* row = values_.get() + rows_ * numeric_columns_.size();
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

namespace internal {

char* FormatShortest(double value, char* out) {
  if (std::isnan(value)) {
    std::memcpy(out, "nan", 3);
    return out + 3;
  }
  if (std::isinf(value)) {
    if (value < 0) *out++ = '-';
    std::memcpy(out, "inf", 3);
    return out + 3;
  }
  // Exact integers below 1e5 (flags, counters, validity codes: a third of the cells) in digits of
  // our own: std::to_chars writes them the same way, as scientific notation is never shorter there.
  // -0.0 takes the general path for its sign.
  if (value > -1e5 && value < 1e5 && value == static_cast<double>(static_cast<int32_t>(value)) &&
      !(value == 0.0 && std::signbit(value))) {
    int32_t integer = static_cast<int32_t>(value);
    if (integer < 0) {
      *out++ = '-';
      integer = -integer;
    }
    char digits[8];
    int count = 0;
    do {
      digits[count++] = static_cast<char>('0' + integer % 10);
      integer /= 10;
    } while (integer > 0);
    while (count > 0) *out++ = digits[--count];
    return out;
  }
  return std::to_chars(out, out + kMaxNumberChars, value).ptr;
}

}  // namespace internal

void SignalLog::WriteCsv(std::FILE* file) const {
  // Rows are assembled in one block and written in large pieces. Formatted numbers are kept per
  // column in a small table keyed by the value's bits: a value seen before in its column (a constant,
  // a held value, one of a 12-bit ADC's readings or the estimate made of them: 55-80 % of the cells
  // of the shipped scenarios) copies its text instead of being formatted again (~40 ns a number).
  struct CachedCell {
    uint64_t bits = 0;
    uint32_t length = 0;  // 0: empty
    char text[internal::kMaxNumberChars] = {};
  };
  constexpr int kCacheBits = 6;  // 64 entries per column
  std::vector<CachedCell> cache(numeric_columns_.size() << kCacheBits);
  std::vector<char> buffer(size_t{1} << 20);
  size_t used = 0;
  const auto flush = [&] {
    if (used > 0 && std::fwrite(buffer.data(), 1, used, file) != used)
      throw std::runtime_error("write error");
    used = 0;
  };
  const auto append = [&](const char* text, size_t length) {
    std::memcpy(buffer.data() + used, text, length);
    used += length;
  };
  const auto reserve = [&](size_t length) {
    if (used + length <= buffer.size()) return;
    flush();
    if (length > buffer.size()) buffer.resize(length);
  };

  // Header: time first, then the text columns, then the other numeric columns.
  const auto header_cell = [&](const std::string& name, bool first) {
    reserve(name.size() + 2);
    if (!first) append(",", 1);
    append(name.data(), name.size());
  };
  if (!numeric_columns_.empty()) header_cell(numeric_columns_[0], true);
  for (const auto& name : text_columns_) header_cell(name, false);
  for (size_t c = 1; c < numeric_columns_.size(); ++c) header_cell(numeric_columns_[c], false);
  reserve(1);
  append("\n", 1);

  const size_t numeric_row_chars = numeric_columns_.size() * (internal::kMaxNumberChars + 1) + 1;
  for (size_t r = 0; r < rows_; ++r) {
    size_t row_chars = numeric_row_chars;
    for (size_t t = 0; t < text_columns_.size(); ++t) row_chars += std::strlen(TextAt(r, t)) + 1;
    reserve(row_chars);
    char* out = buffer.data() + used;
    const double* values = values_.get() + r * numeric_columns_.size();
    for (size_t c = 0; c < numeric_columns_.size(); ++c) {
      if (c > 0) *out++ = ',';
      // Shortest text that reads back to the same double: a replay feeds the loop these very numbers.
      uint64_t bits;
      std::memcpy(&bits, &values[c], sizeof(bits));
      CachedCell& cell = cache[(c << kCacheBits) +
                               static_cast<size_t>((bits * 0x9e37'79b9'7f4a'7c15ull) >> (64 - kCacheBits))];
      if (cell.length == 0 || cell.bits != bits) {
        cell.bits = bits;
        cell.length = static_cast<uint32_t>(internal::FormatShortest(values[c], cell.text) - cell.text);
      }
      // The whole slot is copied (a fixed-size copy is one instruction pair); the row has room for it.
      std::memcpy(out, cell.text, internal::kMaxNumberChars);
      out += cell.length;
      if (c == 0) {
        for (size_t t = 0; t < text_columns_.size(); ++t) {
          *out++ = ',';
          const char* text = TextAt(r, t);
          const size_t length = std::strlen(text);
          std::memcpy(out, text, length);
          out += length;
        }
      }
    }
    *out++ = '\n';
    used = static_cast<size_t>(out - buffer.data());
  }
  flush();
}

void WriteCsvAtomic(const SignalLog& log, const std::string& path) {
  const std::string temp = TempPath(path);
  std::FILE* file = std::fopen(temp.c_str(), "w");
  if (file == nullptr) throw std::runtime_error(path + ": cannot write");
  try {
    log.WriteCsv(file);
  } catch (const std::exception&) {
    std::fclose(file);
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": write error");
  }
  if (std::fclose(file) != 0 || std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": write error");
  }
}

void WriteFileAtomic(const std::string& path, const std::string& content) {
  const std::string temp = TempPath(path);
  {
    std::ofstream stream(temp, std::ios::binary | std::ios::trunc);
    if (!stream) throw std::runtime_error(path + ": cannot write");
    stream << content;
    stream.flush();
    if (!stream) {
      std::remove(temp.c_str());
      throw std::runtime_error(path + ": write error");
    }
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    std::remove(temp.c_str());
    throw std::runtime_error(path + ": cannot rename the temporary file into place");
  }
}

size_t CsvTable::Column(const std::string& name) const {
  for (size_t i = 0; i < header.size(); ++i) {
    if (header[i] == name) return i;
  }
  throw std::invalid_argument(path + ":1: no column '" + name + "'");
}

double CsvTable::Number(size_t row, size_t column) const {
  const std::string& cell = rows[row][column];
  char* end = nullptr;
  const double value = std::strtod(cell.c_str(), &end);
  return cell.empty() || *end != '\0' ? std::numeric_limits<double>::quiet_NaN() : value;
}

CsvTable ReadCsvTable(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw std::invalid_argument(path + ": cannot read");
  CsvTable table;
  table.path = path;
  const auto split = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream stream(line);
    for (std::string cell; std::getline(stream, cell, ',');) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    return cells;
  };
  std::string line;
  if (!std::getline(file, line) || line.empty())
    throw std::invalid_argument(path + ": empty, no header line");
  table.header = split(line);
  int line_number = 1;
  while (std::getline(file, line)) {
    ++line_number;
    if (line.empty()) continue;
    table.rows.push_back(split(line));
    if (table.rows.back().size() != table.header.size()) {
      throw std::invalid_argument(path + ":" + std::to_string(line_number) + ": " +
                                  std::to_string(table.rows.back().size()) + " cells, the header has " +
                                  std::to_string(table.header.size()));
    }
  }
  return table;
}

}  // namespace graspbed::common

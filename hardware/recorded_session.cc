#include "hardware/recorded_session.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "common/yaml_map.h"

namespace graspbed::hardware {
namespace {

using common::ConfigError;

std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> cells;
  size_t begin = 0;
  for (;;) {
    const size_t comma = line.find(',', begin);
    cells.push_back(line.substr(begin, comma == std::string::npos ? std::string::npos : comma - begin));
    if (comma == std::string::npos) break;
    begin = comma + 1;
  }
  if (!cells.empty() && !cells.back().empty() && cells.back().back() == '\r') cells.back().pop_back();
  return cells;
}

class Table {
 public:
  Table(const std::string& path, std::vector<std::string> header) : path_(path), header_(std::move(header)) {
    for (size_t c = 0; c < header_.size(); ++c) index_[header_[c]] = c;
  }
  std::optional<size_t> Find(const std::string& name) const {
    const auto it = index_.find(name);
    if (it == index_.end()) return std::nullopt;
    return it->second;
  }
  size_t Require(const std::string& name) const {
    const std::optional<size_t> column = Find(name);
    if (!column) throw ConfigError(path_ + ":1: no column " + name + " (" + kinds_ + ")");
    return *column;
  }
  /// A number, or NaN for an empty cell (an unknown value).
  double NumberOrUnknown(const std::vector<std::string>& row, size_t column, int line) const {
    if (row[column].empty()) return std::nan("");
    return Number(row, column, line);
  }
  double Number(const std::vector<std::string>& row, size_t column, int line) const {
    const std::string& cell = row[column];
    char* end = nullptr;
    const double value = std::strtod(cell.c_str(), &end);
    if (cell.empty() || end != cell.c_str() + cell.size()) {
      throw ConfigError(path_ + ":" + std::to_string(line) + ": " + header_[column] + " = '" + cell +
                        "': expected a number");
    }
    return value;
  }
  const std::vector<std::string>& header() const { return header_; }

 private:
  std::string path_;
  std::vector<std::string> header_;
  std::map<std::string, size_t> index_;
  std::string kinds_ = "expected a run's signals.csv or a frame log";
};

int CountUnits(const Table& table, const std::string& prefix) {
  int units = 0;
  while (table.Find(prefix + std::to_string(units))) ++units;
  return units;
}

}  // namespace

RecordedSession LoadRecordedSession(const std::string& path, int expected_units,
                                    std::span<const char* const> hand_columns) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot read the recording");
  std::string line;
  if (!std::getline(in, line)) throw ConfigError(path + ":1: empty file, expected a recording");
  const Table table(path, SplitCsv(line));
  RecordedSession session;
  session.path = path;
  const bool signals = table.Find("time_s").has_value();
  if (!signals && !table.Find("device_time_s")) {
    throw ConfigError(path +
                      ":1: neither a run's signals.csv (time_s, r1_ohm_0, ...) nor a frame log (seq, "
                      "device_time_s, r1_0, ...)");
  }
  session.kind = signals ? RecordedSession::Kind::kRunSignals : RecordedSession::Kind::kFrameLog;
  const std::string r1_prefix = signals ? "r1_ohm_" : "r1_";
  const std::string r2_prefix = signals ? "r2_ohm_" : "r2_";
  session.unit_count = CountUnits(table, r1_prefix);
  if (session.unit_count != expected_units) {
    throw ConfigError(path + ":1: the recording has " + std::to_string(session.unit_count) +
                      " units (columns " + r1_prefix + "K) but the scenario's layout has " +
                      std::to_string(expected_units));
  }
  std::vector<size_t> r1_columns;
  std::vector<size_t> r2_columns;
  for (int k = 0; k < session.unit_count; ++k) {
    r1_columns.push_back(table.Require(r1_prefix + std::to_string(k)));
    r2_columns.push_back(table.Require(r2_prefix + std::to_string(k)));
  }
  const size_t time_column = table.Require(signals ? "time_s" : "device_time_s");
  const std::optional<size_t> status_column = table.Find("read_status");
  const std::optional<size_t> seq_column = table.Find(signals ? "frame_seq" : "seq");
  const std::optional<size_t> frame_time_column = table.Find(signals ? "frame_time_s" : "device_time_s");
  const std::optional<size_t> flags_column = table.Find("frame_flags");
  const std::optional<size_t> session_column = table.Find("session");
  const std::optional<size_t> intent_column = table.Find("intent");
  const std::optional<size_t> phase_column = table.Find("phase");
  const std::optional<size_t> effort_column = table.Find("grip_effort");
  const std::optional<size_t> enable_column = table.Find("motor_enable");
  const std::optional<size_t> brake_column = table.Find("brake");
  const bool commands = effort_column && enable_column && brake_column;
  std::vector<size_t> hand_column_index;
  for (const char* name : hand_columns) {
    if (const std::optional<size_t> column = table.Find(name)) hand_column_index.push_back(*column);
  }
  if (hand_column_index.size() != hand_columns.size()) hand_column_index.clear();  // all or none
  session.hand_column_count = hand_column_index.size();

  int line_number = 1;
  double first_time_s = 0.0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.empty()) continue;
    const std::vector<std::string> row = SplitCsv(line);
    if (row.size() != table.header().size()) {
      throw ConfigError(path + ":" + std::to_string(line_number) + ": " + std::to_string(row.size()) +
                        " cells, the header has " + std::to_string(table.header().size()));
    }
    double time_s = table.Number(row, time_column, line_number);
    if (!signals) {
      // A frame log's ticks are its frames, on the device's clock from its first frame.
      if (session.ticks() == 0) first_time_s = time_s;
      time_s -= first_time_s;
    }
    if (!std::isfinite(time_s) || (session.ticks() > 0 && time_s < session.time_s.back())) {
      throw ConfigError(path + ":" + std::to_string(line_number) + ": " + table.header()[time_column] +
                        " = " + row[time_column] + ": times must be finite and not decrease");
    }
    const size_t tick = session.ticks();
    session.time_s.push_back(time_s);
    for (int k = 0; k < session.unit_count; ++k) {
      session.r1_ohm.push_back(table.Number(row, r1_columns[static_cast<size_t>(k)], line_number));
      session.r2_ohm.push_back(table.Number(row, r2_columns[static_cast<size_t>(k)], line_number));
    }
    sensor::ReadStatus status = sensor::ReadStatus::kOk;
    if (status_column) {
      const double code = table.Number(row, *status_column, line_number);
      if (code != std::floor(code) || code < 0 ||
          code > static_cast<double>(sensor::ReadStatus::kDisconnected)) {
        throw ConfigError(path + ":" + std::to_string(line_number) +
                          ": read_status = " + row[*status_column] +
                          ": expected 0 (ok), 1 (no new frame), 2 (stale) or 3 (disconnected)");
      }
      status = static_cast<sensor::ReadStatus>(static_cast<int>(code));
    } else if (signals && tick > 0) {
      // Older signals.csv: a row whose resistances all equal the row before's took no new frame.
      bool same = true;
      const size_t units = static_cast<size_t>(session.unit_count);
      for (size_t k = 0; k < units && same; ++k) {
        same = session.r1_ohm[tick * units + k] == session.r1_ohm[(tick - 1) * units + k] &&
               session.r2_ohm[tick * units + k] == session.r2_ohm[(tick - 1) * units + k];
      }
      if (same) status = sensor::ReadStatus::kNoNewFrame;
    }
    session.status.push_back(status);
    session.sequence.push_back(seq_column ? static_cast<uint32_t>(table.Number(row, *seq_column, line_number))
                                          : static_cast<uint32_t>(tick));
    session.frame_time_s.push_back(frame_time_column ? table.Number(row, *frame_time_column, line_number)
                                                     : time_s);
    session.flags.push_back(flags_column ? static_cast<uint8_t>(table.Number(row, *flags_column, line_number))
                                         : 0);
    session.session.push_back(
        session_column ? static_cast<uint64_t>(table.Number(row, *session_column, line_number)) : 0);
    if (intent_column) session.intent.push_back(row[*intent_column]);
    if (phase_column) session.phase.push_back(row[*phase_column]);
    for (size_t c = 0; c < hand_column_index.size(); ++c) {
      double cell = table.NumberOrUnknown(row, hand_column_index[c], line_number);
      if (c == 0 && !signals) cell -= first_time_s;  // the frame log's device clock, as its ticks
      session.hand_cells.push_back(cell);
    }
    if (commands) {
      hand::HandCommand command;
      command.grip_effort = table.Number(row, *effort_column, line_number);
      command.enable = table.Number(row, *enable_column, line_number) != 0.0;
      command.brake = table.Number(row, *brake_column, line_number) != 0.0;
      session.commands.push_back(command);
    }
  }
  if (session.ticks() == 0) throw ConfigError(path + ": no rows after the header: nothing to replay");
  return session;
}

ReplayBackend::ReplayBackend(const RecordedSession& recording, double nominal_r0_ohm)
    : recording_(recording), nominal_r0_ohm_(nominal_r0_ohm) {}

void ReplayBackend::Seek(size_t tick) {
  if (tick != tick_) served_ = false;
  tick_ = tick;
}

sensor::ReadStatus ReplayBackend::Read(sensor::RawFrame* frame) {
  const sensor::ReadStatus status = recording_.status[tick_];
  if (status != sensor::ReadStatus::kOk) return status;
  if (served_) return sensor::ReadStatus::kNoNewFrame;
  served_ = true;
  const size_t units = static_cast<size_t>(recording_.unit_count);
  frame->sequence = recording_.sequence[tick_];
  frame->time_s = recording_.frame_time_s[tick_];
  frame->unit_count = recording_.unit_count;
  frame->flags = recording_.flags[tick_];
  for (size_t k = 0; k < units; ++k) {
    frame->r1_ohm[k] = recording_.r1_ohm[tick_ * units + k];
    frame->r2_ohm[k] = recording_.r2_ohm[tick_ * units + k];
  }
  ++counters_.frames;
  return status;
}

}  // namespace graspbed::hardware

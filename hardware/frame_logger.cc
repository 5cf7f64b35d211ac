#include "hardware/frame_logger.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <utility>

namespace graspbed::hardware {

FrameLogger::FrameLogger(std::string path, TapSource source, const sensor::Layout& layout,
                         const sensor::Calibration& calibration, const sensor::ReadoutConfig& readout,
                         const sensor::InversionConfig& inversion, double nominal_r0_ohm, HandLogColumns hand)
    : path_(std::move(path)),
      source_(std::move(source)),
      unit_count_(layout.unit_count()),
      readout_(readout, layout.unit_count(), nominal_r0_ohm),
      inversion_(layout, calibration, inversion),
      hand_(std::move(hand)),
      hand_cells_(hand_.names.size()) {
  out_.open(path_ + ".partial", std::ios::trunc);
  if (!out_) throw std::invalid_argument("--log " + path_ + ": cannot write this file");
  out_ << "seq,device_time_s";
  for (int k = 0; k < unit_count_; ++k) {
    out_ << ",r1_" << k << ",r2_" << k << ",fn_" << k << ",ft_" << k << ",valid_" << k;
  }
  for (const std::string& name : hand_.names) out_ << ',' << name;
  out_ << '\n';
  thread_ = std::thread([this] { Run(); });
}

FrameLogger::~FrameLogger() { StopThread(); }

void FrameLogger::Finish() {
  if (!StopThread()) return;
  out_.flush();
  out_.close();
  if (out_.fail()) {
    error_ = "writing " + path_ + ".partial failed (disk full?); left as .partial";
    return;
  }
  std::error_code rename_error;
  std::filesystem::rename(path_ + ".partial", path_, rename_error);
  if (rename_error) error_ = "renaming " + path_ + ".partial failed: " + rename_error.message();
}

bool FrameLogger::StopThread() {
  if (!thread_.joinable()) return false;
  done_ = true;
  thread_.join();
  return true;
}

void FrameLogger::Run() {
  for (;;) {
    // Read the flag before draining: frames tapped before Finish() are all written.
    const bool last_round = done_.load();
    bool any = false;
    while (source_(&entry_)) {
      Write();
      any = true;
    }
    if (last_round) return;
    if (!any) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

void FrameLogger::Write() {
  if (entry_.session != session_) {
    session_ = entry_.session;
    readout_.Reset();
  }
  readout_.Process(entry_.frame, &readout_frame_);
  inversion_.Invert(readout_frame_, &state_);
  char buffer[96];
  std::snprintf(buffer, sizeof(buffer), "%u,%.6f", entry_.frame.sequence, entry_.frame.time_s);
  out_ << buffer;
  for (int k = 0; k < unit_count_; ++k) {
    std::snprintf(buffer, sizeof(buffer), ",%.3f,%.3f,%.5f,%.5f,%d", entry_.frame.r1_ohm[k],
                  entry_.frame.r2_ohm[k], state_.fn_n[k], state_.ft_n[k],
                  state_.validity[k] == sensor::UnitValidity::kValid ? 1 : 0);
    out_ << buffer;
  }
  if (!hand_cells_.empty()) {
    hand_.write(entry_.hand, hand_cells_.data());
    for (const double cell : hand_cells_) {
      // Unknown: nan, as in signals.csv; values to 9 digits (below a micro-unit's wire step).
      if (std::isnan(cell)) {
        out_ << ",nan";
      } else {
        std::snprintf(buffer, sizeof(buffer), ",%.9g", cell);
        out_ << buffer;
      }
    }
  }
  out_ << '\n';
  rows_.fetch_add(1);
}

}  // namespace graspbed::hardware

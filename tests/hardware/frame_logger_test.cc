// FrameLogger on real files, fed from a queue instead of a link's tap: every frame becomes a row with
// its own readout and inversion, a new device session re-tares, and only a finished log is renamed
// into place (an unfinished one stays PATH.partial).
#include "hardware/frame_logger.h"

#include <gtest/gtest.h>

#include <deque>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "tests/support/error_of.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::hardware {
namespace {

using graspbed::test_support::ReadText;
using graspbed::test_support::TempDir;

constexpr double kR0Ohm = 3400.0;
// The paper's worked numbers: Fn = 10 N alone gives R1 = R2 = 5270 Ohm on every unit.
constexpr double kLoadedOhm = 5270.0;
constexpr double kLoadedFnN = 10.0;
// The log prints Fn with %.5f, and 5270 Ohm is the paper's rounding of 5270.0 exactly.
constexpr double kLogFnTolN = 1e-3;
constexpr int kBaselineFrames = 2;

/// A tap fed by the test: frames pushed in order come out in order.
class Queue {
 public:
  void Push(uint32_t sequence, double resistance_ohm, uint64_t session, int units) {
    TappedFrame entry;
    entry.frame.sequence = sequence;
    entry.frame.time_s = 0.001 * sequence;
    entry.frame.unit_count = units;
    entry.frame.r1_ohm.fill(resistance_ohm);
    entry.frame.r2_ohm.fill(resistance_ohm);
    entry.session = session;
    std::lock_guard lock(mutex_);
    frames_.push_back(entry);
  }
  bool Pop(TappedFrame* out) {
    std::lock_guard lock(mutex_);
    if (frames_.empty()) return false;
    *out = frames_.front();
    frames_.pop_front();
    return true;
  }

 private:
  std::mutex mutex_;
  std::deque<TappedFrame> frames_;
};

std::vector<std::vector<std::string>> Rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::stringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> cells;
    std::stringstream split(line);
    for (std::string cell; std::getline(split, cell, ',');) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

class FrameLoggerTest : public ::testing::Test {
 protected:
  std::unique_ptr<FrameLogger> MakeLogger(const std::string& path) {
    sensor::ReadoutConfig readout;
    readout.baseline_frames = kBaselineFrames;
    return std::make_unique<FrameLogger>(
        path, [this](TappedFrame* out) { return queue_.Pop(out); }, layout_,
        sensor::PaperCalibration(layout_.unit_count()), readout, sensor::InversionConfig{}, kR0Ohm);
  }

  const sensor::Layout layout_ = sensor::LoadLayout(sensor::DefaultLayoutPath());
  const int units_ = layout_.unit_count();
  Queue queue_;
  const TempDir dir_{"frame_logger"};
};

TEST_F(FrameLoggerTest, WritesEveryFrameWithItsEstimateAndRetaresOnANewSession) {
  const std::string path = dir_.Path("frames.csv");
  auto logger = MakeLogger(path);
  // Session 1: the tare, then a 10 N load; session 2 (a device reboot): loaded from its first frame.
  queue_.Push(1, kR0Ohm, 1, units_);
  queue_.Push(2, kR0Ohm, 1, units_);
  queue_.Push(3, kLoadedOhm, 1, units_);
  queue_.Push(1, kLoadedOhm, 2, units_);
  logger->Finish();
  EXPECT_TRUE(logger->error().empty()) << logger->error();
  EXPECT_EQ(logger->rows(), 4u);
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));

  const auto rows = Rows(ReadText(path));
  ASSERT_EQ(rows.size(), 5u);
  ASSERT_EQ(rows[0].size(), 2u + 5u * static_cast<size_t>(units_));
  EXPECT_EQ(rows[0][0], "seq");
  EXPECT_EQ(rows[0][2], "r1_0");
  EXPECT_EQ(rows[0][6], "valid_0");
  for (size_t r = 1; r < rows.size(); ++r) ASSERT_EQ(rows[r].size(), rows[0].size()) << "row " << r;
  EXPECT_EQ(rows[1][0], "1");
  EXPECT_EQ(rows[3][0], "3");
  EXPECT_DOUBLE_EQ(std::stod(rows[3][2]), kLoadedOhm);
  for (int k = 0; k < units_; ++k) {
    const size_t base = 2 + 5 * static_cast<size_t>(k);
    // Frames 1 and 2 are the baseline being taken; frame 3 is inverted against it.
    EXPECT_EQ(rows[1][base + 4], "0") << "unit " << k << " valid before its tare";
    EXPECT_EQ(rows[3][base + 4], "1") << "unit " << k;
    EXPECT_NEAR(std::stod(rows[3][base + 2]), kLoadedFnN, kLogFnTolN) << "unit " << k;
    // The new session's first frame starts a new baseline: no estimate yet.
    EXPECT_EQ(rows[4][base + 4], "0") << "unit " << k << ": no re-tare after the device session changed";
  }
}

TEST_F(FrameLoggerTest, AnUnfinishedLogStaysPartial) {
  const std::string path = dir_.Path("crashed.csv");
  {
    auto logger = MakeLogger(path);
    queue_.Push(1, kR0Ohm, 1, units_);
  }  // destroyed without Finish(): as after an exception in the session
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::exists(path + ".partial"));
}

TEST_F(FrameLoggerTest, RefusesAPathItCannotWrite) {
  const std::string path = dir_.Path("no_such_dir/frames.csv");
  const std::string error = graspbed::test_support::ErrorOf<std::invalid_argument>([&] { MakeLogger(path); });
  EXPECT_NE(error.find("--log " + path + ": cannot write this file"), std::string::npos) << error;
}

}  // namespace
}  // namespace graspbed::hardware

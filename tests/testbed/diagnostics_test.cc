// A controller's diagnostic channels in signals.csv: the reference controller's cue statistics and
// thresholds as columns ctl_<name>, consistent with the flags it raised; none for a controller that
// declares none; bad channel names refused naming the controller.
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "common/config_error.h"
#include "controller/grip_slip_controller.h"
#include "testbed/run_outputs.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed::testbed {
namespace {

using graspbed::test_support::SourcePath;
using graspbed::test_support::TempDir;
using test_support::Signals;

/// A controller that does nothing but declare the channels it is given.
class ChannelsOnly final : public controller::GraspController {
 public:
  explicit ChannelsOnly(std::vector<controller::DiagnosticChannel> channels)
      : channels_(std::move(channels)) {}
  void Reset() override {}
  void SetIntent(controller::GraspIntent) override {}
  hand::HandCommand Update(const sensor::TactileState&, const hand::HandState&, double) override {
    return {};
  }
  void SetGripCeiling(double) override {}
  controller::ControllerTelemetry telemetry() const override { return {}; }
  std::string name() const override { return "channels_only"; }
  std::span<const controller::DiagnosticChannel> diagnostic_channels() const override { return channels_; }

 private:
  std::vector<controller::DiagnosticChannel> channels_;
};

std::string RefusalOf(std::vector<controller::DiagnosticChannel> channels) {
  try {
    internal::DiagnosticColumns(ChannelsOnly(std::move(channels)));
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "accepted";
}

/// Runs `config` with outputs in `dir` (no plots) and reads its signals.csv back.
Signals RunAndRead(const ScenarioConfig& config, const TempDir& dir) {
  RunOptions run;
  run.out_dir = dir.Path("run");
  run.write_plots = false;
  EXPECT_TRUE(RunScenario(config, run).completed);
  return Signals(run.out_dir + "/signals.csv");
}

TEST(DiagnosticsTest, TheReferenceControllersCuesAreInTheSignalsAtEveryFlag) {
  // pull_ramp: a pull the grip cannot hold at first, so the cues fire.
  const ScenarioConfig config = LoadScenario(SourcePath("scenarios/pull_ramp.yaml"));
  ASSERT_EQ(config.controller.name, "grip_slip");
  TempDir dir("diagnostics");
  const Signals signals = RunAndRead(config, dir);

  const controller::GripSlipController reference{controller::GripSlipConfig{}};
  ASSERT_FALSE(reference.diagnostic_channels().empty());
  for (const controller::DiagnosticChannel& channel : reference.diagnostic_channels()) {
    EXPECT_TRUE(signals.Has(std::string("ctl_") + channel.name)) << channel.name;
  }
  const std::vector<double>& flag = signals.Column("slip_flag");
  const std::vector<double>& ratio = signals.Column("ctl_ratio_cue");
  const std::vector<double>& vibration = signals.Column("ctl_vibration_cue");
  const std::vector<double>& centroid = signals.Column("ctl_centroid_cue");
  const std::vector<double>& rms = signals.Column("ctl_vibration_rms_n");
  const std::vector<double>& threshold = signals.Column("ctl_vibration_threshold_n");
  const std::vector<double>& load_ratio = signals.Column("ctl_load_ratio");
  const std::vector<double>& ratio_threshold = signals.Column("ctl_ratio_threshold");
  int rises = 0;
  for (size_t r = 1; r < signals.rows(); ++r) {
    // A flag rises only on a cue that counts, and a counted cue is up in the detector.
    if (flag[r] != 0.0 && flag[r - 1] == 0.0) {
      ++rises;
      EXPECT_TRUE(ratio[r] != 0.0 || vibration[r] != 0.0 || centroid[r] != 0.0)
          << "flag rose at " << signals.At("time_s", r) << " s with no cue up";
    }
    // The vibration cue is up only with its statistic over its threshold (for 3 frames running).
    if (vibration[r] != 0.0) {
      EXPECT_GT(rms[r], threshold[r]) << "at " << signals.At("time_s", r) << " s";
    }
    // The ratio cue rises only with the load ratio over its threshold.
    if (ratio[r] != 0.0 && ratio[r - 1] == 0.0) {
      EXPECT_GT(load_ratio[r], ratio_threshold[r]) << "at " << signals.At("time_s", r) << " s";
    }
  }
  EXPECT_GE(rises, 1) << "the pull raised no flag: the test checks nothing";
}

TEST(DiagnosticsTest, AControllerWithoutChannelsAddsNoColumns) {
  ScenarioConfig config = LoadScenario(SourcePath("scenarios/default.yaml"));
  config.controller.name = "open_loop";
  config.controller.params.clear();
  config.duration_s = 0.3;
  TempDir dir("diagnostics_none");
  const Signals signals = RunAndRead(config, dir);
  for (const std::string& column : signals.header()) EXPECT_NE(column.rfind("ctl_", 0), 0u) << column;
}

TEST(DiagnosticsTest, ARunOfAControllerWithBadChannelsIsRefusedBeforeAnyOutput) {
  ScenarioConfig config = LoadScenario(SourcePath("scenarios/default.yaml"));
  TempDir dir("diagnostics_bad");
  RunOptions run;
  run.out_dir = dir.Path("run");
  run.make_controller = [](const ControllerOptions&) {
    return std::make_unique<ChannelsOnly>(std::vector<controller::DiagnosticChannel>{{"Bad Name", ""}});
  };
  try {
    RunScenario(config, run);
    ADD_FAILURE() << "the run was not refused";
  } catch (const common::ConfigError& error) {
    EXPECT_NE(std::string(error.what()).find("controller 'channels_only': diagnostic channel 'Bad Name'"),
              std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(std::filesystem::exists(run.out_dir));
}

TEST(DiagnosticsTest, BadChannelsAreRefusedNamingTheController) {
  EXPECT_EQ(internal::DiagnosticColumns(ChannelsOnly({{"a_n", ""}, {"b2", ""}})),
            (std::vector<std::string>{"ctl_a_n", "ctl_b2"}));
  EXPECT_EQ(RefusalOf({{"Vibration RMS", ""}}),
            "controller 'channels_only': diagnostic channel 'Vibration RMS': a name is lower-case letters, "
            "digits and '_'");
  EXPECT_EQ(
      RefusalOf({{"", ""}}),
      "controller 'channels_only': diagnostic channel '': a name is lower-case letters, digits and '_'");
  EXPECT_EQ(RefusalOf({{"a", ""}, {"a", ""}}),
            "controller 'channels_only': diagnostic channel 'a' declared twice");
  std::vector<controller::DiagnosticChannel> many(controller::kMaxDiagnosticChannels + 1, {"x", ""});
  EXPECT_EQ(RefusalOf(many), "controller 'channels_only': declares 33 diagnostic channels (at most 32)");
}

}  // namespace
}  // namespace graspbed::testbed

// Videos of runs, offscreen (no display, no GPU): the default scenario's video has the frame count and
// size asked for (read back by ffprobe), a video leaves the run's results unchanged, and a missing
// encoder or a bad size is refused with a message that says what to do.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/rgb_image.h"
#include "common/video_writer.h"
#include "sim/sim_rig.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "testbed/show/video.h"
#include "tests/support/cli_runner.h"
#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed {
namespace {

namespace fs = std::filesystem;
using test_support::CliResult;
using test_support::RunCli;
using test_support::SourcePath;
using test_support::TempDir;

constexpr int kExitOk = 0;
constexpr int kExitBadInput = 2;
// Small, quick videos: 10 fps of the 2.5 s default scenario is 26 frames.
constexpr double kFps = 10.0;
constexpr int kWidthPx = 320;
constexpr int kHeightPx = 240;

std::string ReadFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

/// ffprobe's answer for the video stream of `path`: "width,height,frames".
std::string Probe(const std::string& path) {
  const std::string command =
      "ffprobe -v error -select_streams v:0 -count_frames -show_entries "
      "stream=width,height,nb_read_frames -of csv=p=0 '" +
      path + "' 2>&1";
  std::FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return "popen failed";
  std::string out;
  char buffer[256];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) out += buffer;
  pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

TEST(VideoCliTest, DefaultScenarioVideoHasTheFrameCountAndSizeAskedFor) {
  TempDir dir("video_cli");
  const std::string out = dir.Path("run");
  const CliResult result = RunCli("run " + SourcePath("scenarios/default.yaml") + " --no-plots --out " + out +
                                  " --video --video-fps 10 --video-size 320x240");
  ASSERT_EQ(result.exit_code, kExitOk) << result.err;
  const testbed::ScenarioConfig config = testbed::LoadScenario(SourcePath("scenarios/default.yaml"));
  const int expected_frames = show::VideoFrameCount(config.duration_s, kFps);
  EXPECT_EQ(expected_frames, 26);  // 0, 0.1, ..., 2.5 s
  EXPECT_EQ(Probe(out + "/video.mp4"), std::to_string(kWidthPx) + "," + std::to_string(kHeightPx) + "," +
                                           std::to_string(expected_frames));
  EXPECT_NE(result.err.find("ms/frame"), std::string::npos) << result.err;
  // The strip: 6 frames at the video's own size (not scaled down: the panel text stays legible), in two
  // rows of three.
  const image::RgbImage strip = image::ReadPng(out + "/video_strip.png");
  EXPECT_EQ(strip.width_px, 3 * kWidthPx);
  EXPECT_EQ(strip.height_px, 2 * kHeightPx);
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_EQ(entry.path().string().find(".tmp-"), std::string::npos) << entry.path() << " left behind";
  }
}

TEST(VideoCliTest, SuiteAndSweepWriteOneVideoPerRun) {
  TempDir dir("video_suite");
  fs::create_directories(dir.Path("suite"));
  for (const char* name : {"default.yaml", "wide_box.yaml"}) {
    fs::copy_file(SourcePath(std::string("scenarios/") + name), dir.Path(std::string("suite/") + name));
  }
  const std::string video = " --video --video-fps 10 --video-size 160x120";
  // 1 s of each at 10 fps: frames at 0, 0.1, ..., 1 s (the lift starts at 0.8 s).
  const CliResult suite = RunCli("suite " + dir.Path("suite") + " -j 2 --no-plots --set duration_s=1 --out " +
                                 dir.Path("out") + video);
  EXPECT_NE(suite.exit_code, kExitBadInput) << suite.out << suite.err;
  for (const char* name : {"default", "wide_box"}) {
    EXPECT_EQ(Probe(dir.Path("out/") + name + "/video.mp4"), "160,120,11") << name;
    EXPECT_TRUE(fs::exists(dir.Path("out/") + name + "/video_strip.png")) << name;
  }
  std::ofstream(dir.Path("grid.yaml"))
      << "scenario: " << SourcePath("scenarios/default.yaml")
      << "\nset: {duration_s: 1}\nparameters:\n  object.mass_kg: [0.1, 0.2]\n";
  const CliResult sweep = RunCli("sweep " + dir.Path("grid.yaml") + " --out " + dir.Path("sweep") + video);
  ASSERT_EQ(sweep.exit_code, kExitOk) << sweep.out << sweep.err;
  for (const char* run : {"run_0", "run_1"}) {
    EXPECT_EQ(Probe(dir.Path("sweep/videos/") + run + "/video.mp4"), "160,120,11") << run;
  }
}

TEST(VideoCliTest, RefusesBadVideoOptionsBeforeRunning) {
  TempDir dir("video_cli_bad");
  const std::string run =
      "run " + SourcePath("scenarios/default.yaml") + " --no-plots --out " + dir.Path("run") + " --video";
  const struct {
    std::string arguments;
    std::string message;
  } cases[] = {
      {run + " --video-size 321x240", "--video-size 321x240: width and height must be even (H.264)"},
      {run + " --video-size 640", "--video-size 640: expected WIDTHxHEIGHT in pixels, e.g. 640x480"},
      {run + " --video-fps 0", "--video-fps 0: must be in (0, 240]"},
  };
  for (const auto& c : cases) {
    const CliResult result = RunCli(c.arguments);
    EXPECT_EQ(result.exit_code, kExitBadInput) << c.arguments << "\n" << result.err;
    EXPECT_NE(result.err.find(c.message), std::string::npos) << c.arguments << "\n" << result.err;
    EXPECT_FALSE(fs::exists(dir.Path("run/summary.json"))) << c.arguments;
  }
}

// The default scenario passes; its first frames come while the sensor tares, when the controller holds
// by design: the panel says so instead of flagging SAFE-HOLD like a fault. No rendering needed: the
// panel text of each frame as the video composes it.
TEST(VideoTest, FramesOfAPassingRunSayTaringWhileTheSensorTaresNotSafeHold) {
  const testbed::ScenarioConfig config = testbed::LoadScenario(SourcePath("scenarios/default.yaml"));
  testbed::RunOptions run;
  run.frame_period_s = 1.0 / kFps;
  std::vector<std::string> panels;
  run.on_frame = [&](const testbed::FrameContext& frame) {
    const controller::ControllerTelemetry telemetry = frame.rig.controller().telemetry();
    panels.push_back(sim::PanelText(show::LivePanel(config, "default", frame, telemetry)));
  };
  const testbed::RunResult result = testbed::RunScenario(config, run);
  ASSERT_TRUE(result.passed);
  ASSERT_EQ(static_cast<int>(panels.size()), show::VideoFrameCount(config.duration_s, kFps));
  EXPECT_NE(panels.front().find("slip flags\tTARING"), std::string::npos) << panels.front();
  for (const std::string& panel : panels) EXPECT_EQ(panel.find("SAFE-HOLD"), std::string::npos) << panel;
}

TEST(VideoTest, RecordingLeavesTheRunsResultsUnchanged) {
  const testbed::ScenarioConfig config = testbed::LoadScenario(SourcePath("scenarios/default.yaml"));
  TempDir dir("video_same");
  testbed::RunOptions plain;
  plain.out_dir = dir.Path("plain");
  plain.write_plots = false;
  const testbed::RunResult without = testbed::RunScenario(config, plain);

  testbed::RunOptions recorded;
  recorded.out_dir = dir.Path("video");
  recorded.write_plots = false;
  fs::create_directories(recorded.out_dir);
  show::VideoOptions video;
  video.fps = kFps;
  video.render.width_px = kWidthPx;
  video.render.height_px = kHeightPx;
  video.strip_tiles = 0;
  const auto cost = show::AttachVideo(config, video, recorded.out_dir + "/video.mp4", "", recorded);
  const testbed::RunResult with = testbed::RunScenario(config, recorded);

  EXPECT_EQ(cost->frames, show::VideoFrameCount(config.duration_s, kFps));
  EXPECT_TRUE(fs::exists(recorded.out_dir + "/video.mp4"));
  // Every signal of every tick, and the state log, byte for byte.
  const std::string signals = ReadFile(plain.out_dir + "/signals.csv");
  ASSERT_GT(signals.size(), 1000u);
  EXPECT_TRUE(signals == ReadFile(recorded.out_dir + "/signals.csv")) << "signals.csv differs with a video";
  EXPECT_TRUE(ReadFile(plain.out_dir + "/states.csv") == ReadFile(recorded.out_dir + "/states.csv"));
  EXPECT_EQ(without.passed, with.passed);
  EXPECT_EQ(without.control_ticks, with.control_ticks);
  nlohmann::json a = testbed::SummaryJson(without);
  nlohmann::json b = testbed::SummaryJson(with);
  for (nlohmann::json* summary : {&a, &b}) {
    summary->erase("real_time_factor");
    (*summary)["metrics"].erase("wall_s");
  }
  EXPECT_EQ(a, b);
}

TEST(VideoCliTest, WithoutFfmpegSaysSoBeforeSimulating) {
  TempDir dir("video_no_ffmpeg");
  const CliResult result =
      test_support::RunCliUnder("env PATH=/nonexistent ", "run " + SourcePath("scenarios/default.yaml") +
                                                              " --out " + dir.Path("run") + " --video");
  EXPECT_EQ(result.exit_code, 1) << result.err;
  EXPECT_NE(
      result.err.find("video: the ffmpeg program ('ffmpeg') is not installed or not on PATH (on Debian: "
                      "apt-get install ffmpeg)"),
      std::string::npos)
      << result.err;
  EXPECT_FALSE(fs::exists(dir.Path("run/signals.csv")));
}

TEST(VideoWriterTest, MissingEncoderAndOddSizesAreRefusedWithAMessage) {
  TempDir dir("video_writer");
  image::VideoWriter::Options options;
  options.path = dir.Path("v.mp4");
  options.ffmpeg = "/nonexistent/ffmpeg";
  try {
    image::VideoWriter writer(options);
    ADD_FAILURE() << "no error without ffmpeg";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("apt-get install ffmpeg"), std::string::npos) << error.what();
  }
  options.ffmpeg = "ffmpeg";
  options.width_px = 641;
  EXPECT_THROW(image::VideoWriter{options}, std::invalid_argument);
  EXPECT_FALSE(fs::exists(options.path));
}

TEST(VideoWriterTest, EncodesFramesAndRefusesAFrameOfAnotherSize) {
  TempDir dir("video_frames");
  image::VideoWriter::Options options;
  options.path = dir.Path("ramp.mp4");
  options.width_px = 64;
  options.height_px = 48;
  options.fps = 25.0;
  image::VideoWriter writer(options);
  image::RgbImage frame;
  frame.width_px = 64;
  frame.height_px = 48;
  for (int i = 0; i < 7; ++i) {
    frame.rgb.assign(64 * 48 * 3, static_cast<uint8_t>(30 * i));
    writer.Write(frame);
  }
  image::RgbImage wrong = frame;
  wrong.width_px = 32;
  EXPECT_THROW(writer.Write(wrong), std::invalid_argument);
  EXPECT_FALSE(fs::exists(options.path)) << "a video in place before Finish()";
  writer.Finish();
  EXPECT_EQ(Probe(options.path), "64,48,7");
}

}  // namespace
}  // namespace graspbed

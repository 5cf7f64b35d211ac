// `graspbed render` as users run it ($GRASPBED_BINARY, no display): a still of the default scenario
// with the asked size, and bad input refused with exit 2 and a message naming it.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "common/rgb_image.h"
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

TEST(RenderCliTest, WritesOneStillOfTheDefaultScenario) {
  TempDir dir("render_cli");
  const CliResult result = RunCli("render " + SourcePath("scenarios/default.yaml") + " --at 0.5 --out " +
                                  dir.Path("stills") + " --width 160 --height 120 --contact-forces");
  ASSERT_EQ(result.exit_code, kExitOk) << result.err;
  const std::string path = dir.Path("stills/default_t0.500s.png");
  EXPECT_NE(result.out.find(path), std::string::npos) << result.out;
  EXPECT_NE(result.err.find("EGL"), std::string::npos) << result.err;
  const image::RgbImage picture = image::ReadPng(path);
  EXPECT_EQ(picture.width_px, 160);
  EXPECT_EQ(picture.height_px, 120);
  // A scene, not a blank buffer: many distinct colours.
  std::set<uint32_t> colors;
  for (size_t i = 0; i + 2 < picture.rgb.size(); i += 3) {
    colors.insert(uint32_t{picture.rgb[i]} << 16 | uint32_t{picture.rgb[i + 1]} << 8 | picture.rgb[i + 2]);
  }
  EXPECT_GT(colors.size(), 50u);
  // Nothing but the still: no run outputs, no temporary files.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.Path("stills")), fs::directory_iterator{}), 1);
}

TEST(RenderCliTest, RefusesBadInputWithExit2AndAMessage) {
  TempDir dir("render_cli_bad");
  const std::string scenario = SourcePath("scenarios/default.yaml");
  const std::string out = " --out " + dir.Path("stills");
  struct Case {
    std::string arguments;
    std::string message;
  };
  const Case cases[] = {
      {"render " + scenario + " --at 9" + out,
       "--at 9: outside the scenario default (0 .. 2.5 s, duration_s in "},
      {"render " + scenario + " --at 1 --view 1,2,3" + out, "--view 1,2,3: expected 6 numbers"},
      {"render " + scenario + " --at 1 --width 2" + out, "width_px = 2: must be in 16..4096"},
      {"render " + scenario + " --at 0.01 --camera nosuch" + out,
       "--camera nosuch: no such camera; built in: grasp, fingertip; the model has none"},
      {"render " + scenario + out, "--at is required"},
  };
  for (const Case& c : cases) {
    const CliResult result = RunCli(c.arguments);
    EXPECT_EQ(result.exit_code, kExitBadInput) << c.arguments << "\n" << result.err;
    EXPECT_NE(result.err.find(c.message), std::string::npos) << c.arguments << "\n" << result.err;
  }
  // Refused before rendering: no picture anywhere.
  EXPECT_FALSE(fs::exists(dir.Path("stills")) && !fs::is_empty(dir.Path("stills")));
}

}  // namespace
}  // namespace graspbed

// Offscreen rendering of the default scenario in-process (no display, no GPU): the holder is at the
// picture's centre when the camera looks at it and absent when it looks beside it, Project() agrees
// with the rendered pixels, and the unit pressed hardest in the pinch turns from grey to red.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "sim/render/offscreen_gl_context.h"
#include "sim/render/renderer.h"
#include "sim/sim_rig.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "tests/support/files.h"

namespace graspbed::sim {
namespace {

using graspbed::test_support::SourcePath;

// Instants of the default scenario: open hand around the box, then the pinch during the lift [s].
constexpr double kBeforeContactS = 0.12;
constexpr double kPinchS = 1.2;
// Small pictures keep the test fast; sizes chosen so a unit footprint covers several pixels.
constexpr int kWidthPx = 240;
constexpr int kHeightPx = 180;
// Half size of the pixel regions compared [px].
constexpr int kRegionHalfPx = 1;
// A loaded unit for the colour check [N] (the default pinch puts several N on the busiest unit).
constexpr double kPressedFnN = 1.0;
constexpr double kProjectionTolPx = 0.75;
// The legend needs about 200 px of height: checked at a size that has room for it.
constexpr int kLegendWidthPx = 320;
constexpr int kLegendHeightPx = 240;

struct Color {
  double r = 0.0, g = 0.0, b = 0.0;
};

/// Mean colour of the (2 h + 1)^2 pixels around (column, row); fails the test when outside the picture.
Color MeanColor(const image::RgbImage& picture, double column, double row, int h = kRegionHalfPx) {
  const int c0 = static_cast<int>(std::lround(column));
  const int r0 = static_cast<int>(std::lround(row));
  Color mean;
  if (c0 - h < 0 || r0 - h < 0 || c0 + h >= picture.width_px || r0 + h >= picture.height_px) {
    ADD_FAILURE() << "region at (" << column << ", " << row << ") outside the picture";
    return mean;
  }
  const double n = (2 * h + 1) * (2 * h + 1);
  for (int r = r0 - h; r <= r0 + h; ++r) {
    for (int c = c0 - h; c <= c0 + h; ++c) {
      const uint8_t* p = picture.At(c, r);
      mean.r += p[0] / n;
      mean.g += p[1] / n;
      mean.b += p[2] / n;
    }
  }
  return mean;
}

std::string Describe(const Color& c) {
  return "rgb(" + std::to_string(static_cast<int>(c.r)) + ", " + std::to_string(static_cast<int>(c.g)) +
         ", " + std::to_string(static_cast<int>(c.b)) + ")";
}

// The holder shell and the digits are a light beige (0.85 0.82 0.75): bright, red ~ green > blue.
bool IsHandMaterial(const Color& c) {
  return c.r > 90.0 && std::abs(c.r - c.g) < 25.0 && c.r - c.b > 3.0 && c.r - c.b < 60.0;
}
// Unit colours: grey (r = g = b) unloaded, towards pure red when loaded.
double Redness(const Color& c) { return c.r - 0.5 * (c.g + c.b); }

std::array<double, 3> HolderCenter(const Simulation& simulation) {
  const mjModel* m = simulation.model();
  const int holder = mj_name2id(m, mjOBJ_BODY, "holder");
  EXPECT_GE(holder, 0) << "the model has no body 'holder'";
  const mjtNum* p = simulation.data()->xpos + 3 * std::max(holder, 0);
  return {p[0], p[1], p[2]};
}

/// Heading of the units' mean outward normal (they face the object) [deg].
double UnitsHeadingDeg(const Simulation& simulation) {
  const mjModel* m = simulation.model();
  double x = 0.0;
  double y = 0.0;
  for (int i = 0; i < simulation.unit_count(); ++i) {
    const int geom = mj_name2id(m, mjOBJ_GEOM, ("unit_" + std::to_string(i)).c_str());
    x += simulation.data()->geom_xmat[9 * geom + 2];
    y += simulation.data()->geom_xmat[9 * geom + 5];
  }
  return std::atan2(y, x) * 180.0 / std::numbers::pi;
}

int MostLoadedUnit(const sensor::TactileState& state) {
  int best = 0;
  for (int i = 1; i < state.unit_count; ++i) {
    if (state.fn_n[i] > state.fn_n[best]) best = i;
  }
  return best;
}

class RenderTest : public ::testing::Test {
 protected:
  // One run of the default scenario to the pinch, with `at` called at both instants.
  void RunDefault(const std::function<void(double, SimRig&)>& at) {
    // The open-loop controller squeezes at its full effort: about 2 N on each unit the box touches
    // (the reference controller holds the 100 g box with about 0.3 N per unit).
    const testbed::ScenarioConfig config =
        testbed::LoadScenario(SourcePath("scenarios/default.yaml"), {{"controller.name", "open_loop"}});
    testbed::RunOptions run;
    run.instants_s = {kBeforeContactS, kPinchS};
    run.stop_after_instants = true;
    run.at_instant = at;
    testbed::RunScenario(config, run);
  }

  Renderer& RendererFor(SimRig& rig, double object_alpha) {
    if (!renderer_) {
      RenderOptions options;
      options.width_px = kWidthPx;
      options.height_px = kHeightPx;
      options.object_alpha = object_alpha;
      renderer_ = std::make_unique<Renderer>(gl_, rig.simulation(), options);
    }
    return *renderer_;
  }

  OffscreenGlContext gl_;
  std::unique_ptr<Renderer> renderer_;
};

TEST_F(RenderTest, HolderIsWhereTheCameraLooksAndNotBeside) {
  int pictures = 0;
  RunDefault([&](double instant_s, SimRig& rig) {
    if (instant_s != kBeforeContactS) return;
    Simulation& simulation = rig.simulation();
    Renderer& renderer = RendererFor(rig, RenderOptions{}.object_alpha);
    // From the back of the finger (opposite the units), level, 6 cm away: the holder shell fills the
    // centre of the picture.
    CameraSpec camera;
    camera.kind = CameraSpec::Kind::kFree;
    camera.free.azimuth_deg = UnitsHeadingDeg(simulation);
    camera.free.elevation_deg = -10.0;
    camera.free.distance_m = 0.06;
    camera.free.lookat_m = HolderCenter(simulation);
    const image::RgbImage& on = renderer.Render(simulation, &rig.loop().state(), camera);
    const Color center = MeanColor(on, 0.5 * kWidthPx, 0.5 * kHeightPx, 2);
    EXPECT_TRUE(IsHandMaterial(center)) << "picture centre is " << Describe(center) << ", not the holder";
    const std::optional<std::array<double, 2>> pixel = renderer.Project(camera.free.lookat_m);
    ASSERT_TRUE(pixel.has_value());
    EXPECT_NEAR((*pixel)[0], 0.5 * kWidthPx, kProjectionTolPx);
    EXPECT_NEAR((*pixel)[1], 0.5 * kHeightPx, kProjectionTolPx);

    // The same camera turned to look 8 cm above the hand: nothing of the hand at the centre.
    camera.free.lookat_m[2] += 0.08;
    camera.free.elevation_deg = 30.0;
    const image::RgbImage& beside = renderer.Render(simulation, &rig.loop().state(), camera);
    const Color empty = MeanColor(beside, 0.5 * kWidthPx, 0.5 * kHeightPx, 2);
    EXPECT_FALSE(IsHandMaterial(empty)) << "looking away, the centre is still " << Describe(empty);
    ++pictures;
  });
  EXPECT_EQ(pictures, 1);
}

TEST_F(RenderTest, PressedUnitTurnsFromGreyToRedWhereProjectSays) {
  // Fingertip close-up with the object left out, at both instants; regions where Project() puts each
  // unit's centre.
  std::vector<Color> before;
  bool before_valid = false;
  int pressed = -1;
  double pressed_fn = 0.0;
  Color during;
  RunDefault([&](double instant_s, SimRig& rig) {
    Simulation& simulation = rig.simulation();
    const sensor::TactileState& state = rig.loop().state();
    Renderer& renderer = RendererFor(rig, 0.0);
    const image::RgbImage& picture = renderer.Render(simulation, &state, CameraByName("fingertip"));
    if (instant_s == kBeforeContactS) {
      before_valid = state.valid_count == state.unit_count;
      for (int i = 0; i < simulation.unit_count(); ++i) {
        const std::optional<std::array<double, 2>> pixel =
            renderer.Project(renderer.UnitCenter(simulation, i));
        ASSERT_TRUE(pixel.has_value()) << "unit " << i;
        before.push_back(MeanColor(picture, (*pixel)[0], (*pixel)[1]));
      }
      return;
    }
    pressed = MostLoadedUnit(state);
    pressed_fn = state.fn_n[pressed];
    const std::optional<std::array<double, 2>> pixel =
        renderer.Project(renderer.UnitCenter(simulation, pressed));
    ASSERT_TRUE(pixel.has_value());
    during = MeanColor(picture, (*pixel)[0], (*pixel)[1]);
  });
  ASSERT_TRUE(before_valid) << "units not all valid (tared) before contact";
  ASSERT_GE(pressed, 0);
  ASSERT_GT(pressed_fn, kPressedFnN) << "no unit pressed in the pinch";
  const Color& grey = before[static_cast<size_t>(pressed)];
  EXPECT_LT(std::abs(Redness(grey)), 15.0) << "unit " << pressed << " before contact: " << Describe(grey);
  EXPECT_GT(grey.r, 80.0) << "unit " << pressed << " before contact: " << Describe(grey)
                          << " (not lit or hidden)";
  EXPECT_GT(Redness(during), Redness(grey) + 40.0)
      << "unit " << pressed << " at " << pressed_fn << " N: " << Describe(during) << ", before "
      << Describe(grey);
}

bool IsCrossYellow(const uint8_t* p) { return p[0] > 170 && p[1] > 140 && p[2] < 100; }
bool IsLegendRed(const uint8_t* p) { return p[0] > 200 && p[1] < 50 && p[2] < 50; }
bool IsLegendMagenta(const uint8_t* p) { return p[0] > 200 && p[1] < 50 && p[2] > 200; }

/// Pixels of `picture` in the box [c0, c1) x [r0, r1) for which `test` holds.
int CountPixels(const image::RgbImage& picture, int c0, int c1, int r0, int r1,
                bool (*test)(const uint8_t*)) {
  int count = 0;
  for (int r = std::max(r0, 0); r < std::min(r1, picture.height_px); ++r) {
    for (int c = std::max(c0, 0); c < std::min(c1, picture.width_px); ++c)
      count += test(picture.At(c, r)) ? 1 : 0;
  }
  return count;
}

TEST_F(RenderTest, UnusableUnitIsCrossedAndTheLegendShowsTheScale) {
  // The pinch, with the pressed unit's estimate declared unusable (as an open circuit would make it).
  int pressed = -1;
  int yellow_on_unit = 0;
  int yellow_before = 0;
  int legend_red = 0;
  int legend_magenta = 0;
  int legend_off_red = 0;
  RunDefault([&](double instant_s, SimRig& rig) {
    if (instant_s != kPinchS) return;
    Simulation& simulation = rig.simulation();
    sensor::TactileState state = rig.loop().state();
    pressed = MostLoadedUnit(state);
    Renderer& renderer = RendererFor(rig, 0.0);
    const CameraSpec camera = CameraByName("fingertip");
    const auto yellow_near_unit = [&](const image::RgbImage& picture) {
      const std::optional<std::array<double, 2>> pixel =
          renderer.Project(renderer.UnitCenter(simulation, pressed));
      if (!pixel) return -1;
      const int c = static_cast<int>((*pixel)[0]);
      const int r = static_cast<int>((*pixel)[1]);
      return CountPixels(picture, c - 4, c + 5, r - 4, r + 5, IsCrossYellow);
    };
    yellow_before = yellow_near_unit(renderer.Render(simulation, &state, camera));
    state.validity[pressed] = sensor::UnitValidity::kOpen;
    const image::RgbImage& crossed = renderer.Render(simulation, &state, camera);
    yellow_on_unit = yellow_near_unit(crossed);
    // The legend sits in the bottom-right third: its bar reaches full red, its swatch is magenta
    // (a picture of 240 x 180 is too small for it: left out).
    RenderOptions legend;
    legend.width_px = kLegendWidthPx;
    legend.height_px = kLegendHeightPx;
    legend.object_alpha = 0.0;
    const auto corner = [](const image::RgbImage& picture, bool (*test)(const uint8_t*)) {
      return CountPixels(picture, 2 * kLegendWidthPx / 3, kLegendWidthPx, kLegendHeightPx / 3,
                         kLegendHeightPx, test);
    };
    Renderer with_legend(gl_, simulation, legend);
    const image::RgbImage& shown = with_legend.Render(simulation, &state, camera);
    legend_red = corner(shown, IsLegendRed);
    legend_magenta = corner(shown, IsLegendMagenta);
    legend.legend = false;
    Renderer without_legend(gl_, simulation, legend);
    legend_off_red = corner(without_legend.Render(simulation, &state, camera), IsLegendRed);
  });
  ASSERT_GE(pressed, 0);
  EXPECT_EQ(yellow_before, 0) << "unit " << pressed << " crossed while valid";
  EXPECT_GT(yellow_on_unit, 2) << "no yellow cross on unusable unit " << pressed;
  EXPECT_GT(legend_red, 4);
  EXPECT_GT(legend_magenta, 4);
  EXPECT_EQ(legend_off_red, 0);
}

TEST(PanelTextTest, SaysTimePhaseGripFrictionFlagsAndTheLastAction) {
  controller::ControllerTelemetry telemetry;
  telemetry.phase = "holding";
  telemetry.grip_target_n = 2.5;
  telemetry.friction_estimate = 0.42;
  telemetry.slip_detected = true;
  telemetry.slip_cues = "ratio";
  sensor::TactileState state;
  state.total_fn_n = 3.25;
  state.contact_count = 4;
  state.valid_count = 19;
  PanelInfo panel;
  panel.title = "default (grip_slip)";
  panel.time_s = 1.2345;
  panel.telemetry = &telemetry;
  panel.state = &state;
  panel.last_action = "lift at 0.800 s (line 17)";
  EXPECT_EQ(PanelText(panel),
            "default (grip_slip)\t\ntime\t1.234 s\nphase\tholding\ngrip target\t2.50 N\n"
            "measured grip\t3.25 N on 4 units (19 valid)\nfriction est.\t0.42\nslip flags\tSLIP (ratio)\n"
            "last action\tlift at 0.800 s (line 17)");
  telemetry.slip_detected = false;
  panel.last_action = "";
  panel.title.clear();
  const std::string quiet = PanelText(panel);
  EXPECT_NE(quiet.find("slip flags\t-\nlast action\t-"), std::string::npos) << quiet;
  panel.last_action.reset();
  EXPECT_EQ(PanelText(panel).find("last action"), std::string::npos);
}

TEST(UnitColorTest, GreyUnloadedRedAtRatedMagentaSaturatedBlackUnusable) {
  using sensor::UnitValidity;
  const std::array<float, 4> zero = UnitColor(0.0, UnitValidity::kValid, 10.0);
  EXPECT_FLOAT_EQ(zero[0], zero[1]);
  EXPECT_FLOAT_EQ(zero[1], zero[2]);
  EXPECT_EQ(UnitColor(-1.0, UnitValidity::kValid, 10.0), zero);
  const std::array<float, 4> rated = UnitColor(10.0, UnitValidity::kValid, 10.0);
  EXPECT_GT(rated[0], 0.9f);
  EXPECT_LT(rated[1], 0.1f);
  EXPECT_EQ(UnitColor(25.0, UnitValidity::kValid, 10.0), rated);
  // Square-root scale: a quarter of the range is half way.
  const std::array<float, 4> quarter = UnitColor(2.5, UnitValidity::kValid, 10.0);
  EXPECT_NEAR(quarter[0], 0.5f * (zero[0] + rated[0]), 1e-6);
  const std::array<float, 4> saturated = UnitColor(12.0, UnitValidity::kOutOfRange, 10.0);
  EXPECT_GT(saturated[2], 0.8f);
  for (UnitValidity v :
       {UnitValidity::kOpen, UnitValidity::kShort, UnitValidity::kImplausible, UnitValidity::kNotTared}) {
    EXPECT_LT(UnitColor(3.0, v, 10.0)[0], 0.1f);
  }
}

TEST(FreeViewTest, ParsesSixNumbersAndNamesWhatIsWrong) {
  const FreeView view = ParseFreeView("150,-20,0.3,0,0.01,0.05");
  EXPECT_DOUBLE_EQ(view.azimuth_deg, 150.0);
  EXPECT_DOUBLE_EQ(view.elevation_deg, -20.0);
  EXPECT_DOUBLE_EQ(view.distance_m, 0.3);
  EXPECT_DOUBLE_EQ(view.lookat_m[1], 0.01);
  EXPECT_DOUBLE_EQ(view.lookat_m[2], 0.05);
  const auto message = [](const std::string& text) {
    try {
      ParseFreeView(text);
    } catch (const std::invalid_argument& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(
      message("1,2,3"),
      "--view 1,2,3: expected 6 numbers azimuth,elevation,distance,x,y,z (deg, deg, m, m, m, m), got 3");
  EXPECT_EQ(message("1,2,x,0,0,0"), "--view 1,2,x,0,0,0: distance 'x' is not a number");
  EXPECT_EQ(message("0,90,0.3,0,0,0"), "--view 0,90,0.3,0,0,0: elevation 90 must be in (-90, 90) deg");
  EXPECT_EQ(message("0,0,-1,0,0,0"), "--view 0,0,-1,0,0,0: distance -1 must be > 0 m");
  EXPECT_EQ(message("0,0,1,0,0,"), "--view 0,0,1,0,0,: lookat '' is not a number");
}

TEST(RenderOptionsTest, RefusesSizesAndAlphaOutOfRange) {
  RenderOptions options;
  options.width_px = 8;
  EXPECT_THROW(options.Validate(), std::invalid_argument);
  options = RenderOptions{};
  options.object_alpha = 1.5;
  EXPECT_THROW(options.Validate(), std::invalid_argument);
  EXPECT_NO_THROW(RenderOptions{}.Validate());
}

}  // namespace
}  // namespace graspbed::sim

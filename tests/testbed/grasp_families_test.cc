// Each shape family closed on at its oracle grip (the lightest constant grip that holds it, found by
// `graspbed oracle`'s search), lifted and held: held, its acquisition shift within the family's bound,
// the pad's mesas carrying the squeeze, the placement the generator prints; users' STL parts lifted
// and held on the pad by the reference controller; and the strawman for grasped_on_sensor.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>

#include "sensor/layout.h"
#include "sim/model_generator.h"
#include "testbed/metrics.h"
#include "testbed/oracle.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace graspbed::testbed {
namespace {

/// The default lift: close at 0.15 s, lift 50 mm from 0.8 s over 0.8 s, held to 2.5 s.
std::string LiftScenario(const std::string& object_yaml, const std::string& hand_yaml = "") {
  return "name: family\nseed: 1\nduration_s: 2.5\nobject: " + object_yaml + "\n" +
         (hand_yaml.empty() ? "" : "hand: " + hand_yaml + "\n") +
         "sensor: {profile: ideal}\ncontroller: {name: grip_slip}\nscript:\n"
         "  - {at_s: 0.15, action: close}\n"
         "  - {at_s: 0.8, action: lift, height_m: 0.05, duration_s: 0.8}\n"
         "expectations: {not_dropped: true, max_slip_mm: 2.0}\n";
}

std::string MeshObject(const std::string& file) {
  return "{mesh: " + std::string(GRASPBED_SOURCE_DIR) + "/tests/sim/meshes/" + file +
         ", scale: 0.001, mass_kg: 0.1, friction: 0.8}";
}

const sensor::Layout& DefaultLayout() {
  static const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  return layout;
}

struct Family {
  const char* name;
  std::string object;
  std::string hand;
  double max_acquisition_shift_mm;  ///< what the close may move it (measured, with margin)
  const char* placement;            ///< what `graspbed model --kinematics` prints for it
};

// The shape families: a box, a cylinder, a sphere, an egg, a banana, a mug, a glass, a cup, a
// wrapped can and a user's mesh.
TEST(GraspFamilyTest, EachShapeFamilyIsHeldOnThePadAtItsOracleGrip) {
  const Family families[] = {
      {"box", "{shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.8}", "", 1.0,
       "placement: faces pinch its parallel faces"},
      {"cylinder", "{name: marker}", "{pinch_square_pad: true}", 2.0, "placement: faces pinch its parallel faces"},
      {"sphere", "{name: tennis_ball}", "", 1.0, "placement: round pinch through its centre"},
      {"egg", "{name: egg}", "", 1.0, "placement: round pinch through its equator"},
      {"banana", "{name: banana}", "", 2.0, "placement: round pinch through its middle, across its thickness"},
      {"mug", "{name: mug}", "", 3.0, "wrap: palm sideways"},
      {"glass", "{name: wine_glass}", "", 1.0, "placement: faces pinch its most nearly parallel faces"},
      {"cup", "{name: plastic_cup}", "", 2.0, "placement: faces pinch its most nearly parallel faces"},
      {"wrapped can", "{name: can}", "", 3.0, "wrap: palm sideways"},
      {"mesh", MeshObject("hex_bar_45x60.stl"), "", 1.0, "placement: faces pinch its most nearly parallel faces"},
  };
  std::printf("[ measure ] family       oracle N  setpoint N  slip mm  acquisition mm  sensed share  unit\n");
  for (const Family& family : families) {
    SCOPED_TRACE(family.name);
    const ScenarioConfig scenario =
        LoadScenarioFromString(LiftScenario(family.object, family.hand), std::string(family.name) + ".yaml");
    const OracleSearch oracle = FindOracleGrip(scenario);
    ASSERT_TRUE(oracle.grip.grip_n.has_value()) << oracle.grip.reason;
    const RunResult run = RunScenario(OracleStepConfig(scenario, *oracle.setpoint_n));
    const Metrics& m = run.metrics;
    std::printf("[ measure ] %-12s %8.2f  %10.3f  %7.2f  %14.2f  %12.2f  %4d\n", family.name, *oracle.grip.grip_n,
                *oracle.setpoint_n, m.max_slip_mm, m.acquisition_shift_mm, m.sensed_grip_share.value_or(0.0),
                m.contact_unit);
    EXPECT_TRUE(m.grasped);
    EXPECT_FALSE(m.dropped);
    EXPECT_EQ(m.gross.events, 0);
    EXPECT_LE(m.acquisition_shift_mm, family.max_acquisition_shift_mm);
    ASSERT_TRUE(m.sensed_grip_share.has_value());
    EXPECT_GE(*m.sensed_grip_share, 0.25) << "the squeeze on the mesas";
    EXPECT_GE(m.contact_unit, 0);
    const std::string described = sim::DescribeHand(DefaultLayout(), scenario.scene);
    EXPECT_NE(described.find(family.placement), std::string::npos) << described;
  }
}

// `graspbed model --kinematics` says which friction the object's contacts get: auto follows the
// object's stiffness (the default box keeps 1000, the 5e4 N/m apple 20, the 500 N/m foam brick 10),
// a number in the scene replaces it.
TEST(GraspFamilyTest, TheKinematicsSayWhichImpratioTheObjectsContactsGet) {
  const auto line = [](const std::string& scene_yaml) {
    const ScenarioConfig scenario = LoadScenarioFromString(
        scene_yaml + "controller: {name: constant_grip}\nscript:\n  - {at_s: 0.1, action: close}\n", "k.yaml");
    const std::string described = sim::DescribeHand(DefaultLayout(), scenario.scene);
    const size_t at = described.find("object contacts:");
    return at == std::string::npos ? std::string() : described.substr(at, described.find('\n', at) - at);
  };
  EXPECT_EQ(line(""), "object contacts: condim 4, impratio 1000 (auto, the object's stiffness 2.5e+06 N/m)");
  EXPECT_EQ(line("object: {name: apple}\n"), "object contacts: condim 4, impratio 20 (auto, the object's stiffness 50000 N/m)");
  EXPECT_EQ(line("object: {name: foam_brick}\n"), "object contacts: condim 4, impratio 10 (auto, the object's stiffness 500 N/m)");
  EXPECT_EQ(line("object: {name: apple}\nphysics: {impratio: 300}\n"), "object contacts: condim 4, impratio 300");
}

// Users' parts from STL files, several shapes and heights, each with its origin at a corner as CAD
// exports them: lifted by the reference controller and held on the pad.
TEST(GraspFamilyTest, UsersStlPartsAreLiftedAndHeldOnThePad) {
  for (const char* file : {"block_50x50x80.stl", "hex_bar_45x60.stl", "puck_40x40x30.stl", "wedge_60x70.stl"}) {
    SCOPED_TRACE(file);
    const ScenarioConfig scenario = LoadScenarioFromString(LiftScenario(MeshObject(file)), "stl.yaml");
    const RunResult run = RunScenario(scenario);
    const Metrics& m = run.metrics;
    std::printf("[ measure ] %-20s slip %.2f mm, acquisition %.2f mm, peak %.2f N, sensed share %.2f, unit %d\n",
                file, m.max_slip_mm, m.acquisition_shift_mm, m.peak_grip_n, m.sensed_grip_share.value_or(0.0),
                m.contact_unit);
    EXPECT_TRUE(run.passed);
    EXPECT_FALSE(m.dropped);
    for (const ExpectationOutcome& outcome : run.outcomes) {
      if (outcome.name == "grasped_on_sensor") {
        EXPECT_TRUE(outcome.passed) << outcome.note;
      }
    }
  }
}

// The strawman: the default box met 15.6 mm lower than the generator places it (the wrist moved by
// an override, as a hand-placed scene would) is held by the fingertip's cap and the middle phalanx,
// the units feeling little of it: grasped_on_sensor fails, though the box is lifted and not
// dropped; placed by the generator, the same scene passes.
TEST(GraspFamilyTest, ABoxMetOffThePadFailsGraspedOnSensorAndPlacedByTheGeneratorPasses) {
  const std::string box = "{shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.8}";
  const ScenarioConfig placed = LoadScenarioFromString(LiftScenario(box), "placed.yaml");
  const double wrist_z = sim::PlaceHand(DefaultLayout(), placed.scene).wrist_position_m[2];
  const ScenarioConfig lowered = LoadScenarioFromString(
      LiftScenario(box, "{initial_wrist_position_m: [0, 0, " + std::to_string(wrist_z - 0.0156) + "]}"),
      "lowered.yaml");
  for (const auto& [config, on_pad] : {std::pair{&placed, true}, {&lowered, false}}) {
    const RunResult run = RunScenario(*config);
    const Metrics& m = run.metrics;
    std::printf("[ measure ] %s: sensed share %.2f, unsensed %.3f s of %.2f s held, dropped %d\n",
                on_pad ? "placed" : "lowered 15.6 mm", m.sensed_grip_share.value_or(0.0), m.unsensed_held_s,
                m.held_s, m.dropped ? 1 : 0);
    EXPECT_FALSE(m.dropped);
    bool checked = false;
    for (const ExpectationOutcome& outcome : run.outcomes) {
      if (outcome.name != "grasped_on_sensor") continue;
      checked = true;
      EXPECT_EQ(outcome.passed, on_pad) << outcome.value_text << " -- " << outcome.note;
    }
    EXPECT_TRUE(checked);
  }
}

// The shipped object scenarios: each one's oracle against its load bound (the largest of the hand's
// load over 2 mu while held at the oracle grip: the least any two-contact grip could hold it with)
// and the sensed share at the oracle grip, printed as a table. The oracle is within 4x the load
// bound for each but the listed; a pinch's share is at least 0.6 but for the listed.
TEST(GraspFamilyTest, TheShippedObjectScenariosOraclesAgainstTheirLoadBoundsAndSensedShares) {
  // Measured; docs/notes/2026-11-28-grasps-on-the-sensor.md.
  const std::map<std::string, std::string> ratio_exceptions = {
      {"lift_plastic_cup",
       "the 3 g cup's load bound is 0.10 N; its oracle, 1.46 N, is the lightest squeeze the mesas carry "
       "a quarter of: the 2e3 N/m cup sinks 0.5 mm (the mesas' height) at 1 N, and lighter grips "
       "hold it on the holder's shell between them"},
  };
  const std::map<std::string, std::string> share_exceptions = {
      {"lift_plastic_cup", "the compliant cup (2e3 N/m) sinks past the 0.5 mm mesas onto the holder"},
  };
  std::printf("[ measure ] scenario           grasp  oracle N  load bound N  ratio  sensed share\n");
  for (const char* name : {"carry_egg", "lift_can", "lift_mug", "lift_plastic_cup", "pick_card", "pick_marker",
                           "pour_bottle", "hold_foam_brick", "wrap_cylinder"}) {
    SCOPED_TRACE(name);
    const ScenarioConfig scenario =
        LoadScenario(std::string(GRASPBED_SOURCE_DIR) + "/scenarios/" + name + ".yaml", {});
    const OracleSearch oracle = FindOracleGrip(scenario);
    ASSERT_TRUE(oracle.grip.grip_n.has_value()) << oracle.grip.reason;
    const RunResult run = RunScenario(OracleStepConfig(scenario, *oracle.setpoint_n));
    const Metrics& m = run.metrics;
    const double ratio = *oracle.grip.grip_n / m.peak_load_bound_grip_n;
    const bool wrap = scenario.scene.hand.grasp == sim::GraspType::kWrap;
    std::printf("[ measure ] %-18s %-5s  %8.2f  %12.2f  %5.2f  %12.2f\n", name, wrap ? "wrap" : "pinch",
                *oracle.grip.grip_n, m.peak_load_bound_grip_n, ratio, m.sensed_grip_share.value_or(0.0));
    if (!ratio_exceptions.contains(name)) {
      EXPECT_LE(ratio, 4.0);
    }
    if (!wrap && !share_exceptions.contains(name)) {
      EXPECT_GE(m.sensed_grip_share.value_or(0.0), 0.6);
    }
  }
  for (const auto& [name, why] : ratio_exceptions) std::printf("[ not yet ] ratio of %s: %s\n", name.c_str(), why.c_str());
  for (const auto& [name, why] : share_exceptions) std::printf("[ not yet ] share of %s: %s\n", name.c_str(), why.c_str());
}

// The default scenario's lift with each library object by name and nothing else changed: the oracle
// grip of each, printed as a table; at most 10 N for each but the listed.
TEST(GraspFamilyTest, TheDefaultLiftOfEachLibraryObjectByNameHasAnOracleGripOfAtMostTenNewtons) {
  // Measured; docs/notes/2026-11-28-grasps-on-the-sensor.md.
  const std::map<std::string, std::string> not_yet = {
      {"bottle", "the full 470 g bottle (mu 0.45) wrapped: 12.4 N; its pad meets it at its first mesa row"},
  };
  const std::string library_objects[] = {"can",   "bottle",      "bottle_half", "mug",    "marker",
                                         "card",  "banana",      "tennis_ball", "apple",  "egg",
                                         "plastic_cup", "foam_brick", "wine_glass"};
  std::printf("[ measure ] object       grasp  oracle N  weight / (2 mu) N\n");
  int within = 0;
  for (const std::string& name : library_objects) {
    SCOPED_TRACE(name);
    const std::string text =
        "name: lift_" + name + "\nseed: 1\nduration_s: 2.5\nobject: {name: " + name +
        "}\nsensor: {profile: inamp_16bit}\ncontroller: {name: grip_slip}\nscript:\n"
        "  - {at_s: 0.15, action: close}\n  - {at_s: 0.8, action: lift, height_m: 0.05, duration_s: 0.8}\n";
    const ScenarioConfig scenario = LoadScenarioFromString(text, name + ".yaml");
    const OracleSearch oracle = FindOracleGrip(scenario);
    const bool wrap = scenario.scene.hand.grasp == sim::GraspType::kWrap;
    const double bound = scenario.scene.object.mass_kg * 9.81 / (2.0 * scenario.scene.object.friction);
    std::printf("[ measure ] %-12s %-5s  %8s  %17.2f\n", name.c_str(), wrap ? "wrap" : "pinch",
                oracle.grip.grip_n ? std::to_string(*oracle.grip.grip_n).substr(0, 5).c_str() : "none", bound);
    const bool ok = oracle.grip.grip_n && *oracle.grip.grip_n <= 10.0;
    within += ok ? 1 : 0;
    if (!not_yet.contains(name)) {
      EXPECT_TRUE(ok) << oracle.grip.reason;
    } else {
      EXPECT_FALSE(ok) << name << " now has an oracle grip of at most 10 N: take it off the list";
    }
  }
  std::printf("[ measure ] %d of 13 with an oracle grip of at most 10 N\n", within);
  for (const auto& [name, why] : not_yet) std::printf("[ not yet ] %s: %s\n", name.c_str(), why.c_str());
}

}  // namespace
}  // namespace graspbed::testbed

// Scene files: values read with units, bad input named by file, line, key and value.
#include <gtest/gtest.h>

#include <string>

#include "common/yaml_map.h"
#include "sim/scene_config.h"

namespace graspbed::sim {
namespace {

SceneConfig Load(const std::string& text) {
  return LoadSceneConfig(common::YamlMap::LoadString(text, "scene.yaml"));
}

std::string ErrorOf(const std::string& text) {
  try {
    Load(text);
  } catch (const common::ConfigError& error) {
    return error.what();
  }
  return "";
}

TEST(SceneConfigTest, ReadsEverySection) {
  const SceneConfig scene = Load(
      "object:\n  shape: cylinder\n  size_m: [0.04, 0, 0.1]\n  mass_kg: 0.2\n  friction: 0.5\n"
      "hand:\n  open_gap_m: 0.08\n  motor:\n    stall_force_n: 25\n"
      "physics:\n  noslip_iterations: 0\n  timestep_s: 0.001\n");
  EXPECT_EQ(scene.object.shape, ObjectShape::kCylinder);
  EXPECT_DOUBLE_EQ(scene.object.size_m[2], 0.1);
  EXPECT_DOUBLE_EQ(scene.object.mass_kg, 0.2);
  EXPECT_DOUBLE_EQ(scene.hand.open_gap_m, 0.08);
  EXPECT_DOUBLE_EQ(scene.hand.motor.stall_force_n, 25.0);
  EXPECT_EQ(scene.physics.noslip_iterations, 0);
  EXPECT_DOUBLE_EQ(scene.object.RestHalfHeightM(), 0.05);
}

TEST(SceneConfigTest, BadValuesNameFileLineKeyAndValue) {
  EXPECT_EQ(ErrorOf("object:\n  mass_kg: -0.1\n").rfind("scene.yaml:2: object.mass_kg = -0.1", 0), 0u)
      << ErrorOf("object:\n  mass_kg: -0.1\n");
  const std::string shape = ErrorOf("object:\n  shape: cube\n");
  EXPECT_NE(shape.find("object.shape = cube"), std::string::npos) << shape;
  EXPECT_NE(shape.find("box"), std::string::npos) << shape;
  const std::string typo = ErrorOf("hand:\n  motor:\n    stall_torque: 3\n");
  EXPECT_NE(typo.find("hand.motor.stall_torque"), std::string::npos) << typo;
  const std::string timeconst = ErrorOf("object:\n  solref_timeconst_s: 0.0005\n");
  EXPECT_NE(timeconst.find("solref_timeconst_s"), std::string::npos) << timeconst;
  EXPECT_NE(timeconst.find("timestep"), std::string::npos) << timeconst;
  const std::string condim = ErrorOf("physics:\n  condim: 5\n");
  EXPECT_NE(condim.find("physics.condim = 5"), std::string::npos) << condim;
  const std::string object_condim = ErrorOf("object:\n  condim: 5\n");
  EXPECT_NE(object_condim.find("object.condim = 5"), std::string::npos) << object_condim;
}

// Cross-field rules are the scene's field table's: loading places them at the blamed key's line
// (or its section's, when the file leaves the key at its default); Validate() names the key path.
TEST(SceneConfigTest, CrossFieldRulesNameTheLineOfTheKeyTheyBlame) {
  EXPECT_EQ(ErrorOf("object:\n  mass_kg: 0.2\n  solref_timeconst_s: 0.0005\n"),
            "scene.yaml:3: object.solref_timeconst_s = 0.0005: must be >= 2 x physics.timestep_s");
  EXPECT_EQ(ErrorOf("physics:\n  timestep_s: 0.002\n"),
            "scene.yaml: object.solref_timeconst_s = 0.002 (default): must be >= 2 x physics.timestep_s");
  EXPECT_EQ(ErrorOf("object:\n  size_m: [0.05, 0.0005, 0.08]\n"),
            "scene.yaml:2: object.size_m[1] = 0.0005: must be in [0.001, 0.3]");
  EXPECT_EQ(
      ErrorOf("hand:\n  open_gap_m: 0.02\n").rfind("scene.yaml:2: hand.open_gap_m = 0.02: the pre-shape", 0),
      0u);
  // A wrap is built for the prosthetic hand around an upright cylinder, and opens by its clearance.
  EXPECT_EQ(ErrorOf("hand:\n  grasp: wrap\n"),
            "scene.yaml:2: hand.grasp = wrap: needs an upright cylinder, a bottle or a mug (by its body), not "
            "object.shape box");
  EXPECT_EQ(ErrorOf("object:\n  shape: cylinder\nhand:\n  model: jaw\n  grasp: wrap\n"),
            "scene.yaml:5: hand.grasp = wrap: needs hand.model prosthetic (the jaw fixture only pinches)");
  EXPECT_EQ(ErrorOf("object:\n  shape: cylinder\nhand:\n  grasp: wrap\n  open_gap_m: 0.08\n"),
            "scene.yaml:5: hand.open_gap_m = 0.08: is the pinch's aperture; a wrap opens each digit by "
            "hand.preshape_clearance_m");
  SceneConfig scene;
  scene.object.mass_kg = 20.0;
  try {
    scene.Validate();
    FAIL() << "no error";
  } catch (const common::ConfigError& error) {
    EXPECT_EQ(error.key(), "scene.object.mass_kg");
    EXPECT_STREQ(error.what(), "scene.object.mass_kg = 20: must be <= 10");
  }
}

}  // namespace
}  // namespace graspbed::sim

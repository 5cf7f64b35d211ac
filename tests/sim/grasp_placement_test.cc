// Where the pinch meets the object (sim/grasp_placement.h): the placement for each shape family, as
// a function a test calls without building the scene, and the objects it refuses.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "sensor/layout.h"
#include "sim/grasp_placement.h"
#include "sim/model_generator.h"
#include "common/yaml_map.h"
#include "sim/object_shapes.h"

namespace graspbed::sim {
namespace {

const sensor::Layout& DefaultLayout() {
  static const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  return layout;
}

ProstheticKinematics Kinematics(const SceneConfig& scene) {
  const sensor::Layout& layout = DefaultLayout();
  return ProstheticKinematics(scene.hand.finger, scene.hand.thumb, layout.holder.length_m,
                              0.5 * layout.holder.minor_axis_m, layout.unit.mesa_height_m);
}

SceneConfig SceneFrom(const std::string& yaml) {
  return LoadSceneConfig(common::YamlMap::LoadString(yaml, "scene.yaml"));
}

// A library object by name, nothing else set: the scene a scenario naming it gets.
SceneConfig Library(const std::string& name) { return SceneFrom("object: {name: " + name + "}\n"); }

// One of the STL parts of tests/sim/meshes (mm), as a user's scene names it.
SceneConfig Mesh(const std::string& file, double friction = 0.8) {
  return SceneFrom("object: {mesh: " + std::string(GRASPBED_SOURCE_DIR) + "/tests/sim/meshes/" + file +
                   ", scale: 0.001, mass_kg: 0.1, friction: " + std::to_string(friction) + "}\n");
}

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(GraspPlacementTest, BoxesAndCylindersKeepThePinchTheHandAlwaysMade) {
  SceneConfig box;  // the default 50 x 50 x 80 mm box
  const PinchPlacement placed = PlacePinch(box, Kinematics(box));
  EXPECT_EQ(placed.kind, PinchKind::kFaces);
  EXPECT_DOUBLE_EQ(placed.height_m, 0.08 - 0.013);
  EXPECT_DOUBLE_EQ(placed.width_m, 0.05);
  EXPECT_DOUBLE_EQ(placed.centre_x_m, 0.0);
  SceneConfig marker = Library("marker");
  EXPECT_DOUBLE_EQ(PlacePinch(marker, Kinematics(marker)).height_m, 0.121 - 0.013);
}

// A ball, an egg at its equator and a banana across its middle: the pad's normal and the thumb tip's
// centre on one line through the section's centre, the pad's contact moved tipwards only where the
// table asks (the 36 mm banana), the fingertip above the table.
TEST(GraspPlacementTest, RoundSectionsArePinchedThroughTheirCentreOnOneLine) {
  for (const char* name : {"tennis_ball", "apple", "egg", "banana"}) {
    SCOPED_TRACE(name);
    const SceneConfig scene = Library(name);
    const ProstheticKinematics kin = Kinematics(scene);
    const PinchPlacement placed = PlacePinch(scene, kin);
    ASSERT_EQ(placed.kind, PinchKind::kRound);
    const RoundSection section = *PinchRoundSection(scene.object);
    EXPECT_NEAR(placed.height_m, scene.object.StartCentreZM() + section.centre_m.z(), 1e-12);
    EXPECT_NEAR(placed.width_m, 2.0 * section.radius_m, 1e-12);
    const RoundPinchPose& pose = placed.round;
    const DigitContact pad = kin.IndexPadAt(pose.mcp_rad, placed.along_pad_m);
    const Eigen::Vector2d normal(std::cos(pad.normal_angle_rad), std::sin(pad.normal_angle_rad));
    EXPECT_NEAR((pose.centre_xz - pad.point_xz).dot(normal), section.radius_m, 1e-6);
    const Eigen::Vector2d to_thumb = kin.ThumbTipCentre(pose.thumb_rad) - pose.centre_xz;
    EXPECT_NEAR(to_thumb.norm(), section.radius_m + scene.hand.thumb.tip_radius_m, 1e-6);
    EXPECT_NEAR(to_thumb.normalized().dot(normal), 1.0, 1e-9) << "collinear, beyond the centre from the pad";
    const double wrist_z = placed.height_m - pose.centre_xz.y();
    EXPECT_GE(wrist_z + pose.lowest_z_m, 1.5e-3 - 1e-9) << "the fingertip above the table";
    EXPECT_LT(std::abs(pose.line_angle_rad), 20.0 * kDeg);
    if (std::string(name) == "banana") {
      EXPECT_GT(placed.along_pad_m, 0.0);
      EXPECT_LE(placed.along_pad_m, 0.010 + 1e-12);  // the last mesa row
    } else {
      EXPECT_EQ(placed.along_pad_m, 0.0);
    }
  }
}

// A cup, a glass and the bottle by its neck (pinched), and meshes: a level line through the centre of
// mass at the most nearly parallel faces near 13 mm below the top, whatever the file's origin.
TEST(GraspPlacementTest, LibraryShapesAndMeshesArePinchedAtTheirMostParallelFacesThroughTheCentreOfMass) {
  SceneConfig cup = Library("plastic_cup");
  const PinchPlacement cup_placed = PlacePinch(cup, Kinematics(cup));
  EXPECT_EQ(cup_placed.kind, PinchKind::kFaces);
  const double taper = std::atan(0.5 * (0.070 - 0.046) / 0.080);
  EXPECT_NEAR(cup_placed.face_angle_rad[0], taper, 1.0 * kDeg);
  EXPECT_NEAR(cup_placed.height_m, 0.080 - 0.013, 1e-9);

  SceneConfig bottle = Library("bottle");
  bottle.hand.grasp = GraspType::kPinch;
  const PinchPlacement neck = PlacePinch(bottle, Kinematics(bottle));
  EXPECT_NEAR(neck.width_m, 0.028, 0.5e-3) << "by the neck";
  EXPECT_LT(std::max(neck.face_angle_rad[0], neck.face_angle_rad[1]), 1.0 * kDeg);

  const SceneConfig block = Mesh("block_50x50x80.stl");
  const PinchPlacement block_placed = PlacePinch(block, Kinematics(block));
  EXPECT_EQ(block_placed.kind, PinchKind::kFaces);
  EXPECT_NEAR(block_placed.width_m, 0.050, 1e-6);
  EXPECT_NEAR(block_placed.height_m, 0.080 - 0.013, 1e-9);
  EXPECT_NEAR(block_placed.centre_x_m, 0.0, 1e-6);
  EXPECT_NEAR(block_placed.line_y_m, 0.0, 1e-6);

  const SceneConfig hex = Mesh("hex_bar_45x60.stl");
  const PinchPlacement hex_placed = PlacePinch(hex, Kinematics(hex));
  EXPECT_NEAR(hex_placed.width_m, 0.045, 1e-4) << "across the flats";
  EXPECT_LT(std::max(hex_placed.face_angle_rad[0], hex_placed.face_angle_rad[1]), 1.0 * kDeg);

  // The 30 mm puck: 13 mm below its top would put the fingertip into the table; the pad's centre
  // stays at its lowest, 23 mm (holder half length, tip cap and 3 mm).
  const SceneConfig puck = Mesh("puck_40x40x30.stl");
  EXPECT_NEAR(PlacePinch(puck, Kinematics(puck)).height_m, 0.023, 1e-9);

  // The wedge has no parallel faces: its sides meet the pinch 30 degrees from square, within the
  // cone of mu 0.8 (38.7 degrees); the line passes through its centre of mass, a third of its
  // height from the base edge.
  const SceneConfig wedge = Mesh("wedge_60x70.stl");
  const PinchPlacement wedge_placed = PlacePinch(wedge, Kinematics(wedge));
  EXPECT_NEAR(wedge_placed.face_angle_rad[0], 30.0 * kDeg, 0.5 * kDeg);
  EXPECT_NEAR(wedge_placed.face_angle_rad[1], 30.0 * kDeg, 0.5 * kDeg);
  const double triangle_height = 0.060 * std::sin(std::numbers::pi / 3.0);
  EXPECT_NEAR(wedge_placed.line_y_m, -0.5 * triangle_height + triangle_height / 3.0, 0.2e-3);
}

// What the hand cannot pinch is refused, naming the object and why, instead of a grasp that misses.
TEST(GraspPlacementTest, AnObjectTheHandCannotPinchIsRefusedWithItsNameAndWhy) {
  const SceneConfig slippery_wedge = Mesh("wedge_60x70.stl", 0.3);  // atan(0.3) = 16.7 degrees
  try {
    PlacePinch(slippery_wedge, Kinematics(slippery_wedge));
    FAIL() << "a wedge outside the friction cone was placed";
  } catch (const std::invalid_argument& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("object.mesh " + slippery_wedge.object.mesh + ": this hand cannot pinch it"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("outside the friction cone"), std::string::npos) << what;
  }
  SceneConfig low_ball;  // a 30 mm ball: its centre too low for the fingertip
  low_ball.object.shape = ObjectShape::kSphere;
  low_ball.object.size_m = {0.030, 0.0, 0.0};
  try {
    PlacePinch(low_ball, Kinematics(low_ball));
    FAIL() << "a 30 mm ball on the table was placed";
  } catch (const std::invalid_argument& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("the sphere: this hand cannot pinch it: pinched through its centre, the fingertip would "
                        "reach"),
              std::string::npos)
        << what;
  }
  // The generator refuses it the same way.
  EXPECT_THROW(GenerateMjcf(DefaultLayout(), low_ball), std::invalid_argument);
  SceneConfig flat_box;  // 20 mm tall: the pad's centre cannot come down to it
  flat_box.object.size_m = {0.05, 0.05, 0.02};
  try {
    PlacePinch(flat_box, Kinematics(flat_box));
    FAIL() << "a 20 mm box was placed";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("the box: this hand cannot pinch it: its top is 20.0 mm above the table"),
              std::string::npos)
        << error.what();
  }
}

// `graspbed model --kinematics` says which placement it chose.
TEST(GraspPlacementTest, TheKinematicsTableNamesThePlacement) {
  const std::string ball = DescribeHand(DefaultLayout(), Library("tennis_ball"));
  EXPECT_NE(ball.find("placement: round pinch through its centre"), std::string::npos) << ball;
  const std::string cup = DescribeHand(DefaultLayout(), Library("plastic_cup"));
  EXPECT_NE(cup.find("placement: faces pinch its most nearly parallel faces"), std::string::npos) << cup;
  EXPECT_NE(cup.find("pinch line: y 0.00 mm, 67.00 mm above the table"), std::string::npos) << cup;
}

}  // namespace
}  // namespace graspbed::sim

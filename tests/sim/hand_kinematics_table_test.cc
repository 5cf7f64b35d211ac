// The prosthetic hand's design and placement numbers, printed from the code that the model generator
// uses (ProstheticKinematics, PlaceHand) so that docs/simulation.md, "The prosthetic hand", quotes
// them instead of recomputing them. Run:
//   build/tests/sim/sim_tests --gtest_filter='HandKinematicsTable.*'
// The checks are the ones the table's reader relies on: the nominal pinch is square and centred,
// and every printed grasp puts pad and thumb on the object's faces at one height.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include "sim/hand_kinematics.h"
#include "sim/model_generator.h"
#include "sensor/layout.h"

namespace graspbed::sim {
namespace {

constexpr double kMm = 1e3;
constexpr double kPositionTolM = 1e-6;
constexpr double kAngleTolRad = 1e-9;

ProstheticKinematics Kinematics(const sensor::Layout& layout, const SceneConfig& scene) {
  return ProstheticKinematics(scene.hand.finger, scene.hand.thumb, layout.holder.length_m,
                              0.5 * layout.holder.minor_axis_m, layout.unit.mesa_height_m);
}

TEST(HandKinematicsTable, PrintsTheDesign) {
  const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  const SceneConfig scene;
  const ProstheticKinematics kin = Kinematics(layout, scene);
  const FingerConfig& f = kin.finger();
  const ThumbConfig& t = kin.thumb();
  const double ratio = 1.0 + f.pip_mcp_ratio;
  const double mcp_nominal = (0.5 * std::numbers::pi - f.dip_flexion_rad - f.mcp_rest_angle_rad) / ratio;
  const double thumb_nominal = 0.5 * std::numbers::pi + ProstheticKinematics::kThumbLeanRad - t.ip_flexion_rad;

  std::printf("Prosthetic hand, design (hand frame H, mm and rad)\n");
  std::printf("  index proximal (MCP-PIP)        %6.1f mm\n", f.proximal_length_m * kMm);
  std::printf("  index middle (PIP-DIP)          %6.1f mm\n", f.middle_length_m * kMm);
  std::printf("  distal = holder, length         %6.1f mm\n", kin.holder_length_m() * kMm);
  std::printf("  holder axis to mesa tops        %6.1f mm\n", kin.pad_depth_m() * kMm);
  std::printf("  PIP:MCP linkage ratio           %6.2f\n", f.pip_mcp_ratio);
  std::printf("  DIP fixed flexion               %6.3f rad\n", f.dip_flexion_rad);
  std::printf("  MCP rest angle (MCP = 0)        %6.3f rad below the palm plane\n", f.mcp_rest_angle_rad);
  std::printf("  MCP range                       %6.2f .. %.2f rad\n", ProstheticKinematics::kMcpMinRad,
              ProstheticKinematics::kMcpMaxRad);
  std::printf("  thumb CMC-IP                    %6.1f mm\n", t.proximal_length_m * kMm);
  std::printf("  thumb IP-tip centre             %6.1f mm\n", t.distal_length_m * kMm);
  std::printf("  thumb tip radius                %6.1f mm\n", t.tip_radius_m * kMm);
  std::printf("  thumb IP fixed flexion          %6.3f rad\n", t.ip_flexion_rad);
  std::printf("  thumb lean past vertical        %6.3f rad (nominal pinch)\n", ProstheticKinematics::kThumbLeanRad);
  std::printf("  thumb flexion range             %6.2f .. %.2f rad\n", ProstheticKinematics::kThumbMinRad,
              ProstheticKinematics::kThumbMaxRad);
  std::printf("  palm depth (palmar face z)      %6.1f mm\n", -ProstheticKinematics::kPalmDepthM * kMm);
  std::printf("  MCP at (x, z)                   (%.1f, %.1f) mm\n", kin.mcp_xz().x() * kMm, kin.mcp_xz().y() * kMm);
  std::printf("  thumb base (CMC) at (x, z)      (%.1f, %.1f) mm\n", kin.thumb_base_xz().x() * kMm,
              kin.thumb_base_xz().y() * kMm);
  std::printf("  thumb base - MCP                %.1f mm along x, %.1f mm along z, %.1f mm apart\n",
              (kin.thumb_base_xz() - kin.mcp_xz()).x() * kMm, (kin.thumb_base_xz() - kin.mcp_xz()).y() * kMm,
              (kin.thumb_base_xz() - kin.mcp_xz()).norm() * kMm);
  std::printf("  nominal pinch (%.0f mm)          MCP %.3f rad, PIP %.3f rad, thumb flexion %.3f rad\n",
              ProstheticKinematics::kNominalWidthM * kMm, mcp_nominal, f.pip_mcp_ratio * mcp_nominal, thumb_nominal);
  const DigitContact pad = kin.IndexPad(mcp_nominal);
  const DigitContact tip = kin.ThumbTip(thumb_nominal);
  std::printf("  nominal pad / thumb contact     (%.1f, %.1f) / (%.1f, %.1f) mm, pad tilt %.4f rad\n",
              pad.point_xz.x() * kMm, pad.point_xz.y() * kMm, tip.point_xz.x() * kMm, tip.point_xz.y() * kMm,
              pad.normal_angle_rad);
  std::printf("  largest pre-shape aperture      %6.1f mm\n", kin.MaxApertureM() * kMm);
  RecordProperty("mcp_x_mm", std::to_string(kin.mcp_xz().x() * kMm));
  RecordProperty("thumb_base_x_mm", std::to_string(kin.thumb_base_xz().x() * kMm));
  RecordProperty("max_aperture_mm", std::to_string(kin.MaxApertureM() * kMm));

  // The nominal pinch: pad square to the object's -x face, thumb on its +x face, one height.
  EXPECT_NEAR(pad.normal_angle_rad, 0.0, kAngleTolRad);
  EXPECT_NEAR(pad.point_xz.x(), -0.5 * ProstheticKinematics::kNominalWidthM, kPositionTolM);
  EXPECT_NEAR(tip.point_xz.x(), 0.5 * ProstheticKinematics::kNominalWidthM, kPositionTolM);
  EXPECT_NEAR(tip.point_xz.y(), pad.point_xz.y(), kPositionTolM);
  EXPECT_NEAR(kin.mcp_xz().y(), -ProstheticKinematics::kPalmDepthM, kPositionTolM);
}

struct Grasp {
  const char* name;
  ObjectShape shape;
  std::array<double, 3> size_m;
};

TEST(HandKinematicsTable, PrintsThePlacementPerObject) {
  const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  const std::vector<Grasp> grasps = {
      {"box 30 mm", ObjectShape::kBox, {0.03, 0.05, 0.08}},
      {"box 50 mm (default)", ObjectShape::kBox, {0.05, 0.05, 0.08}},
      {"box 70 mm", ObjectShape::kBox, {0.07, 0.05, 0.08}},
      {"cylinder d 55 h 90 (cup)", ObjectShape::kCylinder, {0.055, 0.0, 0.09}},
      {"sphere d 45 mm", ObjectShape::kSphere, {0.045, 0.0, 0.0}},
  };
  std::printf("Prosthetic hand, placement per object (PlaceHand; default hand keys)\n");
  std::printf("%-26s %6s %6s %7s %7s %7s %7s %7s %7s %7s %7s %8s %8s %7s %7s %7s\n", "object", "width", "gap",
              "mcp0", "thumb0", "mcp_c", "thumb_c", "tilt", "arm_i", "arm_t", "pinch_z", "tau_i", "tau_t", "w0_i",
              "w0_t", "wrist_z");
  std::printf("%-26s %6s %6s %7s %7s %7s %7s %7s %7s %7s %7s %8s %8s %7s %7s %7s\n", "", "mm", "mm", "rad", "rad",
              "rad", "rad", "rad", "mm", "mm", "mm", "N m", "N m", "rad/s", "rad/s", "mm");
  for (const Grasp& grasp : grasps) {
    SceneConfig scene;
    scene.object.shape = grasp.shape;
    scene.object.size_m = grasp.size_m;
    const HandPlacement place = PlaceHand(layout, scene);
    const ProstheticKinematics kin = Kinematics(layout, scene);
    const DigitContact pad = kin.IndexPad(place.contact_joint[0]);
    const DigitContact tip = kin.ThumbTip(place.contact_joint[1]);
    // World z of the contacts: wrist z + H z (H is the world frame in the pinch).
    const double pinch_z = place.wrist_position_m[2] + 0.5 * (pad.point_xz.y() + tip.point_xz.y());
    std::printf("%-26s %6.1f %6.1f %7.3f %7.3f %7.3f %7.3f %7.3f %7.2f %7.2f %7.1f %8.4f %8.4f %7.3f %7.3f %7.1f\n",
                grasp.name, place.object_width_m * kMm, place.open_gap_m * kMm, place.preshape_joint[0],
                place.preshape_joint[1], place.contact_joint[0], place.contact_joint[1], pad.normal_angle_rad,
                place.lever_arm_m[0] * kMm, place.lever_arm_m[1] * kMm, pinch_z * kMm, place.stall_effort[0],
                place.stall_effort[1], place.no_load_speed[0], place.no_load_speed[1],
                place.wrist_position_m[2] * kMm);
    // Both contacts on the object's faces, at one height (within the pad's and the tip's mismatch
    // of height away from the nominal width).
    EXPECT_NEAR(pad.point_xz.x(), -0.5 * place.object_width_m, kPositionTolM) << grasp.name;
    EXPECT_NEAR(tip.point_xz.x(), 0.5 * place.object_width_m, kPositionTolM) << grasp.name;
    // Stall torques give the configured pinch force at each contact.
    for (int k = 0; k < 2; ++k) {
      EXPECT_NEAR(place.stall_effort[k] / place.lever_arm_m[k], scene.hand.digit_motor.stall_pinch_force_n, 1e-9)
          << grasp.name;
    }
  }
  std::printf("  width: object across the pinch; gap: pre-shape aperture (width + 2 x preshape_clearance_m);\n"
              "  mcp0/thumb0: pre-shape joint angles; mcp_c/thumb_c: at contact; tilt: pad normal from +x at\n"
              "  contact (+ = facing down); arm: lever arm d(contact x)/d(joint) at contact; pinch_z: contact\n"
              "  height above the table; tau: stall torque; w0: no-load speed; wrist_z: wrist body height.\n");
}

}  // namespace
}  // namespace graspbed::sim

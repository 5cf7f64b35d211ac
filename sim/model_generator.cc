#include "sim/model_generator.h"

#include <Eigen/Geometry>

#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "sensor/raw_frame.h"
#include "sim/grasp_placement.h"
#include "sim/hand_kinematics.h"
#include "sim/object_shapes.h"

namespace graspbed::sim {
namespace {

// Jaw fixture geometry, chosen for a pinch of adult size [m].
constexpr double kPalmHalfHeightM = 0.015;
constexpr double kLinkLengthM = 0.04;          // palm -> holder top
constexpr double kLinkHalfThicknessM = 0.003;  // along the closing direction
constexpr double kLinkHalfWidthM = 0.005;
constexpr double kLinkSetBackM = 0.0025;  // link face behind the mesa tops
constexpr double kThumbPadHalfThicknessM = 0.004;
constexpr double kThumbPadHalfWidthM = 0.007;
constexpr double kStrokeMarginM = 0.002;  // digits stop this far short of touching when closed

// Shared by both hands.
constexpr double kMesaRootDepthM = 0.2e-3;  // mesa box reaches this far into its groove
constexpr int kHolderSegments = 48;         // polygon sides of the elliptic holder mesh
// Torsional friction of the hand and the table, and rolling friction of every geom (MuJoCo's
// geom friction is slide, spin, roll).
constexpr double kHandSpinFriction = 0.005;
constexpr double kRollingFriction = 0.0001;

// Prosthetic hand [m]. The rounded fingertip: an ellipsoid cap on the holder's distal end.
constexpr double kTipCapLengthM = ProstheticKinematics::kTipCapLengthM;
constexpr double kProximalRadiusM = ProstheticKinematics::kProximalRadiusM;
constexpr double kMiddleRadiusM = ProstheticKinematics::kMiddleRadiusM;
constexpr double kThumbProximalRadiusM = ProstheticKinematics::kThumbProximalRadiusM;
constexpr double kPalmMarginM = 0.012;     // palm box beyond the MCP and the thumb base
constexpr double kPalmHalfWidthM = 0.012;  // palm box along H y
// Wrap: the hand's plane (H y = 0) at the cylinder's mid-height, the palm's edge never closer to the
// table than 4 mm; the pad meets the cylinder when it stands this far from the palmar face, so the
// pad's squeeze brings it against the palm.
constexpr double kMinWrapPlaneHeightM = kPalmHalfWidthM + 0.004;
constexpr double kWrapPalmGapM = 0.001;
// Palm-sideways (wrap): H turned +90 deg about world x, H (x, y, z) -> world (x, -z, y); MJCF quat.
constexpr const char* kWrapPalmQuat = "0.70710678 0.70710678 0 0";
// The wrap's coupling spring lets the PIP flex this far past the linkage at the motor's stall [rad].
constexpr double kWrapPipGiveRad = 0.8;

// Fixed-format numbers so the text (and the checked-in model) is reproducible.
class Writer {
 public:
  Writer() { out_ << std::setprecision(8); }
  std::ostringstream& out() { return out_; }
  std::string Num(double value) {
    std::ostringstream s;
    s << std::setprecision(8) << (std::abs(value) < 1e-15 ? 0.0 : value);
    return s.str();
  }
  std::string Vec(const Eigen::Vector3d& v) { return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z()); }
  std::string Vec(double x, double y, double z) { return Num(x) + " " + Num(y) + " " + Num(z); }
  /// MJCF quat (w x y z) of a rotation by `angle` [rad] about the unit axis (x, y, z).
  std::string AxisAngle(double x, double y, double z, double angle) {
    const double s = std::sin(0.5 * angle);
    return Num(std::cos(0.5 * angle)) + " " + Vec(s * x, s * y, s * z);
  }

 private:
  std::ostringstream out_;
};

// ` solref="..." solimp="..."` of the object's contact compliance, which every geom and pair shares.
std::string ComplianceAttributes(Writer& w, const ObjectConfig& object) {
  return " solref=\"" + w.Num(object.solref_timeconst_s) + " " + w.Num(object.solref_dampratio) +
         "\" solimp=\"" + w.Num(object.solimp[0]) + " " + w.Num(object.solimp[1]) + " " +
         w.Num(object.solimp[2]) + " " + w.Num(object.solimp[3]) + " " + w.Num(object.solimp[4]) + "\"";
}

// ` friction="..."` values of the hand's and the table's geoms: sliding, spin, rolling.
std::string HandFriction(Writer& w, const HandConfig& hand) {
  return w.Num(hand.friction) + " " + w.Num(kHandSpinFriction) + " " + w.Num(kRollingFriction);
}

double MesaTopOffset(const sensor::Layout& layout) {
  return 0.5 * layout.holder.minor_axis_m + layout.unit.mesa_height_m;
}

// Jaw fixture: holder frame origin relative to the wrist and the digits' travel [m].
struct JawGeometry {
  double holder_center_below_wrist_m = 0.0;
  double finger_open_x_m = 0.0;
  double thumb_pad_open_x_m = 0.0;
  double mesa_top_offset_m = 0.0;
  double stroke_m = 0.0;
};

JawGeometry ComputeJawGeometry(const sensor::Layout& layout, double open_gap_m) {
  JawGeometry g;
  g.holder_center_below_wrist_m = kPalmHalfHeightM + kLinkLengthM + 0.5 * layout.holder.length_m;
  g.mesa_top_offset_m = MesaTopOffset(layout);
  g.finger_open_x_m = -0.5 * open_gap_m - g.mesa_top_offset_m;
  g.thumb_pad_open_x_m = 0.5 * open_gap_m;
  g.stroke_m = 0.5 * open_gap_m - kStrokeMarginM;
  return g;
}

ProstheticKinematics MakeKinematics(const sensor::Layout& layout, const SceneConfig& scene) {
  return ProstheticKinematics(scene.hand.finger, scene.hand.thumb, layout.holder.length_m,
                              0.5 * layout.holder.minor_axis_m, layout.unit.mesa_height_m);
}


double WrapPlaneHeightM(const ObjectConfig& object) {
  return std::max(object.StartCentreZM(), kMinWrapPlaneHeightM);
}


// The box, cylinder and sphere are one geom sized from object.size_m, as the model always had them;
// the library's shapes and the user's mesh are their parts (ObjectParts).
bool IsPrimitive(const ObjectConfig& object) {
  return object.shape == ObjectShape::kBox || object.shape == ObjectShape::kCylinder ||
         object.shape == ObjectShape::kSphere;
}

std::vector<ObjectPart> ObjectPartsToWrite(const ObjectConfig& object) {
  return IsPrimitive(object) ? std::vector<ObjectPart>{} : ObjectParts(object);
}

void WriteObjectMeshAssets(Writer& w, const std::vector<ObjectPart>& parts) {
  std::ostringstream& o = w.out();
  for (size_t k = 0; k < parts.size(); ++k) {
    if (parts[k].type != ObjectPart::Type::kMesh) continue;
    o << "    <mesh name=\"object_mesh_" << k << "\" vertex=\"";
    for (size_t v = 0; v < parts[k].vertices_m.size(); ++v)
      o << (v == 0 ? "" : "  ") << w.Vec(parts[k].vertices_m[v]);
    o << "\"/>\n";
  }
}

// The object: a free body at its start pose whose geoms have contact priority, so its friction and
// compliance govern. Returns the names of the geoms that collide.
std::vector<std::string> WriteObjectBody(Writer& w, const SceneConfig& scene, const std::vector<ObjectPart>& parts,
                                         const std::string& indent) {
  const ObjectConfig& object = scene.object;
  std::ostringstream& o = w.out();
  const double yaw = object.initial_yaw_rad;
  o << indent << "<body name=\"object\" pos=\""
    << w.Vec(object.initial_position_m[0], object.initial_position_m[1], object.StartCentreZM())
    << "\" quat=\"" << w.Num(std::cos(0.5 * yaw)) << " 0 0 " << w.Num(std::sin(0.5 * yaw)) << "\">\n";
  o << indent << "  <freejoint name=\"object_free\"/>\n";
  const std::string contact = "priority=\"1\" condim=\"" +
                              std::to_string(object.ContactCondim(scene.physics.condim)) + "\" friction=\"" +
                              w.Num(object.friction) + " " + w.Num(scene.TorsionalFrictionM(object.friction)) +
                              " " + w.Num(kRollingFriction) + "\"";
  if (IsPrimitive(object)) {
    o << indent << "  <geom name=\"object_geom\" ";
    switch (object.shape) {
      case ObjectShape::kBox:
        o << "type=\"box\" size=\""
          << w.Vec(0.5 * object.size_m[0], 0.5 * object.size_m[1], 0.5 * object.size_m[2]) << "\"";
        break;
      case ObjectShape::kCylinder:
        o << "type=\"cylinder\" size=\"" << w.Num(0.5 * object.size_m[0]) << " "
          << w.Num(0.5 * object.size_m[2]) << "\"";
        break;
      default:
        o << "type=\"sphere\" size=\"" << w.Num(0.5 * object.size_m[0]) << "\"";
        break;
    }
    o << " mass=\"" << w.Num(object.mass_kg) << "\" " << contact
      << " contype=\"1\" conaffinity=\"3\" rgba=\"0.3 0.7 0.4 1\"/>\n";
    o << indent << "</body>\n";
    return {"object_geom"};
  }
  std::vector<std::string> object_geoms;
  for (size_t k = 0; k < parts.size(); ++k) {
    const ObjectPart& part = parts[k];
    const std::string name = k == 0 ? "object_geom" : "object_geom_" + std::to_string(k);
    if (part.collides) object_geoms.push_back(name);
    o << indent << "  <geom name=\"" << name << "\" ";
    const Eigen::Vector3d half = part.size_m[1] * part.axis;
    switch (part.type) {
      case ObjectPart::Type::kBox:
        o << "type=\"box\" size=\"" << w.Vec(part.size_m[0], part.size_m[1], part.size_m[2]) << "\" pos=\""
          << w.Vec(part.position_m) << "\"";
        break;
      case ObjectPart::Type::kCylinder:
      case ObjectPart::Type::kCapsule:
        o << "type=\"" << (part.type == ObjectPart::Type::kCylinder ? "cylinder" : "capsule") << "\" size=\""
          << w.Num(part.size_m[0]) << "\" fromto=\"" << w.Vec(part.position_m - half) << " "
          << w.Vec(part.position_m + half) << "\"";
        break;
      case ObjectPart::Type::kSphere:
        o << "type=\"sphere\" size=\"" << w.Num(part.size_m[0]) << "\" pos=\"" << w.Vec(part.position_m) << "\"";
        break;
      case ObjectPart::Type::kMesh:
        o << "type=\"mesh\" mesh=\"object_mesh_" << k << "\"";
        break;
    }
    o << " mass=\"" << w.Num(part.mass_kg) << "\" " << contact;
    if (part.collides) {
      o << " contype=\"1\" conaffinity=\"3\" rgba=\"0.3 0.7 0.4 1\"/>\n";
    } else {
      o << " contype=\"0\" conaffinity=\"0\" rgba=\"0.3 0.5 0.9 0.6\"/>\n";
    }
  }
  o << indent << "</body>\n";
  return object_geoms;
}

// The holder: shell mesh, optional rounded tip, one mesa per unit and the pad site, holder frame
// (x = beam of the phalanx towards the tip, -z = palmar).
void WriteHolderGeoms(Writer& w, const sensor::Layout& layout, const std::string& indent, double mass_kg,
                      bool tip_cap) {
  std::ostringstream& o = w.out();
  o << indent << "<geom name=\"holder_shell\" type=\"mesh\" mesh=\"holder_mesh\" mass=\"" << w.Num(mass_kg)
    << "\" rgba=\"0.85 0.82 0.75 1\"/>\n";
  if (tip_cap) {
    o << indent << "<geom name=\"fingertip_cap\" type=\"ellipsoid\" size=\""
      << w.Vec(kTipCapLengthM, 0.5 * layout.holder.major_axis_m, 0.5 * layout.holder.minor_axis_m)
      << "\" pos=\"" << w.Vec(0.5 * layout.holder.length_m, 0, 0)
      << "\" mass=\"0.001\" rgba=\"0.85 0.82 0.75 1\"/>\n";
  }
  // Mesas: boxes in the holder frame; local x = beam axis, local z = outward normal; the top face is
  // mesa_height above the surface point, the root sits a little inside the groove.
  const double mesa_total = layout.unit.mesa_height_m + kMesaRootDepthM;
  for (int i = 0; i < layout.unit_count(); ++i) {
    const sensor::UnitPose& unit = layout.units[i];
    const Eigen::Vector3d outward = -unit.inward_normal.normalized();
    const Eigen::Vector3d beam = unit.beam_axis.normalized();
    const Eigen::Vector3d cross = outward.cross(beam);
    const Eigen::Vector3d center = unit.position_m + outward * (layout.unit.mesa_height_m - 0.5 * mesa_total);
    o << indent << "<geom name=\"unit_" << i << "\" type=\"box\" size=\""
      << w.Vec(0.5 * layout.unit.mesa_length_m, 0.5 * layout.unit.mesa_width_m, 0.5 * mesa_total)
      << "\" pos=\"" << w.Vec(center) << "\" xyaxes=\"" << w.Vec(beam) << " " << w.Vec(cross)
      << "\" mass=\"0.0001\""
      << " rgba=\""
      << (unit.orientation == sensor::BeamOrientation::kAxial ? "0.85 0.2 0.2 1" : "0.2 0.35 0.85 1")
      << "\"/>\n";
  }
  o << indent << "<site name=\"finger_pad\" pos=\"" << w.Vec(0, 0, -MesaTopOffset(layout))
    << "\" size=\"0.001\" rgba=\"1 1 0 0.5\"/>\n";
}

void WriteJawHand(Writer& w, const sensor::Layout& layout, const SceneConfig& scene,
                  const HandPlacement& place) {
  std::ostringstream& o = w.out();
  const HandConfig& hand = scene.hand;
  const JawGeometry g = ComputeJawGeometry(layout, place.open_gap_m);
  const double half_length = 0.5 * layout.holder.length_m;
  const double palm_half_x = 0.5 * place.open_gap_m + 0.02;
  o << "      <body name=\"palm\">\n";
  o << "        <geom name=\"palm_geom\" type=\"box\" size=\"" << w.Vec(palm_half_x, 0.02, kPalmHalfHeightM)
    << "\" mass=\"" << w.Num(hand.palm_mass_kg) << "\" rgba=\"0.3 0.3 0.35 1\"/>\n";
  // The motor's back-EMF (F = stall (effort - v_gap / v0)) as joint damping: MuJoCo integrates joint
  // damping implicitly, while an affine actuator bias this stiff on digits this light is explicit and
  // diverges at 0.5 ms. Each slide moves at half the gap speed and carries the full tendon force,
  // hence 2 stall / v0 per slide.
  const double digit_damping =
      hand.motor.damping_n_s_m + 2.0 * hand.motor.stall_force_n / hand.motor.no_load_speed_m_s;
  const double digit_link_mass = 0.5 * hand.digit_mass_kg;
  const double digit_tip_mass = 0.5 * hand.digit_mass_kg;
  o << "        <body name=\"finger\" pos=\"" << w.Vec(g.finger_open_x_m, 0, 0) << "\">\n";
  o << "          <joint name=\"finger_slide\" type=\"slide\" axis=\"1 0 0\" limited=\"true\" range=\"0 "
    << w.Num(g.stroke_m) << "\" armature=\"" << w.Num(hand.motor.armature_kg) << "\" damping=\""
    << w.Num(digit_damping) << "\"/>\n";
  const double link_center_z = -kPalmHalfHeightM - 0.5 * kLinkLengthM;
  const double link_center_x = g.mesa_top_offset_m - kLinkSetBackM - kLinkHalfThicknessM;
  o << "          <geom name=\"finger_link\" type=\"box\" size=\""
    << w.Vec(kLinkHalfThicknessM, kLinkHalfWidthM, 0.5 * kLinkLengthM) << "\" pos=\""
    << w.Vec(link_center_x, 0, link_center_z) << "\" mass=\"" << w.Num(digit_link_mass)
    << "\" rgba=\"0.75 0.72 0.65 1\"/>\n";
  o << "          <body name=\"holder\" pos=\"" << w.Vec(0, 0, -g.holder_center_below_wrist_m)
    << "\" xyaxes=\"0 0 -1 0 -1 0\">\n";
  WriteHolderGeoms(w, layout, "            ", digit_tip_mass, false);
  o << "          </body>\n";
  o << "        </body>\n";

  // Thumb: a flat pad opposite the holder, slides towards -x.
  o << "        <body name=\"thumb\" pos=\"" << w.Vec(g.thumb_pad_open_x_m, 0, 0) << "\">\n";
  o << "          <joint name=\"thumb_slide\" type=\"slide\" axis=\"-1 0 0\" limited=\"true\" range=\"0 "
    << w.Num(g.stroke_m) << "\" armature=\"" << w.Num(hand.motor.armature_kg) << "\" damping=\""
    << w.Num(digit_damping) << "\"/>\n";
  o << "          <geom name=\"thumb_link\" type=\"box\" size=\""
    << w.Vec(kLinkHalfThicknessM, kLinkHalfWidthM, 0.5 * kLinkLengthM) << "\" pos=\""
    << w.Vec(kLinkSetBackM + kLinkHalfThicknessM, 0, link_center_z) << "\" mass=\"" << w.Num(digit_link_mass)
    << "\" rgba=\"0.75 0.72 0.65 1\"/>\n";
  o << "          <geom name=\"thumb_pad\" type=\"box\" size=\""
    << w.Vec(kThumbPadHalfThicknessM, kThumbPadHalfWidthM, half_length) << "\" pos=\""
    << w.Vec(kThumbPadHalfThicknessM, 0, -g.holder_center_below_wrist_m) << "\" mass=\""
    << w.Num(digit_tip_mass) << "\" rgba=\"0.85 0.82 0.75 1\"/>\n";
  o << "          <site name=\"thumb_pad\" pos=\"" << w.Vec(0, 0, -g.holder_center_below_wrist_m)
    << "\" size=\"0.001\" rgba=\"1 1 0 0.5\"/>\n";
  o << "        </body>\n";
  o << "      </body>\n";
}

void WriteJawTransmission(Writer& w, const SceneConfig& scene) {
  std::ostringstream& o = w.out();
  // One motor closes both digits: the grip tendon is the total closure; the coupling keeps them
  // symmetric; the brake (off until the actuator asks for it) locks the finger where it is.
  o << "  <tendon>\n    <fixed name=\"grip\">\n      <joint joint=\"finger_slide\" coef=\"1\"/>\n"
    << "      <joint joint=\"thumb_slide\" coef=\"1\"/>\n    </fixed>\n  </tendon>\n";
  o << "  <equality>\n";
  o << "    <joint name=\"digit_coupling\" joint1=\"thumb_slide\" joint2=\"finger_slide\" polycoef=\"0 1 0 0 "
       "0\""
    << " solref=\"0.002 1\"/>\n";
  o << "    <joint name=\"grip_brake\" joint1=\"finger_slide\" polycoef=\"0 0 0 0 0\" active=\"false\""
    << " solref=\"0.002 1\"/>\n";
  o << "  </equality>\n";
  // Grip motor on the tendon: force = stall x effort (the speed term is the slides' damping).
  const double stall = scene.hand.motor.stall_force_n;
  o << "  <actuator>\n";
  o << "    <general name=\"grip_motor\" tendon=\"grip\" ctrllimited=\"true\" ctrlrange=\"-1 1\" gainprm=\""
    << w.Num(stall) << "\" forcelimited=\"true\" forcerange=\"" << w.Num(-stall) << " " << w.Num(stall)
    << "\"/>\n";
}

// xyaxes of a phalanx frame whose local x (towards the tip) points along (dx, 0, dz) of its parent
// and whose local y is the parent's -y (flexion about local +y), for the index finger.
std::string IndexAxes(Writer& w, double angle_rad) {
  return w.Vec(-std::cos(angle_rad), 0, -std::sin(angle_rad)) + " 0 -1 0";
}
std::string ThumbAxes(Writer& w, double angle_rad) {
  return w.Vec(std::cos(angle_rad), 0, -std::sin(angle_rad)) + " 0 1 0";
}

void WriteProstheticHand(Writer& w, const sensor::Layout& layout, const SceneConfig& scene,
                         const HandPlacement& place) {
  std::ostringstream& o = w.out();
  const HandConfig& hand = scene.hand;
  const ProstheticKinematics kin = MakeKinematics(layout, scene);
  const FingerConfig& finger = hand.finger;
  const ThumbConfig& thumb = hand.thumb;
  const DigitMotorConfig& motor = hand.digit_motor;
  const double mcp0 = place.preshape_joint[0];
  const double thumb0 = place.preshape_joint[1];
  const double opposition = scene.ThumbOppositionRad();
  const double palm_min_x = std::min(kin.mcp_xz().x(), kin.thumb_base_xz().x()) - kPalmMarginM;
  const double palm_max_x = std::max(kin.mcp_xz().x(), kin.thumb_base_xz().x()) + kPalmMarginM;
  const double half_depth = 0.5 * ProstheticKinematics::kPalmDepthM;
  // The hand frame H is the palm's: level in a pinch, turned palm-sideways in a wrap.
  o << "      <body name=\"palm\" childclass=\"hand\""
    << (hand.grasp == GraspType::kWrap ? std::string(" quat=\"") + kWrapPalmQuat + "\"" : std::string())
    << ">\n";
  o << "        <geom name=\"palm_geom\" type=\"box\" size=\""
    << w.Vec(0.5 * (palm_max_x - palm_min_x), kPalmHalfWidthM, half_depth) << "\" pos=\""
    << w.Vec(0.5 * (palm_min_x + palm_max_x), 0, -half_depth) << "\" mass=\"" << w.Num(hand.palm_mass_kg)
    << "\" rgba=\"0.3 0.3 0.35 1\"/>\n";

  // Index: MCP driven by its motor (back-EMF as implicit joint damping, as for the jaw), PIP held
  // to ratio x MCP by the linkage (an equality), DIP fixed. Joint values are absolute flexion
  // angles: `ref` is the pre-shape, at which the bodies below are posed.
  const double proximal_mass = 0.5 * hand.digit_mass_kg;
  const double middle_mass = 0.25 * hand.digit_mass_kg;
  const double distal_mass = 0.25 * hand.digit_mass_kg;
  // In a wrap the index is driven by a flexor tendon across MCP and PIP (WriteProstheticTransmission)
  // and its motor's back-EMF is split over both joints (in the tendon's squared arms) so that the free
  // finger closes at the linkage's speed; in a pinch the MCP carries it all. The PIP also gets the
  // motor's armature in the tendon's squared arm: the free finger's reflected inertia is about twice
  // the linkage's (splitting it as the damping is lost the can's oracle: a 0.51 mm gross slip at the
  // lift at every grip up to the stall).
  const bool adaptive = hand.grasp == GraspType::kWrap;
  const double back_emf = place.stall_effort[0] / place.no_load_speed[0];
  const double flexor_pip_coef = 1.0 / finger.pip_mcp_ratio;
  const double index_damping = motor.damping_n_m_s + (adaptive ? 0.5 * back_emf : back_emf);
  const double pip_damping =
      motor.damping_n_m_s + (adaptive ? 0.5 * back_emf * flexor_pip_coef * flexor_pip_coef : 0.0);
  const double thumb_damping = motor.damping_n_m_s + place.stall_effort[1] / place.no_load_speed[1];
  const double pip0 = finger.pip_mcp_ratio * mcp0;
  o << "        <body name=\"finger\" pos=\"" << w.Vec(kin.mcp_xz().x(), 0, kin.mcp_xz().y())
    << "\" xyaxes=\"" << IndexAxes(w, finger.mcp_rest_angle_rad + mcp0) << "\">\n";
  o << "          <joint name=\"index_mcp\" type=\"hinge\" axis=\"0 1 0\" ref=\"" << w.Num(mcp0)
    << "\" limited=\"true\" range=\"" << w.Num(ProstheticKinematics::kMcpMinRad) << " "
    << w.Num(ProstheticKinematics::kMcpMaxRad) << "\" armature=\"" << w.Num(motor.armature_kg_m2)
    << "\" damping=\"" << w.Num(index_damping) << "\"/>\n";
  o << "          <geom name=\"finger_proximal\" type=\"capsule\" fromto=\"0 0 0 "
    << w.Num(finger.proximal_length_m) << " 0 0\" size=\"" << w.Num(kProximalRadiusM) << "\" mass=\""
    << w.Num(proximal_mass) << "\" rgba=\"0.75 0.72 0.65 1\"/>\n";
  o << "          <body name=\"finger_middle\" pos=\"" << w.Vec(finger.proximal_length_m, 0, 0)
    << "\" quat=\"" << w.AxisAngle(0, 1, 0, pip0) << "\">\n";
  o << "            <joint name=\"index_pip\" type=\"hinge\" axis=\"0 1 0\" ref=\"" << w.Num(pip0)
    << "\" damping=\"" << w.Num(pip_damping) << "\"";
  if (adaptive) o << " armature=\"" << w.Num(motor.armature_kg_m2 * flexor_pip_coef * flexor_pip_coef) << "\"";
  o << "/>\n";
  o << "            <geom name=\"finger_middle\" type=\"capsule\" fromto=\"0 0 0 "
    << w.Num(finger.middle_length_m) << " 0 0\" size=\"" << w.Num(kMiddleRadiusM) << "\" mass=\""
    << w.Num(middle_mass) << "\" rgba=\"0.75 0.72 0.65 1\"/>\n";
  // Distal phalanx = the holder, turned by the fixed DIP flexion; its frame sits at its centre.
  const double half_length = 0.5 * layout.holder.length_m;
  const double dip = finger.dip_flexion_rad;
  o << "            <body name=\"holder\" pos=\""
    << w.Vec(finger.middle_length_m + half_length * std::cos(dip), 0, -half_length * std::sin(dip))
    << "\" quat=\"" << w.AxisAngle(0, 1, 0, dip) << "\">\n";
  WriteHolderGeoms(w, layout, "              ", distal_mass, true);
  o << "            </body>\n";
  o << "          </body>\n";
  o << "        </body>\n";

  // Thumb: opposition about the palm normal (held at the pre-shape's angle), then flexion; a fixed
  // IP bend and a rounded, unsensorised tip.
  o << "        <body name=\"thumb\" pos=\"" << w.Vec(kin.thumb_base_xz().x(), 0, kin.thumb_base_xz().y())
    << "\" quat=\"" << w.AxisAngle(0, 0, 1, opposition) << "\">\n";
  o << "          <joint name=\"thumb_opposition\" type=\"hinge\" axis=\"0 0 1\" ref=\"" << w.Num(opposition)
    << "\" limited=\"true\" range=\"-0.2 1.7\" armature=\"" << w.Num(motor.armature_kg_m2) << "\"/>\n";
  o << "          <geom name=\"thumb_base\" type=\"sphere\" size=\"" << w.Num(kThumbProximalRadiusM)
    << "\" mass=\"0.002\" rgba=\"0.75 0.72 0.65 1\"/>\n";
  o << "          <body name=\"thumb_proximal\" xyaxes=\"" << ThumbAxes(w, thumb0) << "\">\n";
  o << "            <joint name=\"thumb_flexion\" type=\"hinge\" axis=\"0 1 0\" ref=\"" << w.Num(thumb0)
    << "\" limited=\"true\" range=\"" << w.Num(ProstheticKinematics::kThumbMinRad) << " "
    << w.Num(ProstheticKinematics::kThumbMaxRad) << "\" armature=\"" << w.Num(motor.armature_kg_m2)
    << "\" damping=\"" << w.Num(thumb_damping) << "\"/>\n";
  o << "            <geom name=\"thumb_proximal\" type=\"capsule\" fromto=\"0 0 0 "
    << w.Num(thumb.proximal_length_m) << " 0 0\" size=\"" << w.Num(kThumbProximalRadiusM) << "\" mass=\""
    << w.Num(0.6 * hand.digit_mass_kg) << "\" rgba=\"0.75 0.72 0.65 1\"/>\n";
  o << "            <body name=\"thumb_distal\" pos=\"" << w.Vec(thumb.proximal_length_m, 0, 0)
    << "\" quat=\"" << w.AxisAngle(0, 1, 0, thumb.ip_flexion_rad) << "\">\n";
  o << "              <geom name=\"thumb_pad\" type=\"capsule\" fromto=\"0 0 0 "
    << w.Num(thumb.distal_length_m) << " 0 0\" size=\"" << w.Num(thumb.tip_radius_m) << "\" mass=\""
    << w.Num(0.4 * hand.digit_mass_kg) << "\" rgba=\"0.85 0.82 0.75 1\"/>\n";
  // The tip's face towards the index (H -x) in the nominal pinch, in the distal segment's frame.
  const double distal_nominal = 0.5 * std::numbers::pi + ProstheticKinematics::kThumbLeanRad;
  o << "              <site name=\"thumb_pad\" pos=\""
    << w.Vec(thumb.distal_length_m - thumb.tip_radius_m * std::cos(distal_nominal), 0,
             -thumb.tip_radius_m * std::sin(distal_nominal))
    << "\" size=\"0.001\" rgba=\"1 1 0 0.5\"/>\n";
  o << "            </body>\n";
  o << "          </body>\n";
  o << "        </body>\n";
  o << "      </body>\n";
}

void WriteProstheticTransmission(Writer& w, const SceneConfig& scene, const HandPlacement& place) {
  std::ostringstream& o = w.out();
  const FingerConfig& finger = scene.hand.finger;
  // The linkage: PIP - PIP0 = ratio (MCP - MCP0), stiff as a rigid linkage is. The opposition is
  // held where the pre-shape put it. Brakes hold the driven joints where they are when engaged.
  const bool adaptive = scene.hand.grasp == GraspType::kWrap;
  const double flexor_pip_coef = 1.0 / finger.pip_mcp_ratio;
  if (adaptive) {
    // The wrap's adaptive finger: one flexor tendon pulls MCP and PIP (PIP at 1/ratio the MCP's arm,
    // so the free finger keeps PIP = ratio x MCP), and a coupling spring holds PIP to ratio x MCP
    // against a blocked link: when the proximal phalanx meets the object the MCP stops and the PIP
    // flexes on until the middle phalanx meets it too, as a tendon-driven finger wraps link by link.
    // The spring lets the PIP flex kWrapPipGiveRad past the linkage at the motor's stall.
    const double stall_tension = place.stall_effort[0] / 2.0;
    const double spring = flexor_pip_coef * stall_tension / kWrapPipGiveRad;
    o << "  <tendon>\n";
    o << "    <fixed name=\"index_flexor\">\n      <joint joint=\"index_mcp\" coef=\"1\"/>\n"
      << "      <joint joint=\"index_pip\" coef=\"" << w.Num(flexor_pip_coef) << "\"/>\n    </fixed>\n";
    o << "    <fixed name=\"index_coupling_spring\" stiffness=\"" << w.Num(spring) << "\" springlength=\"0\">\n"
      << "      <joint joint=\"index_pip\" coef=\"1\"/>\n      <joint joint=\"index_mcp\" coef=\""
      << w.Num(-finger.pip_mcp_ratio) << "\"/>\n    </fixed>\n";
    o << "  </tendon>\n";
  }
  o << "  <equality>\n";
  if (!adaptive) {
    o << "    <joint name=\"pip_coupling\" joint1=\"index_pip\" joint2=\"index_mcp\" polycoef=\"0 "
      << w.Num(finger.pip_mcp_ratio) << " 0 0 0\" solref=\"0.002 1\"/>\n";
  }
  o << "    <joint name=\"thumb_opposition_lock\" joint1=\"thumb_opposition\" polycoef=\"0 0 0 0 0\""
    << " solref=\"0.002 1\"/>\n";
  // The index's brake locks its motor: the MCP, or in a wrap the flexor tendon.
  if (adaptive) {
    o << "    <tendon name=\"index_brake\" tendon1=\"index_flexor\" polycoef=\"0 0 0 0 0\" active=\"false\""
      << " solref=\"0.002 1\"/>\n";
  } else {
    o << "    <joint name=\"index_brake\" joint1=\"index_mcp\" polycoef=\"0 0 0 0 0\" active=\"false\""
      << " solref=\"0.002 1\"/>\n";
  }
  o << "    <joint name=\"thumb_brake\" joint1=\"thumb_flexion\" polycoef=\"0 0 0 0 0\" active=\"false\""
    << " solref=\"0.002 1\"/>\n";
  o << "  </equality>\n";
  // One DC motor per digit, torque = stall x effort (the speed term is the joint's damping).
  o << "  <actuator>\n";
  const char* names[2] = {"index_motor", "thumb_motor"};
  const char* joints[2] = {"index_mcp", "thumb_flexion"};
  for (int k = 0; k < 2; ++k) {
    // The flexor tendon moves 1 + ratio x 1/ratio = 2 rad per radian of the free finger's MCP: half
    // the linkage's torque at the MCP makes the same pad force.
    const bool tendon = adaptive && k == 0;
    const double stall = tendon ? 0.5 * place.stall_effort[k] : place.stall_effort[k];
    o << "    <general name=\"" << names[k] << "\" " << (tendon ? "tendon=\"index_flexor" : "joint=\"" + std::string(joints[k]))
      << "\" ctrllimited=\"true\" ctrlrange=\"-1 1\" gainprm=\"" << w.Num(stall)
      << "\" forcelimited=\"true\" forcerange=\"" << w.Num(-stall) << " " << w.Num(stall) << "\"/>\n";
  }
}

// Stall torque of each digit's motor so that it presses stall_pinch_force_n through `lever_arm_m`
// [m]; no-load speeds so that the thumb's contact closes as fast as the pad.
void SizeDigitMotors(const HandConfig& hand, const std::array<double, 2>& lever_arm_m, HandPlacement& place) {
  for (int k = 0; k < 2; ++k) place.stall_effort[k] = hand.digit_motor.stall_pinch_force_n * lever_arm_m[k];
  const double omega = hand.digit_motor.no_load_speed_rad_s;
  place.no_load_speed = {omega, omega * lever_arm_m[0] / lever_arm_m[1]};
}

// Names of the geoms an MJCF fragment declares, in the order they are written. Every geom must be
// named first thing: an unnamed one would get no contact pair and pass through everything.
std::vector<std::string> GeomNames(const std::string& mjcf_fragment) {
  static constexpr std::string_view kGeom = "<geom ";
  static constexpr std::string_view kNamed = "<geom name=\"";
  std::vector<std::string> names;
  for (size_t at = mjcf_fragment.find(kGeom); at != std::string::npos; at = mjcf_fragment.find(kGeom, at)) {
    if (mjcf_fragment.compare(at, kNamed.size(), kNamed) != 0) {
      throw std::logic_error("model generator: a hand geom without a leading name attribute: " +
                             mjcf_fragment.substr(at, 60));
    }
    at += kNamed.size();
    const size_t end = mjcf_fragment.find('"', at);
    names.push_back(mjcf_fragment.substr(at, end - at));
  }
  return names;
}

// Every geom pair that can touch, listed for `collision="predefined"`: the object with each hand
// geom and the table, the table with each hand geom (never the hand with itself, as its contype /
// conaffinity say). MuJoCo then skips its broad phase, 10 to 14 % of a held step. Each pair
// carries the parameters MuJoCo's dynamic collision would mix from the two geoms (the object's
// priority: its condim, friction and compliance; table and hand: the shared defaults); CompileMjcf
// puts them in the order dynamic collision tests them, so the contacts are the same, in the same
// order (ModelTest.ThePredefinedPairsGiveTheContactsOfDynamicCollision). Simulation updates the
// object pairs' friction with the object's.
void WriteContactPairs(Writer& w, const SceneConfig& scene, const std::vector<std::string>& hand_geoms,
                       const std::vector<std::string>& object_geoms) {
  const ObjectConfig& object = scene.object;
  std::ostringstream& o = w.out();
  const std::string compliance = ComplianceAttributes(w, object);
  // MuJoCo spreads a geom's (slide, spin, roll) friction over the contact's five directions.
  const auto friction = [&](double slide, double spin) {
    const std::string roll = w.Num(kRollingFriction);
    return "\" friction=\"" + w.Num(slide) + " " + w.Num(slide) + " " + w.Num(spin) + " " + roll + " " +
           roll + "\"";
  };
  const std::string with_object = " condim=\"" + std::to_string(object.ContactCondim(scene.physics.condim)) +
                                  friction(object.friction, scene.TorsionalFrictionM(object.friction)) +
                                  compliance;
  const std::string table_hand =
      " condim=\"3" + friction(scene.hand.friction, kHandSpinFriction) + compliance;
  o << "  <contact>\n";
  if (scene.physics.table) {
    for (const std::string& geom : hand_geoms)
      o << "    <pair geom1=\"table_geom\" geom2=\"" << geom << "\"" << table_hand << "/>\n";
    for (const std::string& part : object_geoms)
      o << "    <pair geom1=\"table_geom\" geom2=\"" << part << "\"" << with_object << "/>\n";
  }
  for (const std::string& part : object_geoms) {
    for (const std::string& geom : hand_geoms)
      o << "    <pair geom1=\"" << geom << "\" geom2=\"" << part << "\"" << with_object << "/>\n";
  }
  o << "  </contact>\n";
}

}  // namespace

std::vector<std::string> GripMotorNames(HandModel model) {
  if (model == HandModel::kJaw) return {"grip_motor"};
  return {"index_motor", "thumb_motor"};
}

std::vector<std::string> GripBrakeNames(HandModel model) {
  if (model == HandModel::kJaw) return {"grip_brake"};
  return {"index_brake", "thumb_brake"};
}

HandPlacement PlaceHand(const sensor::Layout& layout, const SceneConfig& scene) {
  const ObjectConfig& object = scene.object;
  const HandConfig& hand = scene.hand;
  HandPlacement place;
  place.object_width_m = scene.ObjectWidthM();
  place.open_gap_m = scene.OpenGapM();
  const std::array<double, 3>& wrist_set = hand.initial_wrist_position_m;
  std::array<double, 3> wrist{};
  if (hand.model == HandModel::kJaw) {
    const JawGeometry g = ComputeJawGeometry(layout, place.open_gap_m);
    // Holder centre level with the object centre, digits straddling it.
    wrist = {object.initial_position_m[0], object.initial_position_m[1],
             object.StartCentreZM() + g.holder_center_below_wrist_m};
    place.stall_effort = {hand.motor.stall_force_n, hand.motor.stall_force_n};
    place.no_load_speed = {hand.motor.no_load_speed_m_s, hand.motor.no_load_speed_m_s};
    place.contact_joint = {0.5 * (place.open_gap_m - place.object_width_m),
                           0.5 * (place.open_gap_m - place.object_width_m)};
  } else if (hand.grasp == GraspType::kWrap) {
    const ProstheticKinematics kin = MakeKinematics(layout, scene);
    try {
      place.wrap = kin.Wrap(0.5 * place.object_width_m, kWrapPalmGapM, hand.preshape_clearance_m);
    } catch (const std::invalid_argument& error) {
      throw std::invalid_argument(std::string("object.size_m / hand.grasp wrap: ") + error.what());
    }
    const WrapPose& wrap = *place.wrap;
    place.contact_joint = {wrap.index_contact_rad, wrap.thumb_contact_rad};
    // The cylinder's axis at H (x, z) is at world (x, -z) from the wrist: H turned palm-sideways.
    wrist = {object.initial_position_m[0] - wrap.centre_xz.x(),
             object.initial_position_m[1] + wrap.centre_xz.y(), WrapPlaneHeightM(object)};
    place.lever_arm_m = {wrap.pad_lever_arm_m, wrap.thumb_lever_arm_m};
    // As in the pinch, the pad presses stall_pinch_force_n at stall in this grasp's posture; the
    // thumb a share of it (its firmware's grip pattern), so that the pad's squeeze goes into the
    // palm: at equal forces the thumb, closing round the cylinder's far side, would press it off
    // the palm and hold it against the pad alone.
    SizeDigitMotors(hand, place.lever_arm_m, place);
    place.stall_effort[1] *= hand.digit_motor.wrap_thumb_share;
    // Both digits meet the cylinder together (as in the pinch, where the thumb is geared for it):
    // the one with less travel at its no-load speed opens further than its clearance.
    const double travel_s =
        std::max((wrap.index_contact_rad - wrap.index_preshape_rad) / place.no_load_speed[0],
                 (wrap.thumb_contact_rad - wrap.thumb_preshape_rad) / place.no_load_speed[1]);
    place.preshape_joint = {std::max(wrap.index_contact_rad - travel_s * place.no_load_speed[0],
                                     ProstheticKinematics::kMcpMinRad),
                            std::max(wrap.thumb_contact_rad - travel_s * place.no_load_speed[1],
                                     ProstheticKinematics::kThumbMinRad)};
  } else {
    const ProstheticKinematics kin = MakeKinematics(layout, scene);
    place.pinch = PlacePinch(scene, kin);
    const PinchPlacement& pinch = *place.pinch;
    place.object_width_m = pinch.width_m;
    if (std::isnan(hand.open_gap_m)) place.open_gap_m = pinch.width_m + 2.0 * hand.preshape_clearance_m;
    const double max_aperture = kin.MaxApertureM();
    if (place.open_gap_m > max_aperture) {
      std::ostringstream message;
      message << "hand.open_gap_m / object.size_m: a pre-shape of " << place.open_gap_m * 1e3
              << " mm is wider than the prosthetic hand opens (" << max_aperture * 1e3 << " mm)";
      throw std::invalid_argument(message.str());
    }
    double centre_x = 0.0;  // the middle between the contacts, H x
    double contact_z = 0.0;
    if (pinch.kind == PinchKind::kRound) {
      // The section's centre on the line through both contacts; each digit opens by the clearance.
      const RoundPinchPose& round = pinch.round;
      centre_x = round.centre_xz.x();
      contact_z = round.centre_xz.y();
      place.contact_joint = {round.mcp_rad, round.thumb_rad};
      const double clearance = 0.5 * (place.open_gap_m - pinch.width_m);
      place.preshape_joint = {kin.McpForPadX(kin.IndexPad(round.mcp_rad).point_xz.x() - clearance),
                              kin.ThumbForTipX(kin.ThumbTip(round.thumb_rad).point_xz.x() + clearance)};
    } else {
      // Each digit's contact angle for this width, and the height at which their contacts meet it.
      const double half_width = 0.5 * pinch.width_m;
      const double half_gap = 0.5 * place.open_gap_m;
      centre_x = PinchCentreX(scene, kin, pinch.width_m);
      place.contact_joint = {kin.McpForPadX(centre_x - half_width), kin.ThumbForTipX(centre_x + half_width)};
      place.preshape_joint = {kin.McpForPadX(centre_x - half_gap), kin.ThumbForTipX(centre_x + half_gap)};
      contact_z = 0.5 * (kin.IndexPad(place.contact_joint[0]).point_xz.y() +
                         kin.ThumbTip(place.contact_joint[1]).point_xz.y());
    }
    wrist = {pinch.centre_x_m - centre_x, pinch.line_y_m, pinch.height_m - contact_z};
    // Motors sized so that at stall each digit presses stall_pinch_force_n on the object in this
    // grasp's contact posture: torque = force x lever arm there.
    place.lever_arm_m = {std::abs(kin.PadLeverArmM(place.contact_joint[0])),
                         std::abs(kin.ThumbLeverArmM(place.contact_joint[1]))};
    SizeDigitMotors(hand, place.lever_arm_m, place);
  }
  for (int k = 0; k < 3; ++k) place.wrist_position_m[k] = std::isnan(wrist_set[k]) ? wrist[k] : wrist_set[k];
  return place;
}

namespace {

// "object contacts: condim 4, impratio 20 (auto, the object's stiffness 5e+04 N/m)".
std::string ObjectContactsLine(const SceneConfig& scene) {
  std::ostringstream o;
  o << "object contacts: condim " << scene.object.ContactCondim(scene.physics.condim) << ", impratio "
    << scene.Impratio();
  if (std::isnan(scene.physics.impratio)) {
    o << " (auto, the object's stiffness " << scene.object.stiffness_n_m.value_or(StiffnessOfSolref(scene.object))
      << " N/m)";
  }
  o << "\n";
  return o.str();
}

}  // namespace

std::string DescribeHand(const sensor::Layout& layout, const SceneConfig& scene) {
  scene.Validate();
  const HandPlacement place = PlaceHand(layout, scene);
  std::ostringstream o;
  o << std::fixed << std::setprecision(2);
  const auto mm = [](double m) { return m * 1e3; };
  const auto deg = [](double rad) { return rad * 180.0 / std::numbers::pi; };
  o << "hand model " << ToString(scene.hand.model) << ", grasp " << ToString(scene.hand.grasp) << ", object "
    << ToString(scene.object.shape) << " " << mm(place.object_width_m) << " mm across, ";
  if (scene.hand.grasp == GraspType::kWrap) {
    o << "pre-shape clear of it by " << mm(scene.hand.preshape_clearance_m) << " mm\n";
  } else {
    o << "pre-shape aperture " << mm(place.open_gap_m) << " mm\n";
  }
  o << "wrist start (world) [mm]: " << mm(place.wrist_position_m[0]) << " " << mm(place.wrist_position_m[1])
    << " " << mm(place.wrist_position_m[2]) << "\n";
  if (scene.hand.model == HandModel::kJaw) {
    o << "jaw: each digit travels " << mm(place.contact_joint[0]) << " mm to the object; stall force "
      << scene.hand.motor.stall_force_n << " N; no-load gap speed " << scene.hand.motor.no_load_speed_m_s
      << " m/s\n";
    return o.str();
  }
  const ProstheticKinematics kin = MakeKinematics(layout, scene);
  const FingerConfig& f = scene.hand.finger;
  const ThumbConfig& t = scene.hand.thumb;
  o << "hand frame H: origin at the wrist, x index -> thumb, z up; palmar face at z = "
    << mm(-ProstheticKinematics::kPalmDepthM) << " mm\n";
  o << "index: MCP at x " << mm(kin.mcp_xz().x()) << " z " << mm(kin.mcp_xz().y()) << " mm; proximal "
    << mm(f.proximal_length_m) << " mm, middle " << mm(f.middle_length_m) << " mm, distal = holder "
    << mm(layout.holder.length_m) << " mm + " << mm(kTipCapLengthM)
    << " mm rounded tip; PIP = " << f.pip_mcp_ratio << " x MCP; DIP fixed at " << deg(f.dip_flexion_rad)
    << " deg; proximal " << deg(f.mcp_rest_angle_rad) << " deg below the palm at MCP 0; MCP range "
    << deg(ProstheticKinematics::kMcpMinRad) << " .. " << deg(ProstheticKinematics::kMcpMaxRad) << " deg\n";
  o << "thumb: base at x " << mm(kin.thumb_base_xz().x()) << " z " << mm(kin.thumb_base_xz().y())
    << " mm; CMC-IP " << mm(t.proximal_length_m) << " mm, IP-tip " << mm(t.distal_length_m)
    << " mm, tip radius " << mm(t.tip_radius_m) << " mm, IP fixed at " << deg(t.ip_flexion_rad)
    << " deg; opposition " << deg(scene.ThumbOppositionRad()) << " deg; flexion range "
    << deg(ProstheticKinematics::kThumbMinRad) << " .. " << deg(ProstheticKinematics::kThumbMaxRad)
    << " deg\n";
  const double mcp_square = kin.SquarePadMcpRad();
  // Pre-shape and contact angles, and the pad's normal (from H +x towards the palm) in each.
  const auto joint_rows = [&](const std::string& pad_column) {
    const int width = static_cast<int>(pad_column.size()) + 6;
    o << "                     MCP [deg]  thumb [deg]  " << pad_column << " [deg]\n";
    for (const auto& [label, joints] :
         {std::pair{"pre-shape", place.preshape_joint}, {"contact", place.contact_joint}}) {
      o << std::left << std::setw(21) << label << std::right << std::setw(9) << deg(joints[0]) << "  "
        << std::setw(11) << deg(joints[1]) << "  " << std::setw(width)
        << deg(kin.IndexPad(joints[0]).normal_angle_rad) << "\n";
    }
  };
  o << ObjectContactsLine(scene);
  if (place.wrap) {
    const WrapPose& wrap = *place.wrap;
    o << "wrap: palm sideways (H z -> world -y, H y -> world z); cylinder axis at H x "
      << mm(wrap.centre_xz.x()) << " z " << mm(wrap.centre_xz.y()) << " mm, " << mm(kWrapPalmGapM)
      << " mm from the palm when the pad touches it " << mm(-wrap.pad_contact_along_m)
      << " mm from its centre towards the DIP; proximal and middle phalanges " << mm(wrap.index_link_clearance_m)
      << " mm clear then\n";
    joint_rows("pad normal");
    o << "lever arms at contact: pad " << mm(place.lever_arm_m[0]) << " mm (along its normal), thumb "
      << mm(place.lever_arm_m[1]) << " mm (towards the axis)\n";
    o << "motors: stall " << place.stall_effort[0] << " N m (index MCP), " << place.stall_effort[1]
      << " N m (thumb): at stall the pad presses " << place.stall_effort[0] / place.lever_arm_m[0]
      << " N, the thumb " << place.stall_effort[1] / place.lever_arm_m[1] << " N\n";
    o << "wrap height: hand plane " << mm(WrapPlaneHeightM(scene.object)) << " mm above the table\n";
    return o.str();
  }
  o << "nominal pinch: " << mm(ProstheticKinematics::kNominalWidthM)
    << " mm, pad square to the object at MCP " << deg(mcp_square) << " deg\n";
  joint_rows("pad tilt");
  o << "lever arms at contact: pad " << mm(place.lever_arm_m[0]) << " mm, thumb " << mm(place.lever_arm_m[1])
    << " mm\n";
  o << "motors: stall " << place.stall_effort[0] << " N m (index MCP), " << place.stall_effort[1]
    << " N m (thumb) = " << scene.hand.digit_motor.stall_pinch_force_n << " N pinch; no-load "
    << place.no_load_speed[0] << " rad/s (index), " << place.no_load_speed[1] << " rad/s (thumb)\n";
  const PinchPlacement& pinch = *place.pinch;
  o << "placement: " << ToString(pinch.kind) << " pinch " << pinch.reason << "\n";
  o << "pinch line: y " << mm(pinch.line_y_m) << " mm, " << mm(pinch.height_m) << " mm above the table; contacts "
    << mm(pinch.width_m) << " mm apart about x " << mm(pinch.centre_x_m) << " mm\n";
  o << "largest aperture: " << mm(kin.MaxApertureM()) << " mm\n";
  return o.str();
}

std::string ObjectOnlyMjcf(const SceneConfig& scene) {
  Writer w;
  std::ostringstream& o = w.out();
  const std::vector<ObjectPart> parts = ObjectPartsToWrite(scene.object);
  o << "<mujoco model=\"graspbed_object\">\n  <compiler angle=\"radian\" inertiafromgeom=\"true\"/>\n"
    << "  <option gravity=\"0 0 0\"/>\n  <asset>\n";
  WriteObjectMeshAssets(w, parts);
  o << "  </asset>\n  <worldbody>\n";
  WriteObjectBody(w, scene, parts, "    ");
  o << "  </worldbody>\n</mujoco>\n";
  return o.str();
}

namespace {

// Step 1: the header, solver options, buffer sizes, visual settings and the geom defaults.
void WriteOptionsAndDefaults(Writer& w, const sensor::Layout& layout, const SceneConfig& scene) {
  const HandConfig& hand = scene.hand;
  const PhysicsConfig& physics = scene.physics;
  std::ostringstream& o = w.out();
  o << "<!-- graspbed scene, generated by `graspbed model` from layout '" << layout.name << "', "
    << ToString(hand.model) << " hand, " << ToString(hand.grasp)
    << " pre-shape. Do not edit: regenerate. -->\n";
  o << "<mujoco model=\"graspbed_" << layout.name << "\">\n";
  o << "  <compiler angle=\"radian\" inertiafromgeom=\"true\"/>\n";
  o << "  <option timestep=\"" << w.Num(physics.timestep_s) << "\" gravity=\"0 0 "
    << w.Num(-physics.gravity_m_s2) << "\" cone=\"" << (physics.elliptic_cones ? "elliptic" : "pyramidal")
    << "\" impratio=\"" << w.Num(scene.Impratio()) << "\" noslip_iterations=\"" << physics.noslip_iterations
    << "\" iterations=\"" << physics.solver_iterations << "\" tolerance=\"" << w.Num(physics.tolerance)
    << "\" solver=\"Newton\" integrator=\"Euler\" collision=\""
    << (physics.contact_pairs ? "predefined" : "dynamic") << "\"/>\n";
  // Sized from use with a wide margin: over the shipped suite and the scorecard set the most seen at
  // once were 21 contacts, 65 constraint rows and 1.7k stack doubles (mjData.maxuse_*). MuJoCo 2.x
  // allocates and clears njmax^2 doubles for the solver when a run starts: njmax 1000 and nstack 1e6
  // cost 2.9 ms of the 4.8 ms a Simulation took to build (bench/sim_bench BM_BuildSimulation). A
  // scene that outgrows them gets MuJoCo's buffer-full warning, which ends the run as a fault. A
  // contact takes condim rows: a soft object at condim 6, deep in the pad, takes over 300 of them.
  const int object_condim = scene.object.ContactCondim(physics.condim);
  o << "  <size nconmax=\"100\" njmax=\"" << 100 * object_condim << "\" nstack=\"100000\"/>\n";
  o << "  <visual><map znear=\"0.001\"/><global offwidth=\"1280\" offheight=\"960\"/></visual>\n";
  o << "  <default>\n";
  o << "    <geom" << ComplianceAttributes(w, scene.object) << " friction=\"" << HandFriction(w, hand) << "\"/>\n";
  // Prosthetic hand geoms (class "hand"): contype 2 / conaffinity 1 touch the object and the table
  // (contype 1 / conaffinity 3) but never each other: the linkage, not contact, keeps the digits
  // apart, and every pair the collision check skips is time saved.
  o << "    <default class=\"hand\"><geom contype=\"2\" conaffinity=\"1\"/></default>\n";
  o << "  </default>\n";
}

// Step 2: the meshes: the holder (an elliptic cylinder, no such primitive in MuJoCo, as a convex
// mesh in the holder frame) and the object's parts that are meshes.
void WriteAssets(Writer& w, const sensor::Layout& layout, const std::vector<ObjectPart>& parts) {
  const double a = 0.5 * layout.holder.major_axis_m;
  const double b = 0.5 * layout.holder.minor_axis_m;
  const double half_length = 0.5 * layout.holder.length_m;
  std::ostringstream& o = w.out();
  o << "  <asset>\n    <mesh name=\"holder_mesh\" vertex=\"";
  for (int ring = 0; ring < 2; ++ring) {
    const double x = ring == 0 ? -half_length : half_length;
    for (int i = 0; i < kHolderSegments; ++i) {
      const double t = 2.0 * std::numbers::pi * i / kHolderSegments;
      o << (ring == 0 && i == 0 ? "" : "  ") << w.Vec(x, a * std::sin(t), -b * std::cos(t));
    }
  }
  o << "\"/>\n";
  WriteObjectMeshAssets(w, parts);
  o << "  </asset>\n";
}

// Step 3: the light and the table, in the world body.
void WriteSceneFixtures(Writer& w, const SceneConfig& scene) {
  std::ostringstream& o = w.out();
  o << "    <light pos=\"0 -0.3 0.6\" dir=\"0 0.4 -1\" directional=\"true\"/>\n";
  if (!scene.physics.table) return;
  // A plane, not a box: MuJoCo tests a plane against every geom with cheap analytic functions,
  // while a box this large overlaps every geom's bounding sphere and sends each hand geom to a
  // box-box or general convex test every step (docs/simulation.md, "Where a step's time goes").
  // A world geom, not a body of its own: MuJoCo 2.2.2's dynamic broad phase pairs a static body
  // holding a plane with every body and then again wherever the boxes overlap, which doubled each
  // contact of an object resting over the table's origin.
  o << "    <geom name=\"table_geom\" type=\"plane\" size=\"0.3 0.3 0.02\" rgba=\"0.55 "
       "0.45 0.35 1\""
    << " contype=\"1\" conaffinity=\"3\" friction=\"" << HandFriction(w, scene.hand) << "\"/>\n";
}

// Step 4: the wrist carriage on three slide joints, with the hand below it. Returns the hand's geom
// names (the contact pairs list them).
std::vector<std::string> WriteWristAndHand(Writer& w, const sensor::Layout& layout, const SceneConfig& scene,
                                           const HandPlacement& place) {
  std::ostringstream& o = w.out();
  const std::array<double, 3>& wrist = place.wrist_position_m;
  o << "    <body name=\"wrist\" pos=\"" << w.Vec(wrist[0], wrist[1], wrist[2]) << "\">\n";
  for (const char* axis : {"x", "y", "z"}) {
    const std::string dir = axis[0] == 'x' ? "1 0 0" : axis[0] == 'y' ? "0 1 0" : "0 0 1";
    o << "      <joint name=\"wrist_" << axis << "\" type=\"slide\" axis=\"" << dir << "\" damping=\""
      << w.Num(scene.hand.wrist_damping_n_s_m) << "\"/>\n";
  }
  const std::streamoff hand_start = o.tellp();
  if (scene.hand.model == HandModel::kJaw) {
    WriteJawHand(w, layout, scene, place);
  } else {
    WriteProstheticHand(w, layout, scene, place);
  }
  std::vector<std::string> hand_geoms = GeomNames(o.str().substr(static_cast<size_t>(hand_start)));
  o << "    </body>\n";
  return hand_geoms;
}

// Step 6: the actuators (the hand's transmission and its motors, then the wrist's stiff position
// servos) and the end of the document.
void WriteActuators(Writer& w, const SceneConfig& scene, const HandPlacement& place) {
  std::ostringstream& o = w.out();
  if (scene.hand.model == HandModel::kJaw) {
    WriteJawTransmission(w, scene);
  } else {
    WriteProstheticTransmission(w, scene, place);
  }
  for (const char* axis : {"x", "y", "z"}) {
    o << "    <position name=\"wrist_" << axis << "_servo\" joint=\"wrist_" << axis << "\" kp=\""
      << w.Num(scene.hand.wrist_stiffness_n_m) << "\"/>\n";
  }
  o << "  </actuator>\n";
  o << "</mujoco>\n";
}

}  // namespace

std::string GenerateMjcf(const sensor::Layout& layout, const SceneConfig& scene) {
  scene.Validate();
  if (layout.unit_count() < 1 || layout.unit_count() > sensor::kMaxUnits) {
    throw std::invalid_argument("layout " + layout.name + ": " + std::to_string(layout.unit_count()) +
                                " units, the model supports 1.." + std::to_string(sensor::kMaxUnits));
  }
  const HandPlacement place = PlaceHand(layout, scene);
  // The library's shapes and the user's mesh: the object's parts (one geom each, object frame).
  const std::vector<ObjectPart> parts = ObjectPartsToWrite(scene.object);
  Writer w;
  WriteOptionsAndDefaults(w, layout, scene);
  WriteAssets(w, layout, parts);
  w.out() << "  <worldbody>\n";
  WriteSceneFixtures(w, scene);
  const std::vector<std::string> hand_geoms = WriteWristAndHand(w, layout, scene, place);
  // Step 5: the object, then the pairs of geoms that can touch.
  const std::vector<std::string> object_geoms = WriteObjectBody(w, scene, parts, "    ");
  w.out() << "  </worldbody>\n";
  if (scene.physics.contact_pairs) WriteContactPairs(w, scene, hand_geoms, object_geoms);
  WriteActuators(w, scene, place);
  return w.out().str();
}

}  // namespace graspbed::sim

#include "sim/scene_config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "sim/object_library.h"
#include "sim/object_shapes.h"

namespace graspbed::sim {
namespace {

using common::FieldError;
using common::NumberRule;

// A cross-field failure of the scene: `key` relative to the scene ("object.solimp[1]").
[[noreturn]] void Bad(const std::string& key, double value, const std::string& reason) {
  FieldError(key, value, reason);
}

void RequireIn(const std::string& key, double value, double min, double max) {
  if (!(value >= min && value <= max)) {
    Bad(key, value, "must be in [" + common::DocNumber(min) + ", " + common::DocNumber(max) + "]");
  }
}

}  // namespace

const char* ToString(ObjectShape shape) {
  switch (shape) {
    case ObjectShape::kBox:
      return "box";
    case ObjectShape::kCylinder:
      return "cylinder";
    case ObjectShape::kSphere:
      return "sphere";
    case ObjectShape::kMug:
      return "mug";
    case ObjectShape::kBottle:
      return "bottle";
    case ObjectShape::kCup:
      return "cup";
    case ObjectShape::kWineGlass:
      return "wine_glass";
    case ObjectShape::kEgg:
      return "egg";
    case ObjectShape::kBanana:
      return "banana";
    case ObjectShape::kMesh:
      return "mesh";
  }
  return "?";
}

const char* ToString(HandModel model) { return model == HandModel::kJaw ? "jaw" : "prosthetic"; }

const char* ToString(GraspType grasp) { return grasp == GraspType::kWrap ? "wrap" : "pinch"; }

double SceneConfig::ObjectWidthM() const {
  const auto& size = object.size_m;
  switch (object.shape) {
    case ObjectShape::kBox:
      break;
    case ObjectShape::kBottle:  // pinched by the neck, 13 mm below the top; wrapped by the body
      return hand.grasp == GraspType::kWrap ? size[0] : size[1];
    case ObjectShape::kBanana:  // across its thickness
      return size[1];
    case ObjectShape::kCup:  // its diameter 13 mm below the rim
      return size[0] - (size[0] - size[1]) * std::min(1.0, 0.013 / size[2]);
    default:
      return size[0];
  }
  // A box's extent along the pinch (world x), turned by its yaw.
  return std::abs(std::cos(object.initial_yaw_rad)) * object.size_m[0] +
         std::abs(std::sin(object.initial_yaw_rad)) * object.size_m[1];
}

namespace {

/// Whether the wrap takes an object of this shape (by its upright cylindrical body).
bool WrapTakesShape(ObjectShape shape) {
  return shape == ObjectShape::kCylinder || shape == ObjectShape::kBottle || shape == ObjectShape::kMug;
}

}  // namespace

GraspType DefaultGrasp(const ObjectConfig& object, const HandConfig& hand) {
  if (hand.model != HandModel::kProsthetic || !WrapTakesShape(object.shape)) return GraspType::kPinch;
  const double diameter = object.size_m[0];
  const double height = object.size_m[2];
  const bool wrappable =
      diameter >= kMinDefaultWrapDiameterM && diameter <= kMaxDefaultWrapDiameterM && height >= diameter;
  return wrappable ? GraspType::kWrap : GraspType::kPinch;
}

double SceneConfig::OpenGapM() const {
  if (!std::isnan(hand.open_gap_m)) return hand.open_gap_m;
  return ObjectWidthM() + 2.0 * hand.preshape_clearance_m;
}

double SceneConfig::ThumbOppositionRad() const {
  return std::isnan(hand.thumb.opposition_rad) ? 0.0 : hand.thumb.opposition_rad;
}

std::string FormatConfigNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

std::string FormatConfigTriple(const std::array<double, 3>& values) {
  std::string text = "[";
  for (int k = 0; k < 3; ++k) {
    text += (k ? ", " : "") + (std::isnan(values[k]) ? std::string("auto") : FormatConfigNumber(values[k]));
  }
  return text + "]";
}

double SceneConfig::TorsionalFrictionM(double friction) const {
  if (!std::isnan(object.torsional_friction)) return object.torsional_friction;
  return 2.0 / 3.0 * friction * hand.contact_patch_radius_m;
}

double SceneConfig::Impratio() const {
  if (!std::isnan(physics.impratio)) return physics.impratio;
  const double stiffness = object.stiffness_n_m.value_or(StiffnessOfSolref(object));
  return std::clamp(kMaxImpratio * stiffness / kHardFrictionStiffnessNM, kMinAutoImpratio, kMaxImpratio);
}

double ObjectConfig::RestHalfHeightM() const {
  switch (shape) {
    case ObjectShape::kBox:
    case ObjectShape::kCylinder:
      return 0.5 * size_m[2];
    case ObjectShape::kSphere:
      return 0.5 * size_m[0];
    case ObjectShape::kBanana:
      return 0.5 * size_m[1];
    default:
      return 0.5 * size_m[2];
  }
}

const common::FieldTable<ObjectConfig>& ObjectConfigFields() {
  using Table = common::FieldTable<ObjectConfig>;
  using C = ObjectConfig;
  static const Table table(
      "object",
      {
          Table::Choice("shape", &C::shape,
                        {{ObjectShape::kBox, "box"},
                         {ObjectShape::kCylinder, "cylinder"},
                         {ObjectShape::kSphere, "sphere"},
                         {ObjectShape::kMug, "mug"},
                         {ObjectShape::kBottle, "bottle"},
                         {ObjectShape::kCup, "cup"},
                         {ObjectShape::kWineGlass, "wine_glass"},
                         {ObjectShape::kEgg, "egg"},
                         {ObjectShape::kBanana, "banana"},
                         {ObjectShape::kMesh, "mesh"}},
                        "the primitives, the library's everyday shapes (docs/scenarios.md, \"Object library\"), "
                        "or `mesh` (set by the `mesh` key)"),
          Table::Numbers("size_m", &C::size_m, NumberRule::Between(0.0, kMaxObjectSizeM), "m",
                         "box: edge lengths x, y, z; cylinder: diameter, unused, height (axis along z); "
                         "sphere: diameter, unused, unused; the library's shapes: docs/scenarios.md, \"Object "
                         "library\"; mesh: from the file")
              .Note("the ones the shape uses >= 0.001"),
          Table::Number("mass_kg", &C::mass_kg, NumberRule::Between(kMinObjectMassKg, kMaxObjectMassKg), "kg",
                        "uniform solid"),
          Table::Number("friction", &C::friction, {0.0, kMaxFriction, true}, "-",
                        "Coulomb coefficient of every contact with the object"),
          Table::Number("torsional_friction", &C::torsional_friction,
                        NumberRule::Between(0.0, kMaxTorsionalFrictionM), "m",
                        "torque about a contact's normal per newton of normal force, only with "
                        "`physics.condim` or `condim` >= 4; auto: the soft finger's (2/3) x `friction` x "
                        "`hand.contact_patch_radius_m`")
              .NanIsAuto(),
          Table::Integer("condim", &C::condim, 0, 6, "",
                         "contact dimensionality of this object's contacts; 0 = `physics.condim`; 6 adds "
                         "rolling friction (0.1 mm), which a soft object the pad sinks into needs")
              .Note("0, 3, 4 or 6"),
          Table::Number("solref_timeconst_s", &C::solref_timeconst_s, {0.0, kMaxSolrefTimeconstS, true}, "s",
                        "contact compliance (MuJoCo solref); larger = softer (e.g. a compliant cup: 0.006)")
              .Note(">= 2 x `physics.timestep_s`"),
          Table::Number("solref_dampratio", &C::solref_dampratio, {0.0, kMaxSolrefDampratio, true}, "-", ""),
          Table::Numbers("solimp", &C::solimp, NumberRule::Between(0.0, kMaxSolimpPower), "",
                         "MuJoCo solimp: dmin, dmax, width [m], midpoint, power")
              .Note("0 < dmin <= dmax < 1, 0 < width <= 0.1, midpoint 0 .. 1, power 1 .. 10"),
          Table::Numbers("initial_position_m", &C::initial_position_m,
                         NumberRule::Between(-kMaxPositionM, kMaxPositionM), "m",
                         "centre; z < 0 = resting on the table")
              .Note("x, y -0.3 .. 0.3 (on the table)"),
          Table::Number("initial_yaw_rad", &C::initial_yaw_rad, NumberRule::Between(-kMaxYawRad, kMaxYawRad),
                        "rad", "rotation about z"),
          Table::Number("crush_limit_n", &C::crush_limit_n, NumberRule::Between(0.0, kMaxForceN), "N",
                        "squeeze above which the object counts as crushed (scored, not simulated); 0 = not "
                        "fragile"),
          Table::Custom("name", "", "none", "a library object (`graspbed objects`)",
                        "start from this library object; the section's other keys override its values"),
          Table::Custom("mesh", "", "none", "an .stl or .obj file",
                        "the user's own object: this mesh (relative to the scenario's directory), hulled by "
                        "MuJoCo; sets `shape: mesh` and `size_m` from the file"),
          Table::OptionalNumber("scale", &C::scale, {0.0, 1000.0, true}, "-",
                                "mesh only: multiplies the file's coordinates into metres (0.001 for mm)"),
          Table::OptionalNumber("fill_fraction", &C::fill_fraction, NumberRule::Between(0.0, 1.0), "-",
                                "bottle only: share of the body's inner height filled with water, part of "
                                "`mass_kg`"),
          Table::OptionalNumber("stiffness_n_m", &C::stiffness_n_m, NumberRule::Between(kMinStiffnessNM, kMaxStiffnessNM),
                                "N/m",
                                "contact stiffness against a rigid surface; sets `solref_timeconst_s` and "
                                "`solimp` from it and the mass (docs/scenarios.md, \"Object compliance\")"),
      },
      [](const C& o) {
        if (o.condim != 0 && o.condim != 3 && o.condim != 4 && o.condim != 6)
          Bad("condim", o.condim, "must be 0 (physics.condim), 3, 4 or 6");
        const auto require_size = [&o](int i) {
          RequireIn("size_m[" + std::to_string(i) + "]", o.size_m[i], kMinObjectSizeM, kMaxObjectSizeM);
        };
        switch (o.shape) {
          case ObjectShape::kBox:
          case ObjectShape::kMug:
          case ObjectShape::kBottle:
          case ObjectShape::kCup:
          case ObjectShape::kWineGlass:
          case ObjectShape::kBanana:
          case ObjectShape::kMesh:
            for (int i = 0; i < 3; ++i) require_size(i);
            break;
          case ObjectShape::kCylinder:
          case ObjectShape::kEgg:
            require_size(0);
            require_size(2);
            break;
          case ObjectShape::kSphere:
            require_size(0);
            break;
        }
        if (o.shape == ObjectShape::kMug && !(o.size_m[1] >= o.size_m[0] + 0.015))
          Bad("size_m[1]", o.size_m[1], "a mug's depth with the handle must exceed its diameter by >= 0.015 m");
        if (o.shape == ObjectShape::kBottle && !(o.size_m[1] < o.size_m[0]))
          Bad("size_m[1]", o.size_m[1], "a bottle's neck must be narrower than its body (size_m[0])");
        if (o.shape == ObjectShape::kWineGlass && !(o.size_m[2] >= 0.05 && o.size_m[0] >= 0.02))
          Bad("size_m[2]", o.size_m[2], "a wine glass needs a height >= 0.05 m and a bowl >= 0.02 m across");
        if (o.shape == ObjectShape::kBanana && !(o.size_m[2] < 0.5 * o.size_m[0]))
          Bad("size_m[2]", o.size_m[2], "a banana's bow must be under half its chord (size_m[0])");
        if (o.shape == ObjectShape::kMesh && o.mesh.empty())
          throw common::ConfigError("", 0, "shape", "mesh", "give the file with `mesh: FILE` instead");
        if (o.shape != ObjectShape::kMesh && !o.mesh.empty())
          throw common::ConfigError("", 0, "shape", ToString(o.shape),
                                    "an object given by `mesh` has shape mesh; drop `shape` (and `size_m`)");
        if (o.shape != ObjectShape::kMesh && o.scale)
          Bad("scale", *o.scale, "only for a mesh (`mesh: FILE`)");
        if (o.fill_fraction) {
          if (o.shape != ObjectShape::kBottle) Bad("fill_fraction", *o.fill_fraction, "only for shape bottle");
          const double liquid_kg = LiquidMassKg(o);
          if (!(liquid_kg < o.mass_kg))
            Bad("fill_fraction", *o.fill_fraction,
                "the water alone weighs " + common::ReadableNumber(liquid_kg) + " kg, more than mass_kg (" +
                    common::ReadableNumber(o.mass_kg) + " kg, bottle and water)");
        }
        if (!(o.solimp[0] > 0.0 && o.solimp[0] <= o.solimp[1] && o.solimp[1] < 1.0)) {
          Bad("solimp[1]", o.solimp[1], "need 0 < dmin <= dmax < 1");
        }
        if (!(o.solimp[2] > 0.0)) Bad("solimp[2]", o.solimp[2], "must be > 0");
        RequireIn("solimp[2]", o.solimp[2], 0.0, kMaxSolimpWidthM);
        RequireIn("solimp[3]", o.solimp[3], 0.0, 1.0);
        RequireIn("solimp[4]", o.solimp[4], 1.0, kMaxSolimpPower);
        for (int k = 0; k < 2; ++k) {
          RequireIn("initial_position_m[" + std::to_string(k) + "]", o.initial_position_m[k],
                    -kMaxObjectOffsetM, kMaxObjectOffsetM);
        }
      });
  return table;
}

namespace {

const common::FieldTable<MotorConfig>& MotorConfigFields() {
  using Table = common::FieldTable<MotorConfig>;
  using C = MotorConfig;
  static const Table table(
      "motor",
      {
          Table::Number("stall_force_n", &C::stall_force_n, {0.0, kMaxStallForceN, true}, "N",
                        "jaw only: tendon (= static pinch) force at effort 1"),
          Table::Number("no_load_speed_m_s", &C::no_load_speed_m_s, {0.0, kMaxDigitSpeedMS, true}, "m/s",
                        "jaw only: closing speed of the gap at effort 1, no load"),
          Table::Number("armature_kg", &C::armature_kg, NumberRule::Between(0.0, kMaxArmatureKg), "kg",
                        "jaw only: reflected rotor inertia per digit slide"),
          Table::Number("damping_n_s_m", &C::damping_n_s_m, NumberRule::Between(0.0, kMaxMotorDampingNSM),
                        "N s/m", "jaw only: viscous friction per digit slide"),
      });
  return table;
}

const common::FieldTable<FingerConfig>& FingerConfigFields() {
  using Table = common::FieldTable<FingerConfig>;
  using C = FingerConfig;
  static const Table table(
      "finger",
      {
          Table::Number("proximal_length_m", &C::proximal_length_m, NumberRule::Between(0.02, 0.07), "m",
                        "prosthetic index, MCP -> PIP"),
          Table::Number("middle_length_m", &C::middle_length_m, NumberRule::Between(0.01, 0.05), "m",
                        "PIP -> DIP (the distal phalanx is the holder, its length from the layout)"),
          Table::Number("pip_mcp_ratio", &C::pip_mcp_ratio, NumberRule::Between(0.5, 2.0), "-",
                        "PIP flexion per radian of MCP flexion, fixed by the linkage"),
          Table::Number("dip_flexion_rad", &C::dip_flexion_rad, NumberRule::Between(0.0, 1.0), "rad",
                        "fixed DIP flexion"),
          Table::Number("mcp_rest_angle_rad", &C::mcp_rest_angle_rad, NumberRule::Between(-0.6, 0.6), "rad",
                        "angle of the proximal phalanx below the palm plane at MCP = 0. With the three "
                        "above it must leave the pad able to meet a 50 mm object squarely inside the MCP "
                        "range, else the load fails with `hand.finger: the pad cannot meet an object "
                        "squarely`"),
      });
  return table;
}

const common::FieldTable<ThumbConfig>& ThumbConfigFields() {
  using Table = common::FieldTable<ThumbConfig>;
  using C = ThumbConfig;
  static const Table table(
      "thumb",
      {
          Table::Number("proximal_length_m", &C::proximal_length_m, NumberRule::Between(0.02, 0.07), "m",
                        "flexion joint (CMC) -> IP"),
          Table::Number("distal_length_m", &C::distal_length_m, NumberRule::Between(0.01, 0.05), "m",
                        "IP -> tip centre"),
          Table::Number("tip_radius_m", &C::tip_radius_m, NumberRule::Between(0.004, 0.015), "m",
                        "the rounded, unsensorised tip"),
          Table::Number("ip_flexion_rad", &C::ip_flexion_rad, NumberRule::Between(0.0, 1.2), "rad",
                        "fixed interphalangeal flexion"),
          Table::Number("opposition_rad", &C::opposition_rad, NumberRule::Between(-0.2, 1.7), "rad",
                        "rotation about the palm normal, held during the run; auto: 0 in a pinch (the thumb "
                        "flexes in the index's plane)")
              .NanIsAuto(),
      });
  return table;
}

const common::FieldTable<DigitMotorConfig>& DigitMotorConfigFields() {
  using Table = common::FieldTable<DigitMotorConfig>;
  using C = DigitMotorConfig;
  static const Table table(
      "digit_motor",
      {
          Table::Number("stall_pinch_force_n", &C::stall_pinch_force_n, NumberRule::Between(1.0, 200.0), "N",
                        "fingertip force of each digit at stall, effort 1, in this object's contact "
                        "posture: each motor's stall torque is this x the digit's lever arm there (the "
                        "static pinch is this x effort)"),
          Table::Number("no_load_speed_rad_s", &C::no_load_speed_rad_s, NumberRule::Between(0.1, 50.0),
                        "rad/s",
                        "index MCP speed at effort 1, no load (open to closed in about 1 s); the thumb's is "
                        "scaled by the lever arms so both contacts close at the same speed"),
          Table::Number("armature_kg_m2", &C::armature_kg_m2, NumberRule::Between(0.0, 1.0), "kg m^2",
                        "reflected rotor + gearbox inertia on each driven joint"),
          Table::Number("damping_n_m_s", &C::damping_n_m_s, NumberRule::Between(0.0, 10.0), "N m s/rad",
                        "viscous friction on every finger joint (the back-EMF comes on top)"),
          Table::Number("wrap_thumb_share", &C::wrap_thumb_share, NumberRule::Between(0.05, 1.0), "",
                        "in a wrap, the thumb's stall force as a share of the pad's: the palm takes the rest "
                        "of the pad's squeeze (at 1 the thumb presses the cylinder off the palm)"),
      });
  return table;
}

}  // namespace

const common::FieldTable<HandConfig>& HandConfigFields() {
  using Table = common::FieldTable<HandConfig>;
  using C = HandConfig;
  static const Table table(
      "hand",
      {
          Table::Choice("model", &C::model,
                        {{HandModel::kProsthetic, "prosthetic"}, {HandModel::kJaw, "jaw"}},
                        "`prosthetic`: index finger flexing at MCP and PIP (linkage), the holder as its "
                        "distal phalanx, opposable thumb, one DC motor per digit. `jaw`: the slide-joint "
                        "bench fixture (docs/simulation.md, \"The jaw fixture\")"),
          Table::Choice("grasp", &C::grasp, {{GraspType::kPinch, "pinch"}, {GraspType::kWrap, "wrap"}},
                        "the grasp the pre-shape prepares. `pinch`: index fingertip pad against the thumb "
                        "tip, placed from the object's geometry (a box or cylinder 13 mm below its top, a ball, "
                        "an egg or a banana through its round section's centre, other shapes and meshes at "
                        "their most parallel faces: docs/simulation.md, \"How a placement is chosen\"). `wrap` "
                        "(prosthetic hand, upright cylinder, a bottle's or a mug's body): the palm faces the "
                        "cylinder from the side at its mid-height, the index curls round it until its pad "
                        "presses it against the palm, the thumb closes round its other side "
                        "(docs/simulation.md, \"The wrap\"). Unset with a library object (`object: {name: "
                        "...}`): chosen from its shape and size, wrap for a can, a bottle or a mug 40 to 90 mm "
                        "across, pinch for the rest (`graspbed objects` lists each one's)"),
          Table::Number("open_gap_m", &C::open_gap_m, NumberRule::Between(kMinOpenGapM, kMaxOpenGapM), "m",
                        "pre-shape aperture between the pad's mesa tops and the thumb's contact point. "
                        "Unset (auto), it follows the object: its width across the pinch + 2 x "
                        "`preshape_clearance_m` (65 mm for the 50 mm box), so `--set object.size_m=[w,d,h]` "
                        "alone re-targets the grasp. Set, it stays whatever the object. A pre-shape wider "
                        "than the prosthetic hand opens (186.84 mm) is refused")
              .NanIsAuto()
              .Note("wider than the object across the pinch"),
          Table::Bool("pinch_square_pad", &C::pinch_square_pad,
                      "pinch: the pad meets the object square (its posture in the nominal 50 mm pinch) and "
                      "the thumb closes the rest of the way; false: both digits meet it equally far from "
                      "the hand's centre, the pad tilted for any other width"),
          Table::Number("preshape_clearance_m", &C::preshape_clearance_m, NumberRule::Between(0.0, 0.05), "m",
                        "clearance on each side of the object in the automatic pre-shape"),
          Table::Number("contact_patch_radius_m", &C::contact_patch_radius_m, NumberRule::Between(0.0, 0.02), "m",
                        "a fingertip's contact patch on an object: the soft finger's spin friction (2/3) mu x "
                        "this (half the default holder's minor axis)"),
          Table::Number("palm_mass_kg", &C::palm_mass_kg, NumberRule::Between(kMinPalmMassKg, kMaxPalmMassKg),
                        "kg", "palm with wrist carriage"),
          Table::Number("digit_mass_kg", &C::digit_mass_kg,
                        NumberRule::Between(kMinDigitMassKg, kMaxDigitMassKg), "kg",
                        "each digit (prosthetic: index 50/25/25 % over its phalanges, thumb 60/40 %)"),
          Table::Number("friction", &C::friction, {0.0, kMaxFriction, true}, "-",
                        "hand geoms against geoms without contact priority (the table)"),
          Table::Numbers("initial_wrist_position_m", &C::initial_wrist_position_m,
                         NumberRule::Between(-kMaxPositionM, kMaxPositionM), "m",
                         "wrist start; each auto (unset) entry is chosen from the object: x, y over the "
                         "object's start, z so that the contacts meet it at the pinch height (prosthetic) or "
                         "the holder centre is level with the object's centre (jaw)")
              .NanIsAuto(),
          Table::Number("wrist_stiffness_n_m", &C::wrist_stiffness_n_m, {0.0, kMaxWristStiffnessNM, true},
                        "N/m", "wrist position servo per axis"),
          Table::Number("wrist_damping_n_s_m", &C::wrist_damping_n_s_m,
                        NumberRule::Between(0.0, kMaxWristDampingNSM), "N s/m", ""),
          Table::Section("motor", &C::motor, MotorConfigFields()),
          Table::Section("finger", &C::finger, FingerConfigFields()),
          Table::Section("thumb", &C::thumb, ThumbConfigFields()),
          Table::Section("digit_motor", &C::digit_motor, DigitMotorConfigFields()),
      });
  return table;
}

const common::FieldTable<PhysicsConfig>& PhysicsConfigFields() {
  using Table = common::FieldTable<PhysicsConfig>;
  using C = PhysicsConfig;
  static const Table table(
      "physics",
      {
          Table::Number("timestep_s", &C::timestep_s, NumberRule::Between(kMinTimestepS, kMaxTimestepS), "s",
                        "physics step"),
          Table::Bool("elliptic_cones", &C::elliptic_cones,
                      "elliptic friction cones; pyramidal cones drop held objects (docs/simulation.md)"),
          Table::Number("impratio", &C::impratio, NumberRule::Between(1.0, kMaxImpratio), "-",
                        "friction-to-normal impedance ratio; auto: 1000 for an object at least 2.5e6 N/m "
                        "stiff (soft-contact creep near 1 um/s without noslip), 1000 x stiffness / 2.5e6 N/m "
                        "for a softer one, at least 10 (docs/simulation.md, \"Friction on a sunk pad\")")
              .NanIsAuto(),
          Table::Integer(
              "noslip_iterations", &C::noslip_iterations, 0, kMaxNoslipIterations, "",
              "post-solve friction projection (removes soft-contact creep; costs a J M^-1 J' per step)"),
          Table::Integer("solver_iterations", &C::solver_iterations, 1, kMaxSolverIterations, "",
                         "Newton iterations"),
          Table::Number("tolerance", &C::tolerance, NumberRule::Between(kMinTolerance, kMaxTolerance), "-",
                        "solver tolerance"),
          Table::Integer("condim", &C::condim, 3, 6, "",
                         "object contact dimensionality: 4, the soft finger, resists spin about each contact "
                         "normal; 3, point contacts an object pivots about; 6 adds rolling friction")
              .Note("not 5"),
          Table::Number("gravity_m_s2", &C::gravity_m_s2, NumberRule::Between(0.0, kMaxGravityMS2), "m/s^2",
                        "along -z; 0 = off"),
          Table::Bool("table", &C::table, "include the table (off for free-floating tests)"),
          Table::Bool("contact_pairs", &C::contact_pairs,
                      "list the geom pairs that can touch; false: MuJoCo's broad phase finds them (same "
                      "contacts, slower)"),
      },
      [](const C& p) {
        if (p.condim != 3 && p.condim != 4 && p.condim != 6) Bad("condim", p.condim, "must be 3, 4 or 6");
      });
  return table;
}

const common::FieldTable<SceneConfig>& SceneConfigFields() {
  using Table = common::FieldTable<SceneConfig>;
  using C = SceneConfig;
  static const Table table(
      "scene",
      {
          Table::Section("object", &C::object, ObjectConfigFields()),
          Table::Section("hand", &C::hand, HandConfigFields()),
          Table::Section("physics", &C::physics, PhysicsConfigFields()),
      },
      [](const C& scene) {
        if (scene.object.solref_timeconst_s < 2.0 * scene.physics.timestep_s) {
          Bad("object.solref_timeconst_s", scene.object.solref_timeconst_s,
              "must be >= 2 x physics.timestep_s");
        }
        if (scene.hand.grasp == GraspType::kWrap) {
          const auto refuse = [](const std::string& key, const std::string& value, const std::string& why) {
            throw common::ConfigError("", 0, key, value, why);
          };
          if (scene.hand.model != HandModel::kProsthetic)
            refuse("hand.grasp", "wrap", "needs hand.model prosthetic (the jaw fixture only pinches)");
          if (!WrapTakesShape(scene.object.shape))
            refuse("hand.grasp", "wrap",
                   std::string("needs an upright cylinder, a bottle or a mug (by its body), not object.shape ") +
                       ToString(scene.object.shape));
          if (!std::isnan(scene.hand.open_gap_m))
            Bad("hand.open_gap_m", scene.hand.open_gap_m,
                "is the pinch's aperture; a wrap opens each digit by hand.preshape_clearance_m");
        }
        if (scene.OpenGapM() <= scene.ObjectWidthM()) {
          Bad("hand.open_gap_m", scene.OpenGapM(),
              "the pre-shape must be wider than the object (object.size_m across the grasp: " +
                  std::to_string(scene.ObjectWidthM()) + " m)");
        }
      });
  return table;
}

void SceneConfig::Validate() const { SceneConfigFields().Validate(*this); }

double SolrefTimeconstForStiffness(double stiffness_n_m, double mass_kg, double dampratio) {
  return std::sqrt(mass_kg / ((1.0 - kStiffnessImpedance) * stiffness_n_m)) / dampratio;
}

double StiffnessOfSolref(const ObjectConfig& object) {
  const double tau = object.solref_timeconst_s * object.solref_dampratio;
  return object.mass_kg / ((1.0 - object.solimp[1]) * tau * tau);
}

namespace {

// Before the section's keys are read: the library entry or the mesh the section starts from.
void StartObject(const common::YamlMap& map, ObjectConfig* object) {
  if (map.Has("name")) {
    if (map.Has("mesh")) map.Fail("mesh", "give either `name` (a library object) or `mesh` (your own), not both");
    const std::string name = map.GetString("name", "");
    const ObjectLibrary* library = nullptr;
    try {
      library = &ShippedObjectLibrary();
    } catch (const common::ConfigError&) {
      throw;
    } catch (const std::exception& error) {
      map.Fail("name", std::string("cannot read the object library: ") + error.what());
    }
    const LibraryObject* entry = library->Find(name);
    if (entry == nullptr)
      map.Fail("name", "unknown object; the library (" + library->path() + ") has: " + library->NameList());
    *object = entry->object;
    // `--set object.name=apple` on a file whose object is a box keeps the box's keys beside the name:
    // say so, since the run is then no apple (a shape beside a name is allowed, as any key is).
    if (map.Has("shape") && map.GetString("shape", "") != ToString(entry->object.shape)) {
      std::cerr << "warning: " << map.file() << ": object.name = " << name << " beside "
                << "object.shape = " << map.GetString("shape", "") << ": the library's " << name
                << " is a " << ToString(entry->object.shape)
                << "; the object is the section's shape with the library entry's other keys where the section "
                   "does not set them (to get the library's object, give `name` alone)\n";
    }
  }
  if (map.Has("mesh")) {
    std::filesystem::path path(map.GetString("mesh", ""));
    if (path.empty()) map.Fail("mesh", "empty path");
    if (path.is_relative() && !map.file().empty() && map.file().front() != '<') {
      path = std::filesystem::path(map.file()).parent_path() / path;
    }
    object->shape = ObjectShape::kMesh;
    object->mesh = std::filesystem::absolute(path).lexically_normal().string();
  }
  // A section that sets the compliance directly drops the stiffness it would otherwise inherit.
  if ((map.Has("solref_timeconst_s") || map.Has("solimp")) && !map.Has("stiffness_n_m"))
    object->stiffness_n_m.reset();
}

// After the section's keys are read: a mesh's size from its file, the stiffness as solref / solimp.
void FinishObject(const common::YamlMap& map, double timestep_s, ObjectConfig* object) {
  if (object->shape == ObjectShape::kMesh && !object->mesh.empty()) {
    if (map.Has("size_m")) map.Fail("size_m", "a mesh's size comes from its file; scale it with `scale`");
    const std::string key = map.Has("mesh") ? "mesh" : "shape";
    try {
      const MeshFile mesh = ReadMeshFile(object->mesh);
      const double scale = object->scale.value_or(1.0);
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
      for (const Eigen::Vector3d& v : mesh.vertices) {
        lo = lo.cwiseMin(v * scale);
        hi = hi.cwiseMax(v * scale);
      }
      for (int k = 0; k < 3; ++k) object->size_m[k] = hi[k] - lo[k];
      for (int k = 0; k < 3; ++k) {
        if (!(object->size_m[k] >= kMinObjectSizeM && object->size_m[k] <= kMaxObjectSizeM)) {
          std::ostringstream why;
          why << "the mesh scaled by " << scale << " is " << object->size_m[0] << " x " << object->size_m[1]
              << " x " << object->size_m[2] << " m; each extent must be in [" << kMinObjectSizeM << ", "
              << kMaxObjectSizeM << "] m (is the file in mm? `scale: 0.001`)";
          map.Fail(key, why.str());
        }
      }
      const std::string warning = MeshHullWarning(object->mesh, scale);
      if (!warning.empty()) std::cerr << "warning: " << warning << "\n";
    } catch (const std::invalid_argument& error) {
      map.Fail(key, error.what());
    }
  }
  if (object->stiffness_n_m) {
    const std::string key = map.Has("stiffness_n_m") || !map.Has("name") ? "stiffness_n_m" : "name";
    const double stiffness = *object->stiffness_n_m;
    const double tau = SolrefTimeconstForStiffness(stiffness, object->mass_kg, object->solref_dampratio);
    const double factor = object->mass_kg / ((1.0 - kStiffnessImpedance) * object->solref_dampratio *
                                             object->solref_dampratio);
    if (tau < 2.0 * timestep_s) {
      map.Fail(key, "stiffness_n_m " + common::ReadableNumber(stiffness) + " N/m is too stiff for " +
                        common::ReadableNumber(object->mass_kg) + " kg at physics.timestep_s " +
                        common::ReadableNumber(timestep_s) + " (solref time constant " + common::ReadableNumber(tau) +
                        " s < 2 x timestep); at most " +
                        common::ReadableNumber(factor / (4.0 * timestep_s * timestep_s)) + " N/m");
    }
    if (tau > kMaxSolrefTimeconstS) {
      map.Fail(key, "stiffness_n_m " + common::ReadableNumber(stiffness) + " N/m is too soft for " +
                        common::ReadableNumber(object->mass_kg) + " kg (solref time constant " +
                        common::ReadableNumber(tau) + " s > " + common::ReadableNumber(kMaxSolrefTimeconstS) +
                        " s); at least " +
                        common::ReadableNumber(factor / (kMaxSolrefTimeconstS * kMaxSolrefTimeconstS)) + " N/m");
    }
    object->solref_timeconst_s = tau;
    object->solimp = {kStiffnessImpedance, kStiffnessImpedance, 0.001, 0.5, 2.0};
  }
}

}  // namespace

SceneConfig LoadSceneConfig(const common::YamlMap& map) {
  SceneConfig scene;
  const std::optional<common::YamlMap> object_map = map.GetMap("object");
  if (object_map) StartObject(*object_map, &scene.object);
  SceneConfigFields().Load(map, &scene);
  if (object_map) {
    FinishObject(*object_map, scene.physics.timestep_s, &scene.object);
    // A library object the scenario grasps without saying how: the grasp its size and shape call for.
    const std::optional<common::YamlMap> hand_map = map.GetMap("hand");
    const bool grasp_stated = hand_map && (hand_map->Has("grasp") || hand_map->Has("open_gap_m"));
    if (object_map->Has("name") && !grasp_stated) scene.hand.grasp = DefaultGrasp(scene.object, scene.hand);
    // The size and compliance may have changed: the scene's rules again.
    try {
      SceneConfigFields().ValidateRelative(scene);
    } catch (const common::ConfigError& error) {
      map.FailAt(error);
    }
  }
  return scene;
}

ObjectConfig LoadLibraryObjectConfig(const common::YamlMap& map, const std::vector<std::string>& also_valid) {
  if (map.Has("mesh")) map.Fail("mesh", "library objects are built from shapes, not from files");
  ObjectConfig object;
  ObjectConfigFields().Load(map, &object, also_valid);
  object.name = map.RequireString("name");
  FinishObject(map, PhysicsConfig{}.timestep_s, &object);
  SceneConfig scene;
  scene.object = object;
  try {
    SceneConfigFields().ValidateRelative(scene);
    ObjectParts(object);  // a shape that cannot be built fails here, not in a run
  } catch (const common::ConfigError& error) {
    map.FailAt(error);
  } catch (const std::invalid_argument& error) {
    map.FailHere(error.what());
  }
  return object;
}

void EmitSceneConfig(const SceneConfig& scene, YAML::Emitter& out) {
  out << YAML::Key << "object" << YAML::Value << YAML::BeginMap;
  // A mesh's size comes from its file when the config is read back.
  const std::vector<std::string> derived =
      scene.object.mesh.empty() ? std::vector<std::string>{} : std::vector<std::string>{"size_m"};
  ObjectConfigFields().Emit(scene.object, out, derived);
  if (!scene.object.name.empty()) out << YAML::Key << "name" << YAML::Value << scene.object.name;
  if (!scene.object.mesh.empty()) out << YAML::Key << "mesh" << YAML::Value << scene.object.mesh;
  out << YAML::EndMap;
  SceneConfigFields().Emit(scene, out, {"object"});
}

SceneConfig LoadSceneConfigFile(const std::string& path) {
  return LoadSceneConfig(common::YamlMap::LoadFile(path));
}

}  // namespace graspbed::sim

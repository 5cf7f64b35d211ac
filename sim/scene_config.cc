#include "sim/scene_config.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

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
  }
  return "?";
}

const char* ToString(HandModel model) { return model == HandModel::kJaw ? "jaw" : "prosthetic"; }

const char* ToString(GraspType grasp) { return grasp == GraspType::kWrap ? "wrap" : "pinch"; }

double SceneConfig::ObjectWidthM() const {
  if (object.shape != ObjectShape::kBox) return object.size_m[0];
  // A box's extent along the pinch (world x), turned by its yaw.
  return std::abs(std::cos(object.initial_yaw_rad)) * object.size_m[0] +
         std::abs(std::sin(object.initial_yaw_rad)) * object.size_m[1];
}

double SceneConfig::OpenGapM() const {
  if (!std::isnan(hand.open_gap_m)) return hand.open_gap_m;
  return ObjectWidthM() + 2.0 * hand.preshape_clearance_m;
}

double SceneConfig::ThumbOppositionRad() const {
  return std::isnan(hand.thumb.opposition_rad) ? 0.0 : hand.thumb.opposition_rad;
}

double ObjectConfig::RestHalfHeightM() const {
  switch (shape) {
    case ObjectShape::kBox:
    case ObjectShape::kCylinder:
      return 0.5 * size_m[2];
    case ObjectShape::kSphere:
      return 0.5 * size_m[0];
  }
  return 0.0;
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
                         {ObjectShape::kSphere, "sphere"}},
                        ""),
          Table::Numbers("size_m", &C::size_m, NumberRule::Between(0.0, kMaxObjectSizeM), "m",
                         "box: edge lengths x, y, z; cylinder: diameter, unused, height (axis along z); "
                         "sphere: diameter, unused, unused")
              .Note("the ones the shape uses >= 0.001"),
          Table::Number("mass_kg", &C::mass_kg, NumberRule::Between(kMinObjectMassKg, kMaxObjectMassKg), "kg",
                        "uniform solid"),
          Table::Number("friction", &C::friction, {0.0, kMaxFriction, true}, "-",
                        "Coulomb coefficient of every contact with the object"),
          Table::Number("torsional_friction", &C::torsional_friction,
                        NumberRule::Between(0.0, kMaxTorsionalFrictionM), "m",
                        "only with `physics.condim` >= 4"),
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
      },
      [](const C& o) {
        const int used_sizes = o.shape == ObjectShape::kBox ? 3 : 1;
        for (int i = 0; i < used_sizes; ++i) {
          RequireIn("size_m[" + std::to_string(i) + "]", o.size_m[i], kMinObjectSizeM, kMaxObjectSizeM);
        }
        if (o.shape == ObjectShape::kCylinder) {
          RequireIn("size_m[2]", o.size_m[2], kMinObjectSizeM, kMaxObjectSizeM);
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
                        "tip, near the object's top (a box or cylinder 13 mm below its top, a sphere at its "
                        "equator). `wrap` (prosthetic hand, upright cylinder): the palm faces the cylinder "
                        "from the side at its mid-height, the index curls round it until its pad presses it "
                        "against the palm, the thumb closes round its other side (docs/simulation.md, "
                        "\"The wrap\")"),
          Table::Number("open_gap_m", &C::open_gap_m, NumberRule::Between(kMinOpenGapM, kMaxOpenGapM), "m",
                        "pre-shape aperture between the pad's mesa tops and the thumb's contact point. "
                        "Unset (auto), it follows the object: its width across the pinch + 2 x "
                        "`preshape_clearance_m` (65 mm for the 50 mm box), so `--set object.size_m=[w,d,h]` "
                        "alone re-targets the grasp. Set, it stays whatever the object. A pre-shape wider "
                        "than the prosthetic hand opens (186.84 mm) is refused")
              .NanIsAuto()
              .Note("wider than the object across the pinch"),
          Table::Number("preshape_clearance_m", &C::preshape_clearance_m, NumberRule::Between(0.0, 0.05), "m",
                        "clearance on each side of the object in the automatic pre-shape"),
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
          Table::Number(
              "impratio", &C::impratio, NumberRule::Between(1.0, kMaxImpratio), "-",
              "friction-to-normal impedance ratio; 1000 keeps soft-contact creep near 1 um/s without noslip"),
          Table::Integer(
              "noslip_iterations", &C::noslip_iterations, 0, kMaxNoslipIterations, "",
              "post-solve friction projection (removes soft-contact creep; costs a J M^-1 J' per step)"),
          Table::Integer("solver_iterations", &C::solver_iterations, 1, kMaxSolverIterations, "",
                         "Newton iterations"),
          Table::Number("tolerance", &C::tolerance, NumberRule::Between(kMinTolerance, kMaxTolerance), "-",
                        "solver tolerance"),
          Table::Integer("condim", &C::condim, 3, 6, "", "object contact dimensionality").Note("not 5"),
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
          if (scene.object.shape != ObjectShape::kCylinder)
            refuse(
                "hand.grasp", "wrap",
                std::string("needs an upright cylinder, not object.shape ") + ToString(scene.object.shape));
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

SceneConfig LoadSceneConfig(const common::YamlMap& map) {
  SceneConfig scene;
  SceneConfigFields().Load(map, &scene);
  return scene;
}

SceneConfig LoadSceneConfigFile(const std::string& path) {
  return LoadSceneConfig(common::YamlMap::LoadFile(path));
}

}  // namespace graspbed::sim

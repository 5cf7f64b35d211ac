#include "sim/scene_config.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace graspbed::sim {
namespace {

[[noreturn]] void Bad(const std::string& field, double value, const std::string& reason) {
  std::ostringstream message;
  message << "scene." << field << " = " << value << ": " << reason;
  throw std::invalid_argument(message.str());
}

void RequirePositive(const std::string& field, double value) {
  if (!(value > 0.0) || !std::isfinite(value)) Bad(field, value, "must be > 0");
}

void RequireNonNegative(const std::string& field, double value) {
  if (!(value >= 0.0) || !std::isfinite(value)) Bad(field, value, "must be >= 0");
}

void RequireIn(const std::string& field, double value, double min, double max) {
  if (!(value >= min && value <= max)) {
    std::ostringstream reason;
    reason << "must be in [" << min << ", " << max << "]";
    Bad(field, value, reason.str());
  }
}

void RequireAtMost(const std::string& field, double value, double max) {
  if (value > max) {
    std::ostringstream reason;
    reason << "must be <= " << max;
    Bad(field, value, reason.str());
  }
}

HandModel ParseHandModel(const std::string& text) {
  return text == "jaw" ? HandModel::kJaw : HandModel::kProsthetic;  // GetString restricted the names
}

GraspType ParseGrasp(const std::string&) { return GraspType::kPinch; }  // the only name GetString allows

ObjectShape ParseShape(const std::string& text) {
  if (text == "box") return ObjectShape::kBox;
  if (text == "cylinder") return ObjectShape::kCylinder;
  return ObjectShape::kSphere;  // GetString already restricted the value to the three names
}

std::array<double, 3> GetTriple(const common::YamlMap& map, std::string_view key,
                                std::array<double, 3> fallback, common::NumberRule rule = {}) {
  const std::vector<double> list =
      map.GetNumberList(key, std::vector<double>(fallback.begin(), fallback.end()), 3, rule);
  return {list[0], list[1], list[2]};
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

const char* ToString(GraspType) { return "pinch"; }

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

void SceneConfig::Validate() const {
  const int used_sizes = object.shape == ObjectShape::kBox ? 3 : 1;
  for (int i = 0; i < used_sizes; ++i) {
    RequireIn("object.size_m[" + std::to_string(i) + "]", object.size_m[i], kMinObjectSizeM, kMaxObjectSizeM);
  }
  if (object.shape == ObjectShape::kCylinder) {
    RequireIn("object.size_m[2]", object.size_m[2], kMinObjectSizeM, kMaxObjectSizeM);
  }
  RequireIn("object.mass_kg", object.mass_kg, kMinObjectMassKg, kMaxObjectMassKg);
  RequirePositive("object.friction", object.friction);
  RequireAtMost("object.friction", object.friction, kMaxFriction);
  RequireIn("object.torsional_friction", object.torsional_friction, 0.0, kMaxTorsionalFrictionM);
  if (object.solref_timeconst_s < 2.0 * physics.timestep_s) {
    Bad("object.solref_timeconst_s", object.solref_timeconst_s, "must be >= 2 x physics.timestep_s");
  }
  RequireAtMost("object.solref_timeconst_s", object.solref_timeconst_s, kMaxSolrefTimeconstS);
  RequirePositive("object.solref_dampratio", object.solref_dampratio);
  RequireAtMost("object.solref_dampratio", object.solref_dampratio, kMaxSolrefDampratio);
  if (!(object.solimp[0] > 0.0 && object.solimp[0] <= object.solimp[1] && object.solimp[1] < 1.0)) {
    Bad("object.solimp[1]", object.solimp[1], "need 0 < dmin <= dmax < 1");
  }
  RequirePositive("object.solimp[2]", object.solimp[2]);
  RequireAtMost("object.solimp[2]", object.solimp[2], kMaxSolimpWidthM);
  RequireIn("object.solimp[3]", object.solimp[3], 0.0, 1.0);
  RequireIn("object.solimp[4]", object.solimp[4], 1.0, kMaxSolimpPower);
  for (int k = 0; k < 2; ++k) {
    RequireIn("object.initial_position_m[" + std::to_string(k) + "]", object.initial_position_m[k],
              -kMaxObjectOffsetM, kMaxObjectOffsetM);
  }
  RequireIn("object.initial_position_m[2]", object.initial_position_m[2], -kMaxPositionM, kMaxPositionM);
  RequireIn("object.initial_yaw_rad", object.initial_yaw_rad, -kMaxYawRad, kMaxYawRad);
  RequireIn("object.crush_limit_n", object.crush_limit_n, 0.0, kMaxForceN);
  if (!std::isnan(hand.open_gap_m)) {
    RequireIn("hand.open_gap_m", hand.open_gap_m, kMinOpenGapM, kMaxOpenGapM);
  }
  RequireNonNegative("hand.preshape_clearance_m", hand.preshape_clearance_m);
  if (OpenGapM() <= ObjectWidthM()) {
    Bad("hand.open_gap_m", OpenGapM(),
        "the pre-shape must be wider than the object (object.size_m across the grasp: " +
            std::to_string(ObjectWidthM()) + " m)");
  }
  RequirePositive("hand.finger.proximal_length_m", hand.finger.proximal_length_m);
  RequirePositive("hand.finger.middle_length_m", hand.finger.middle_length_m);
  RequirePositive("hand.finger.pip_mcp_ratio", hand.finger.pip_mcp_ratio);
  RequirePositive("hand.thumb.proximal_length_m", hand.thumb.proximal_length_m);
  RequirePositive("hand.thumb.distal_length_m", hand.thumb.distal_length_m);
  RequirePositive("hand.thumb.tip_radius_m", hand.thumb.tip_radius_m);
  RequirePositive("hand.digit_motor.stall_pinch_force_n", hand.digit_motor.stall_pinch_force_n);
  RequirePositive("hand.digit_motor.no_load_speed_rad_s", hand.digit_motor.no_load_speed_rad_s);
  RequireNonNegative("hand.digit_motor.armature_kg_m2", hand.digit_motor.armature_kg_m2);
  RequireNonNegative("hand.digit_motor.damping_n_m_s", hand.digit_motor.damping_n_m_s);
  RequireIn("hand.palm_mass_kg", hand.palm_mass_kg, kMinPalmMassKg, kMaxPalmMassKg);
  RequireIn("hand.digit_mass_kg", hand.digit_mass_kg, kMinDigitMassKg, kMaxDigitMassKg);
  RequirePositive("hand.friction", hand.friction);
  RequireAtMost("hand.friction", hand.friction, kMaxFriction);
  for (int k = 0; k < 3; ++k) {
    // NaN = chosen from the object (pre-grasp pose).
    if (std::isnan(hand.initial_wrist_position_m[k])) continue;
    RequireIn("hand.initial_wrist_position_m[" + std::to_string(k) + "]", hand.initial_wrist_position_m[k],
              -kMaxPositionM, kMaxPositionM);
  }
  RequirePositive("hand.wrist_stiffness_n_m", hand.wrist_stiffness_n_m);
  RequireAtMost("hand.wrist_stiffness_n_m", hand.wrist_stiffness_n_m, kMaxWristStiffnessNM);
  RequireIn("hand.wrist_damping_n_s_m", hand.wrist_damping_n_s_m, 0.0, kMaxWristDampingNSM);
  RequirePositive("hand.motor.stall_force_n", hand.motor.stall_force_n);
  RequireAtMost("hand.motor.stall_force_n", hand.motor.stall_force_n, kMaxStallForceN);
  RequirePositive("hand.motor.no_load_speed_m_s", hand.motor.no_load_speed_m_s);
  RequireAtMost("hand.motor.no_load_speed_m_s", hand.motor.no_load_speed_m_s, kMaxDigitSpeedMS);
  RequireIn("hand.motor.armature_kg", hand.motor.armature_kg, 0.0, kMaxArmatureKg);
  RequireIn("hand.motor.damping_n_s_m", hand.motor.damping_n_s_m, 0.0, kMaxMotorDampingNSM);
  RequireIn("physics.timestep_s", physics.timestep_s, kMinTimestepS, kMaxTimestepS);
  RequireIn("physics.impratio", physics.impratio, 1.0, kMaxImpratio);
  RequireIn("physics.noslip_iterations", physics.noslip_iterations, 0, kMaxNoslipIterations);
  RequireIn("physics.solver_iterations", physics.solver_iterations, 1, kMaxSolverIterations);
  RequireIn("physics.tolerance", physics.tolerance, kMinTolerance, kMaxTolerance);
  if (physics.condim != 3 && physics.condim != 4 && physics.condim != 6) {
    Bad("physics.condim", physics.condim, "must be 3, 4 or 6");
  }
  RequireIn("physics.gravity_m_s2", physics.gravity_m_s2, 0.0, kMaxGravityMS2);
}

SceneConfig LoadSceneConfig(const common::YamlMap& map) {
  using common::NumberRule;
  SceneConfig scene;
  if (auto object = map.GetMap("object")) {
    ObjectConfig& o = scene.object;
    o.shape = ParseShape(object->GetString("shape", ToString(o.shape), {"box", "cylinder", "sphere"}));
    o.size_m = GetTriple(*object, "size_m", o.size_m, NumberRule::Between(0.0, kMaxObjectSizeM));
    o.mass_kg =
        object->GetNumber("mass_kg", o.mass_kg, NumberRule::Between(kMinObjectMassKg, kMaxObjectMassKg));
    o.friction = object->GetNumber("friction", o.friction, {0.0, kMaxFriction, true});
    o.torsional_friction = object->GetNumber("torsional_friction", o.torsional_friction,
                                             NumberRule::Between(0.0, kMaxTorsionalFrictionM));
    o.solref_timeconst_s =
        object->GetNumber("solref_timeconst_s", o.solref_timeconst_s, {0.0, kMaxSolrefTimeconstS, true});
    o.solref_dampratio =
        object->GetNumber("solref_dampratio", o.solref_dampratio, {0.0, kMaxSolrefDampratio, true});
    const std::vector<double> solimp =
        object->GetNumberList("solimp", std::vector<double>(o.solimp.begin(), o.solimp.end()), 5,
                              NumberRule::Between(0.0, kMaxSolimpPower));
    for (int i = 0; i < 5; ++i) o.solimp[i] = solimp[i];
    o.initial_position_m = GetTriple(*object, "initial_position_m", o.initial_position_m,
                                     NumberRule::Between(-kMaxPositionM, kMaxPositionM));
    o.initial_yaw_rad =
        object->GetNumber("initial_yaw_rad", o.initial_yaw_rad, NumberRule::Between(-kMaxYawRad, kMaxYawRad));
    o.crush_limit_n =
        object->GetNumber("crush_limit_n", o.crush_limit_n, NumberRule::Between(0.0, kMaxForceN));
    object->RejectUnknownKeys();
  }
  if (auto hand = map.GetMap("hand")) {
    HandConfig& h = scene.hand;
    h.model = ParseHandModel(hand->GetString("model", ToString(h.model), {"prosthetic", "jaw"}));
    h.grasp = ParseGrasp(hand->GetString("grasp", ToString(h.grasp), {"pinch"}));
    h.open_gap_m =
        hand->GetNumber("open_gap_m", h.open_gap_m, NumberRule::Between(kMinOpenGapM, kMaxOpenGapM));
    h.preshape_clearance_m =
        hand->GetNumber("preshape_clearance_m", h.preshape_clearance_m, NumberRule::Between(0.0, 0.05));
    h.palm_mass_kg =
        hand->GetNumber("palm_mass_kg", h.palm_mass_kg, NumberRule::Between(kMinPalmMassKg, kMaxPalmMassKg));
    h.digit_mass_kg = hand->GetNumber("digit_mass_kg", h.digit_mass_kg,
                                      NumberRule::Between(kMinDigitMassKg, kMaxDigitMassKg));
    h.friction = hand->GetNumber("friction", h.friction, {0.0, kMaxFriction, true});
    h.initial_wrist_position_m = GetTriple(*hand, "initial_wrist_position_m", h.initial_wrist_position_m,
                                           NumberRule::Between(-kMaxPositionM, kMaxPositionM));
    h.wrist_stiffness_n_m =
        hand->GetNumber("wrist_stiffness_n_m", h.wrist_stiffness_n_m, {0.0, kMaxWristStiffnessNM, true});
    h.wrist_damping_n_s_m = hand->GetNumber("wrist_damping_n_s_m", h.wrist_damping_n_s_m,
                                            NumberRule::Between(0.0, kMaxWristDampingNSM));
    if (auto motor = hand->GetMap("motor")) {
      MotorConfig& m = h.motor;
      m.stall_force_n = motor->GetNumber("stall_force_n", m.stall_force_n, {0.0, kMaxStallForceN, true});
      m.no_load_speed_m_s =
          motor->GetNumber("no_load_speed_m_s", m.no_load_speed_m_s, {0.0, kMaxDigitSpeedMS, true});
      m.armature_kg =
          motor->GetNumber("armature_kg", m.armature_kg, NumberRule::Between(0.0, kMaxArmatureKg));
      m.damping_n_s_m =
          motor->GetNumber("damping_n_s_m", m.damping_n_s_m, NumberRule::Between(0.0, kMaxMotorDampingNSM));
      motor->RejectUnknownKeys();
    }
    if (auto finger = hand->GetMap("finger")) {
      FingerConfig& f = h.finger;
      f.proximal_length_m =
          finger->GetNumber("proximal_length_m", f.proximal_length_m, NumberRule::Between(0.02, 0.07));
      f.middle_length_m =
          finger->GetNumber("middle_length_m", f.middle_length_m, NumberRule::Between(0.01, 0.05));
      f.pip_mcp_ratio = finger->GetNumber("pip_mcp_ratio", f.pip_mcp_ratio, NumberRule::Between(0.5, 2.0));
      f.dip_flexion_rad =
          finger->GetNumber("dip_flexion_rad", f.dip_flexion_rad, NumberRule::Between(0.0, 1.0));
      f.mcp_rest_angle_rad =
          finger->GetNumber("mcp_rest_angle_rad", f.mcp_rest_angle_rad, NumberRule::Between(-0.6, 0.6));
      finger->RejectUnknownKeys();
    }
    if (auto thumb = hand->GetMap("thumb")) {
      ThumbConfig& t = h.thumb;
      t.proximal_length_m =
          thumb->GetNumber("proximal_length_m", t.proximal_length_m, NumberRule::Between(0.02, 0.07));
      t.distal_length_m =
          thumb->GetNumber("distal_length_m", t.distal_length_m, NumberRule::Between(0.01, 0.05));
      t.tip_radius_m = thumb->GetNumber("tip_radius_m", t.tip_radius_m, NumberRule::Between(0.004, 0.015));
      t.ip_flexion_rad = thumb->GetNumber("ip_flexion_rad", t.ip_flexion_rad, NumberRule::Between(0.0, 1.2));
      t.opposition_rad = thumb->GetNumber("opposition_rad", t.opposition_rad, NumberRule::Between(-0.2, 1.7));
      thumb->RejectUnknownKeys();
    }
    if (auto motor = hand->GetMap("digit_motor")) {
      DigitMotorConfig& m = h.digit_motor;
      m.stall_pinch_force_n =
          motor->GetNumber("stall_pinch_force_n", m.stall_pinch_force_n, NumberRule::Between(1.0, 200.0));
      m.no_load_speed_rad_s =
          motor->GetNumber("no_load_speed_rad_s", m.no_load_speed_rad_s, NumberRule::Between(0.1, 50.0));
      m.armature_kg_m2 = motor->GetNumber("armature_kg_m2", m.armature_kg_m2, NumberRule::Between(0.0, 1.0));
      m.damping_n_m_s = motor->GetNumber("damping_n_m_s", m.damping_n_m_s, NumberRule::Between(0.0, 10.0));
      motor->RejectUnknownKeys();
    }
    hand->RejectUnknownKeys();
  }
  if (auto physics = map.GetMap("physics")) {
    PhysicsConfig& p = scene.physics;
    p.timestep_s =
        physics->GetNumber("timestep_s", p.timestep_s, NumberRule::Between(kMinTimestepS, kMaxTimestepS));
    p.elliptic_cones = physics->GetBool("elliptic_cones", p.elliptic_cones);
    p.impratio = physics->GetNumber("impratio", p.impratio, NumberRule::Between(1.0, kMaxImpratio));
    p.noslip_iterations = physics->GetInt("noslip_iterations", p.noslip_iterations, 0, kMaxNoslipIterations);
    p.solver_iterations = physics->GetInt("solver_iterations", p.solver_iterations, 1, kMaxSolverIterations);
    p.tolerance =
        physics->GetNumber("tolerance", p.tolerance, NumberRule::Between(kMinTolerance, kMaxTolerance));
    p.condim = physics->GetInt("condim", p.condim, 3, 6);
    if (p.condim == 5) physics->Fail("condim", "must be 3, 4 or 6");
    p.gravity_m_s2 =
        physics->GetNumber("gravity_m_s2", p.gravity_m_s2, NumberRule::Between(0.0, kMaxGravityMS2));
    p.table = physics->GetBool("table", p.table);
    physics->RejectUnknownKeys();
  }
  map.RejectUnknownKeys();
  // Cross-field rules (time constant vs timestep) are checked here with the file name in front.
  try {
    scene.Validate();
  } catch (const std::invalid_argument& error) {
    throw common::ConfigError(map.file() + ": " + error.what());
  }
  return scene;
}

SceneConfig LoadSceneConfigFile(const std::string& path) {
  return LoadSceneConfig(common::YamlMap::LoadFile(path));
}

}  // namespace graspbed::sim

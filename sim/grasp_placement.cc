#include "sim/grasp_placement.h"

#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "sim/model_generator.h"
#include "sim/object_shapes.h"
#include "sim/simulation.h"

namespace graspbed::sim {
namespace {

// The pinch the hand has always made on a box or upright cylinder: the pad's centre this far below
// the top, so the middle phalanx passes over the object, and never lower than kMinPadHeightM
// (holder half length + tip cap + 3 mm), where the fingertip clears the table [m].
constexpr double kPinchBelowTopM = 0.013;
constexpr double kMinPadHeightM = 0.023;
// The lowest point of the fingertip and the thumb's tip in a round pinch stay this far above the
// table [m]; the pad's contact moves tipwards in these steps, as far as its last mesa row [m].
constexpr double kTableClearanceM = 0.0015;
constexpr double kAlongPadStepM = 0.0005;
constexpr double kMaxAlongPadM = 0.010;
// Probing faces: heights 1 mm apart from the pad's lowest to 3 mm below the top; surface normals
// from rays this far to either side [m].
constexpr double kProbeStepM = 0.001;
constexpr double kProbeTopMarginM = 0.003;
constexpr double kNormalProbeM = 0.0005;
// Faces within this angle of square count as square (a mesh's facets, the probe's differences)
// [rad]; a height further from the preferred one costs this much angle per metre, so a sphere-like
// bowl is pinched at its widest and a box at the usual height [rad/m].
constexpr double kSquareEnoughRad = 1.0 * std::numbers::pi / 180.0;
constexpr double kHeightCostRadPerM = 0.25 * std::numbers::pi / 180.0 / 1e-3;
// Placements kept per process before the cache starts over.
constexpr size_t kPlacementCacheEntries = 256;
// The index's proximal and middle phalanges must clear the object above the pad by this much [m].
constexpr double kLinkClearanceM = 0.001;

double Degrees(double rad) { return rad * 180.0 / std::numbers::pi; }

std::string ObjectName(const ObjectConfig& object) {
  if (!object.name.empty()) return "object '" + object.name + "'";
  if (object.shape == ObjectShape::kMesh) return "object.mesh " + object.mesh;
  return std::string("the ") + ToString(object.shape);
}

[[noreturn]] void Refuse(const ObjectConfig& object, const std::string& why) {
  throw std::invalid_argument("scene: object.size_m = " + FormatConfigTriple(object.size_m) + ": " +
                              ObjectName(object) + ": this hand cannot pinch it: " + why);
}

// Whether the table limits how low the pinch goes (a scene without one, in free space, does not).
bool TableBoundsThePinch(const SceneConfig& scene) { return scene.physics.table; }

// The object's centre of mass, world frame at its start pose [m].
Eigen::Vector3d StartCentreOfMass(const ObjectConfig& object) {
  const Eigen::Vector3d local = ComputeMassProperties(ObjectParts(object)).centre_of_mass_m;
  const Eigen::Vector3d origin(object.initial_position_m[0], object.initial_position_m[1], object.StartCentreZM());
  return origin + Eigen::AngleAxisd(object.initial_yaw_rad, Eigen::Vector3d::UnitZ()) * local;
}

// The object alone in MuJoCo, for ray casts against its geoms (the surfaces the digits meet).
class ObjectProbe {
 public:
  explicit ObjectProbe(const SceneConfig& scene)
      : model_(CompileMjcf(ObjectOnlyMjcf(scene)), mj_deleteModel), x_centre_(scene.object.initial_position_m[0]) {
    data_.reset(mj_makeData(model_.get()));
    mj_kinematics(model_.get(), data_.get());
  }

  // Where the line along x at (y, z) first meets the object coming from -x (side -1) or +x (side
  // +1): its x [m], or NaN when it misses.
  double FaceX(double y, double z, int side) const {
    const mjtNum start[3] = {x_centre_ + (side < 0 ? -kFar : kFar), y, z};
    const mjtNum direction[3] = {side < 0 ? 1.0 : -1.0, 0.0, 0.0};
    int geom = -1;
    const mjtNum distance = mj_ray(model_.get(), data_.get(), start, direction, nullptr, 1, -1, &geom);
    if (distance < 0.0) return std::numeric_limits<double>::quiet_NaN();
    return start[0] + direction[0] * distance;
  }

  // The angle between that face's outward normal and the pinch axis (pointing away from the
  // object's middle) [rad]: from the face's slopes, by rays either side; NaN at an edge.
  double FaceAngle(double y, double z, int side) const {
    const double dx_dy = (FaceX(y + kNormalProbeM, z, side) - FaceX(y - kNormalProbeM, z, side)) / (2 * kNormalProbeM);
    const double dx_dz = (FaceX(y, z + kNormalProbeM, side) - FaceX(y, z - kNormalProbeM, side)) / (2 * kNormalProbeM);
    return std::atan(std::hypot(dx_dy, dx_dz));
  }

 private:
  struct DataFree {
    void operator()(mjData* d) const { mj_deleteData(d); }
  };
  static constexpr double kFar = 1.0;  // rays start this far either side of the object's start [m]
  std::unique_ptr<mjModel, void (*)(mjModel*)> model_;
  double x_centre_ = 0.0;  // the object's start x [m]
  std::unique_ptr<mjData, DataFree> data_;
};

// The lowest the pad's centre goes [m]: where the fingertip clears the table, or without a table
// bounding it, the object's centre if that is lower.
double LowestPadHeightM(const SceneConfig& scene) {
  return TableBoundsThePinch(scene) ? kMinPadHeightM : std::min(scene.object.StartCentreZM(), kMinPadHeightM);
}

// The preferred height of a faces pinch: 13 mm below the top, not below the pad's lowest [m].
double PreferredFacesHeightM(const SceneConfig& scene) {
  const double top = scene.object.StartCentreZM() + scene.object.RestHalfHeightM();
  return std::max(top - kPinchBelowTopM, LowestPadHeightM(scene));
}

// Whether the index's proximal or middle phalanx, in the posture that puts the pad's centre at the
// finger's face at `height`, would meet the object above the pad (rays at each link point's
// height: the object's face there nearer the thumb than the link's surface).
bool LinksMeetObject(const ObjectProbe& probe, const ProstheticKinematics& kin, double line_y, double height,
                     double finger_face_x, double contact_mcp) {
  const DigitContact pad = kin.IndexPad(contact_mcp);
  const Eigen::Vector2d to_world(finger_face_x - pad.point_xz.x(), height - pad.point_xz.y());
  const auto link_clear = [&](const Eigen::Vector2d& from, const Eigen::Vector2d& to, double radius) {
    for (int k = 0; k <= 20; ++k) {
      const Eigen::Vector2d point = from + (to - from) * (k / 20.0) + to_world;
      const double face = probe.FaceX(line_y, point.y(), -1);
      if (std::isnan(face)) continue;  // nothing of the object at this height
      if (point.x() + radius + kLinkClearanceM > face) return false;
    }
    return true;
  };
  return !link_clear(kin.mcp_xz(), kin.Pip(contact_mcp), ProstheticKinematics::kProximalRadiusM) ||
         !link_clear(kin.Pip(contact_mcp), kin.Dip(contact_mcp), ProstheticKinematics::kMiddleRadiusM);
}

PinchPlacement PlaceFacesPinch(const SceneConfig& scene, const ProstheticKinematics& kin) {
  const ObjectConfig& object = scene.object;
  PinchPlacement place;
  place.kind = PinchKind::kFaces;
  const double preferred = PreferredFacesHeightM(scene);
  const double top = object.StartCentreZM() + object.RestHalfHeightM();
  if (TableBoundsThePinch(scene) && preferred > top - kProbeTopMarginM) {
    std::ostringstream why;
    why << std::fixed << std::setprecision(1) << "its top is " << 1e3 * top
        << " mm above the table: the pad's centre cannot come lower than " << 1e3 * kMinPadHeightM
        << " mm (the fingertip above the table) and meet it " << 1e3 * kProbeTopMarginM << " mm below its top";
    Refuse(object, why.str());
  }
  if (object.shape == ObjectShape::kBox || object.shape == ObjectShape::kCylinder) {
    // Parallel vertical faces at every height: the pinch the hand has always made.
    place.line_y_m = object.initial_position_m[1];
    place.height_m = preferred;
    place.centre_x_m = object.initial_position_m[0];
    place.width_m = scene.ObjectWidthM();
    place.reason = "its parallel faces, 13 mm below the top (or at the pad's lowest height)";
    return place;
  }
  const Eigen::Vector3d com = StartCentreOfMass(object);
  const ObjectProbe probe(scene);
  const double lowest = LowestPadHeightM(scene);
  const double highest = top - kProbeTopMarginM;
  const double friction_angle = std::atan(object.friction);
  double best_cost = std::numeric_limits<double>::infinity();
  double best_angle = std::numeric_limits<double>::infinity();
  bool any_hit = false;
  bool links_blocked = false;
  for (double z = lowest; z <= highest + 1e-9; z += kProbeStepM) {
    const double left = probe.FaceX(com.y(), z, -1);
    const double right = probe.FaceX(com.y(), z, +1);
    if (std::isnan(left) || std::isnan(right)) continue;
    any_hit = true;
    const std::array<double, 2> angles = {probe.FaceAngle(com.y(), z, -1), probe.FaceAngle(com.y(), z, +1)};
    if (std::isnan(angles[0]) || std::isnan(angles[1])) continue;
    const double angle = std::max(angles[0], angles[1]);
    best_angle = std::min(best_angle, angle);
    if (angle >= friction_angle) continue;
    const double cost = std::max(0.0, angle - kSquareEnoughRad) + kHeightCostRadPerM * std::abs(z - preferred);
    if (cost >= best_cost) continue;
    const double width = right - left;
    const double mcp = kin.McpForPadX(PinchCentreX(scene, kin, width) - 0.5 * width);
    if (LinksMeetObject(probe, kin, com.y(), z, left, mcp)) {
      links_blocked = true;
      continue;
    }
    best_cost = cost;
    place.line_y_m = com.y();
    place.height_m = z;
    place.centre_x_m = 0.5 * (left + right);
    place.width_m = width;
    place.face_angle_rad = angles;
  }
  if (!any_hit) Refuse(object, "the pinch line through its centre of mass misses it at every height");
  if (!std::isfinite(best_cost)) {
    std::ostringstream why;
    why << std::fixed << std::setprecision(1);
    if (best_angle >= friction_angle) {
      why << "at every height the pinch meets faces at least " << Degrees(best_angle)
          << " deg from square, outside the friction cone (atan(mu) = " << Degrees(friction_angle)
          << " deg): the squeeze would push it out";
    } else {
      why << "wherever its faces could be pinched, the index's proximal or middle phalanx would meet it "
             "above the pad";
    }
    Refuse(object, why.str());
  }
  std::ostringstream reason;
  reason << std::fixed << std::setprecision(1) << "its most nearly parallel faces under the pinch line through its centre of mass ("
         << Degrees(place.face_angle_rad[0]) << " and " << Degrees(place.face_angle_rad[1])
         << " deg from square), nearest 13 mm below its top" << (links_blocked ? ", clear of the phalanges" : "");
  place.reason = reason.str();
  return place;
}

PinchPlacement PlaceRoundPinch(const SceneConfig& scene, const ProstheticKinematics& kin,
                               const RoundSection& section) {
  const ObjectConfig& object = scene.object;
  const Eigen::Vector3d origin(object.initial_position_m[0], object.initial_position_m[1], object.StartCentreZM());
  const Eigen::Vector3d centre =
      origin + Eigen::AngleAxisd(object.initial_yaw_rad, Eigen::Vector3d::UnitZ()) * section.centre_m;
  PinchPlacement place;
  place.kind = PinchKind::kRound;
  std::string last_error;
  // The pad's centre first; tipwards until the fingertip clears the table and the posture is in
  // the joints' ranges with the links clear (the last reason a step failed is the refusal's).
  for (double along = 0.0; along <= kMaxAlongPadM + 1e-12; along += kAlongPadStepM) {
    RoundPinchPose pose;
    try {
      pose = kin.RoundPinch(section.radius_m, along);
    } catch (const std::invalid_argument& error) {
      last_error = error.what();
      continue;
    }
    const double wrist_z = centre.z() - pose.centre_xz.y();
    if (TableBoundsThePinch(scene) && wrist_z + pose.lowest_z_m < kTableClearanceM) {
      std::ostringstream why;
      why << std::fixed << std::setprecision(1) << "pinched through " << section.where << ", the fingertip would reach "
          << 1e3 * (wrist_z + pose.lowest_z_m) << " mm above the table (at least " << 1e3 * kTableClearanceM
          << " mm) with the pad's contact up to " << 1e3 * kMaxAlongPadM << " mm towards its tip";
      last_error = why.str();
      continue;
    }
    if (kin.IndexClearanceM(pose.mcp_rad, pose.centre_xz, section.radius_m, true) < kLinkClearanceM) {
      last_error = "the index's proximal or middle phalanx would meet it before the pad";
      continue;
    }
    place.round = pose;
    place.along_pad_m = along;
    place.line_y_m = centre.y();
    place.height_m = centre.z();
    place.centre_x_m = centre.x();
    place.width_m = 2.0 * section.radius_m;
    std::ostringstream reason;
    reason << std::fixed << std::setprecision(1) << "through " << section.where << ": the pad's normal and the thumb tip on one line through it, "
           << Degrees(pose.line_angle_rad) << " deg from level, the pad's contact " << 1e3 * along
           << " mm from its centre towards the tip";
    place.reason = reason.str();
    return place;
  }
  Refuse(object, last_error);
}

}  // namespace

double PinchCentreX(const SceneConfig& scene, const ProstheticKinematics& kin, double width_m) {
  if (!scene.hand.pinch_square_pad) return 0.0;
  return kin.IndexPad(kin.SquarePadMcpRad()).point_xz.x() + 0.5 * width_m;
}

const char* ToString(PinchKind kind) { return kind == PinchKind::kRound ? "round" : "faces"; }

PinchPlacement PlacePinch(const SceneConfig& scene, const ProstheticKinematics& kin) {
  // Probing compiles the object and casts a few thousand rays (8 ms for the plastic cup), and a run
  // places its scene more than once (the MJCF, the Simulation, an oracle search's every step): the
  // placements are kept per process, keyed by the scene as config.yaml writes it and the fingertip.
  YAML::Emitter emitted;
  emitted << YAML::BeginMap;
  EmitSceneConfig(scene, emitted);
  emitted << YAML::EndMap;
  std::ostringstream key;
  key << std::setprecision(17) << emitted.c_str() << "\nholder " << kin.holder_length_m() << " " << kin.pad_depth_m();
  static std::mutex mutex;
  static std::map<std::string, PinchPlacement> placed;
  {
    const std::lock_guard<std::mutex> lock(mutex);
    const auto found = placed.find(key.str());
    if (found != placed.end()) return found->second;
  }
  const std::optional<RoundSection> section = PinchRoundSection(scene.object);
  PinchPlacement placement = section ? PlaceRoundPinch(scene, kin, *section) : PlaceFacesPinch(scene, kin);
  const std::lock_guard<std::mutex> lock(mutex);
  if (placed.size() >= kPlacementCacheEntries) placed.clear();  // a sweep's many scenes: start over
  placed.emplace(key.str(), placement);
  return placement;
}

}  // namespace graspbed::sim

#pragma once
/// Generates the self-contained MJCF of the scene from the sensor layout (the one source of truth for
/// where the units are) and the scene config. The output loads in mj_loadXML and in MuJoCo's own
/// tools (mujoco-simulate, mujoco-testspeed) with no other files.
///
/// Names the rest of sim/ relies on (docs/simulation.md, "Model"):
///   bodies  wrist, palm, finger, holder, thumb, object, table
///   geoms   unit_0 .. unit_{N-1} (one mesa box per layout unit, layout order), holder_shell (the
///           elliptic holder, a convex mesh), finger_link, thumb_pad, thumb_link, palm_geom,
///           object_geom, table_geom
///   joints  wrist_x, wrist_y, wrist_z (slides), finger_slide, thumb_slide; object_free
///   tendon  grip (finger_slide + thumb_slide: the closure of the gap)
///   actuators wrist_x_servo, wrist_y_servo, wrist_z_servo (position), grip_motor (on tendon grip)
///   equality  digit_coupling (thumb_slide = finger_slide), grip_brake (finger_slide held; off)

#include <string>

#include "sensor/layout.h"
#include "sim/scene_config.h"

namespace graspbed::sim {

/// Position of the holder frame's origin relative to the wrist body [m]: the holder axis points
/// down (holder +x = world -z), its palmar side faces world +x (holder -z = world +x), holder +y =
/// world -y. With both digits at 0 (fully open).
struct HandGeometry {
  double holder_center_below_wrist_m = 0.0;  ///< holder centre z below the wrist origin [m]
  double finger_open_x_m = 0.0;              ///< holder axis x relative to the wrist when open [m]
  double thumb_pad_open_x_m = 0.0;           ///< thumb pad face x relative to the wrist when open [m]
  double mesa_top_offset_m = 0.0;            ///< palmar mesa top beyond the holder axis along +x [m]
  double stroke_m = 0.0;                     ///< travel of each digit from open to closed [m]
};

/// The hand geometry that GenerateMjcf uses for `layout` and `scene`.
HandGeometry ComputeHandGeometry(const sensor::Layout& layout, const SceneConfig& scene);

/// Full MJCF text of the scene. Throws std::invalid_argument if the layout or scene is invalid
/// (e.g. more units than sensor::kMaxUnits).
std::string GenerateMjcf(const sensor::Layout& layout, const SceneConfig& scene);

}  // namespace graspbed::sim

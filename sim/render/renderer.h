#pragma once
/// Renderer: pictures of a Simulation's current state with MuJoCo's own renderer (mjv/mjr), offscreen
/// (OffscreenGlContext: EGL, no display, no GPU needed). The sensing units are drawn coloured by their
/// estimated normal force -- each mesa (geom unit_i) and a patch the size of the unit's footprint on the
/// holder surface under it -- from a TactileState: grey unloaded, red at the rated force, with a legend
/// of that colour map. Each valid unit's estimated Ft is an arrow along its beam axis; an unusable unit
/// is black with a yellow cross. Optional contact-force arrows, an optionally see-through object (the
/// units face it), a text panel (PanelText() composes the one of videos and the viewer). Sites
/// (markers for code) are not drawn.
///
/// The renderer draws from its own copy of the model (visual settings only), so the simulation's
/// mjModel is never touched. Nothing is hard-coded about the hand's bodies: the units are found as
/// geoms unit_0 .. unit_{N-1}, the object as body "object" (or the body of geom "object_geom"), and
/// the built-in cameras aim from the units' own outward normals.

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common/rgb_image.h"
#include "controller/grasp_controller.h"
#include "sensor/tactile_state.h"
#include "sim/render/offscreen_gl_context.h"
#include "sim/simulation.h"

namespace graspbed::sim {

/// MuJoCo's orbit camera: looks at `lookat_m` from `distance_m` away.
struct FreeView {
  double azimuth_deg =
      0.0;  ///< heading of the view direction about world z: 0 looks along +x, 90 along +y [deg]
  double elevation_deg = -20.0;      ///< pitch of the view direction: negative looks down [deg], in (-90, 90)
  double distance_m = 0.3;           ///< camera to lookat point [m], > 0
  std::array<double, 3> lookat_m{};  ///< point at the image centre, world frame [m]
};

/// A mouse camera motion (mujoco-simulate: left drag rotates, right drag moves, wheel zooms; with
/// shift the horizontal variants).
enum class CameraMove { kRotateVertical, kRotateHorizontal, kMoveVertical, kMoveHorizontal, kZoom };

/// Parses "azimuth,elevation,distance,lookat_x,lookat_y,lookat_z" (deg, deg, m, m, m, m). Throws
/// std::invalid_argument quoting the text and saying what is wrong.
FreeView ParseFreeView(const std::string& text);

/// The camera a picture is taken with.
struct CameraSpec {
  enum class Kind {
    kGrasp,      ///< built in: hand and object, from 45 deg beside the units' outward normal, from above
    kFingertip,  ///< built in: close-up of the units, from 30 deg beside their outward normal; no object
    kModel,      ///< a <camera> of the model, by name
    kFree,       ///< `free`
  };
  Kind kind = Kind::kGrasp;
  std::string model_camera;  ///< kModel: the camera's name in the model
  FreeView free;             ///< kFree
};

/// "grasp" and "fingertip" name the built-in cameras; any other name is a model camera (checked when
/// rendering, against the model).
CameraSpec CameraByName(const std::string& name);

/// Size and content of the pictures.
struct RenderOptions {
  int width_px = 800;   ///< [px], 16 .. 4096
  int height_px = 600;  ///< [px], 16 .. 4096
  /// Force arrows at every contact (MuJoCo's contact-force visualisation) [-].
  bool contact_forces = false;
  double force_arrow_m_per_n = 0.01;  ///< arrow length per newton of contact force [m/N], > 0
  /// Opacity of the object [0, 1]: below 1 the units it covers show through; 0 leaves it out.
  double object_alpha = 0.3;
  double rated_force_n = 10.0;  ///< estimated Fn drawn full red [N], > 0 (the paper's range)
  /// An arrow per valid unit for its estimated Ft, along its beam axis, from the edge of its footprint
  /// the way the shear points [-].
  bool shear_arrows = true;
  double shear_arrow_m_per_n = 4e-3;  ///< shear arrow length per newton [m/N], > 0
  bool legend = true;  ///< colour scale of the units (bottom right) when a TactileState is drawn; left out
                       ///< below ~200 px height
  /// MuJoCo's shadows. On llvmpipe (no GPU) they are most of a frame's cost (a 4096 px shadow map per
  /// light): about 115 against 36 ms per 640 x 480 frame here; videos and the viewer leave them out.
  bool shadows = true;
  int multisamples = 4;  ///< anti-aliasing samples of the offscreen buffer (MuJoCo's default 4), 0..16
  /// Throws std::invalid_argument naming the field and value.
  void Validate() const;
};

/// RGBA of a unit with estimate `fn_n` [N]: grey (0 N or less) to red (at `rated_force_n` and above)
/// on a square-root scale (a quarter of the range is half way) when valid; magenta when saturated (out of
/// range); black when the estimate is unusable (open, short, implausible, not tared).
std::array<float, 4> UnitColor(double fn_n, sensor::UnitValidity validity, double rated_force_n);

/// What the text panel of a video frame or the viewer says (PanelText()).
struct PanelInfo {
  std::string title;    ///< first line, e.g. "default (grip_slip)"
  double time_s = 0.0;  ///< simulated time [s]
  const controller::ControllerTelemetry* telemetry =
      nullptr;  ///< phase, grip target, friction, slip; may be null
  const sensor::TactileState* state =
      nullptr;  ///< measured grip (sum of valid Fn), units in contact; may be null
  /// The script action that last fired, e.g. "lift at 1.000 s" ("" none yet: shown as "-"; nullopt:
  /// no such line).
  std::optional<std::string> last_action;
  std::string extra;  ///< more "name\tvalue" lines appended (e.g. the viewer's speed)
};

/// Whether `state` has no usable estimate yet without any unit having failed: no frame yet, or every
/// unit still taring (valid_count 0, each unit valid-by-default or kNotTared).
bool SensorStarting(const sensor::TactileState& state);

/// The panel as Render()'s `label`: "name\tvalue" lines for time, controller phase, grip target,
/// measured grip (estimated total Fn and units in contact), friction estimate, slip flags (the
/// controller's slip flag, safe hold, stale data) and the last script action. A safe hold while the
/// sensor is starting (SensorStarting) is "TARING", its phase "<phase> (sensor taring)": the start of
/// every run, not a fault.
std::string PanelText(const PanelInfo& info);

/// Renders one simulation's scene. Owns its model copy, mjvScene and mjrContext; not copyable, not
/// movable. Use it on the thread that owns `gl`, which must outlive it.
class Renderer {
 public:
  /// Throws std::invalid_argument for bad options, std::runtime_error when MuJoCo cannot set up its
  /// GL resources (e.g. a size beyond the GL implementation's limit).
  Renderer(GlContext& gl, const Simulation& simulation, const RenderOptions& options);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Renders `simulation` (the one this renderer was made for) as it is now, units coloured from
  /// `state` (nullptr: all grey), seen by `camera`, with `label` in the top-left corner: lines split at
  /// '\n', each "name\tvalue" in two columns ("" draws none). Returns the picture, valid until the next call.
  /// Throws std::invalid_argument for a model camera the model lacks (naming those it has).
  const image::RgbImage& Render(Simulation& simulation, const sensor::TactileState* state,
                                const CameraSpec& camera, const std::string& label = "");

  /// Renders like Render() into the window whose context `gl` is (the viewer), `width_px` x
  /// `height_px` framebuffer pixels, without reading the pixels back.
  void RenderToWindow(Simulation& simulation, const sensor::TactileState* state, const CameraSpec& camera,
                      const std::string& label, int width_px, int height_px);

  /// The last orbit camera rendered with (the built-in cameras are orbit cameras; a model camera
  /// leaves it unchanged), to start a mouse camera from.
  FreeView LastView() const;
  /// Moves orbit camera `view` as mujoco-simulate does for a mouse drag by (`dx`, `dy`), fractions of
  /// the window height (mjv_moveCamera).
  void MoveCamera(CameraMove move, double dx, double dy, FreeView& view) const;

  /// Pixel where world point `point_m` [m] appears in the last picture: {column, row}, from the top
  /// left, in pixels (may lie outside the picture); nullopt when it is behind the camera or no
  /// picture was rendered yet.
  std::optional<std::array<double, 2>> Project(const std::array<double, 3>& point_m) const;

  /// Centre of unit `unit`'s footprint on the holder surface now, world frame [m].
  std::array<double, 3> UnitCenter(const Simulation& simulation, int unit) const;

 private:
  struct Scene;  // model copy and MuJoCo's visualisation state, kept out of this header

  /// Shear arrows of valid units, crosses over unusable ones, added to the scene.
  void AddUnitMarks(const Simulation& simulation, const sensor::TactileState& state);
  /// The text panel and the colour legend over the rendered scene, in pixels of `viewport`
  /// (left, bottom, width, height).
  void DrawOverlays(const std::array<int, 4>& viewport, bool units_coloured, const std::string& label);
  void DrawLegend(const std::array<int, 4>& viewport);
  /// The scene and overlays into the offscreen buffer or the window, in `pixels` (left, bottom, width,
  /// height).
  void Draw(Simulation& simulation, const sensor::TactileState* state, const CameraSpec& camera,
            const std::string& label, const std::array<int, 4>& pixels, bool window);
  /// Reads the offscreen buffer into image_ (rows from the top).
  void ReadPixels(const std::array<int, 4>& viewport);

  GlContext& gl_;
  RenderOptions options_;
  double mesa_height_m_ = 0.0;
  std::array<double, 2> unit_footprint_m_{};  ///< beam length, beam width [m]
  std::vector<int> unit_geoms_;               ///< geom id per unit
  std::vector<int> unit_of_geom_;             ///< unit index per geom id, -1 for other geoms
  int object_body_ = -1;                      ///< -1: no object found
  std::unique_ptr<Scene> scene_;
  image::RgbImage image_;
  std::vector<uint8_t> bottom_up_;  ///< mjr_readPixels output, rows from the bottom
  bool rendered_ = false;
};

}  // namespace graspbed::sim

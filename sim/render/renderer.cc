#include "sim/render/renderer.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

namespace graspbed::sim {
namespace {

constexpr int kMinSizePx = 16;
constexpr int kMaxSizePx = 4096;
// Room in the scene for the model's geoms, one footprint patch per unit and contact arrows.
constexpr int kExtraSceneGeoms = 1500;
constexpr float kUnloadedGrey[3] = {0.62f, 0.62f, 0.62f};
constexpr float kLoadedRed[3] = {0.95f, 0.05f, 0.05f};
// Footprint patches: thin boxes lying on the holder surface, a hair above it so they win the depth test.
constexpr double kPatchHalfThicknessM = 0.05e-3;
constexpr double kPatchLiftM = 0.06e-3;
// Units glow a little, so their colour reads the same on the lit and the shaded side of the holder.
constexpr float kUnitEmission = 0.5f;
// Built-in cameras: view direction relative to the units' mean outward normal.
constexpr double kGraspSideAngleDeg = 45.0;
constexpr double kGraspElevationDeg = -25.0;
constexpr double kFingertipSideAngleDeg = 30.0;
constexpr double kFingertipElevationDeg = -20.0;
constexpr double kFingertipDistanceM = 0.05;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;
// Shear arrows: smaller estimates are noise at rest and would clutter every frame [N]; width [m]; lift
// above the holder surface so they clear the mesas [m].
constexpr double kMinShearArrowN = 0.05;
constexpr double kShearArrowWidthM = 0.35e-3;
constexpr double kShearArrowLiftM = 0.7e-3;
constexpr float kShearArrowRgba[4] = {0.1f, 0.45f, 1.0f, 1.0f};
// Unusable units: a yellow cross over the (black) footprint, bar width [m].
constexpr float kInvalidCrossRgba[4] = {1.0f, 0.85f, 0.0f, 1.0f};
constexpr double kInvalidCrossWidthM = 0.25e-3;
// Legend: colour bar steps, size and margin [px].
constexpr int kLegendSteps = 24;
constexpr int kLegendBarWidthPx = 16;
constexpr int kLegendMarginPx = 8;

struct ModelDeleter {
  void operator()(mjModel* model) const { mj_deleteModel(model); }
};

double ParseNumber(const std::string& field, const std::string& whole, const char* what) {
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(field, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  while (used < field.size() && field[used] == ' ') ++used;
  if (field.empty() || used != field.size() || !std::isfinite(value)) {
    throw std::invalid_argument("--view " + whole + ": " + what + " '" + field + "' is not a number");
  }
  return value;
}

// A decoration from point a to point b (an arrow or a bar) in the scene, which must have room.
void AddConnector(mjvScene& scene, int type, double width_m, const double a[3], const double b[3],
                  const float rgba[4]) {
  mjvGeom* geom = scene.geoms + scene.ngeom;
  mjv_initGeom(geom, type, nullptr, nullptr, nullptr, rgba);
  mjv_makeConnector(geom, type, width_m, a[0], a[1], a[2], b[0], b[1], b[2]);
  geom->category = mjCAT_DECOR;
  geom->emission = kUnitEmission;
  ++scene.ngeom;
}

void SetRgba(float rgba[4], const std::array<float, 4>& color) {
  for (int k = 0; k < 4; ++k) rgba[k] = color[k];
}

}  // namespace

struct Renderer::Scene {
  std::unique_ptr<mjModel, ModelDeleter> model;
  mjvScene scene;
  mjvOption option;
  mjrContext context;
  mjvGLCamera camera;     // of the last picture (both eyes averaged)
  mjvCamera free_camera;  // the last orbit camera used (built-in cameras are orbit cameras)
};

FreeView ParseFreeView(const std::string& text) {
  std::vector<std::string> fields;
  std::stringstream stream(text);
  for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
  if (!text.empty() && text.back() == ',') fields.push_back("");
  if (fields.size() != 6) {
    throw std::invalid_argument("--view " + text + ": expected 6 numbers azimuth,elevation,distance,x,y,z " +
                                "(deg, deg, m, m, m, m), got " + std::to_string(fields.size()));
  }
  FreeView view;
  view.azimuth_deg = ParseNumber(fields[0], text, "azimuth");
  view.elevation_deg = ParseNumber(fields[1], text, "elevation");
  view.distance_m = ParseNumber(fields[2], text, "distance");
  for (int k = 0; k < 3; ++k) view.lookat_m[k] = ParseNumber(fields[3 + k], text, "lookat");
  if (!(view.elevation_deg > -90.0 && view.elevation_deg < 90.0)) {
    throw std::invalid_argument("--view " + text + ": elevation " + fields[1] + " must be in (-90, 90) deg");
  }
  if (!(view.distance_m > 0.0)) {
    throw std::invalid_argument("--view " + text + ": distance " + fields[2] + " must be > 0 m");
  }
  return view;
}

CameraSpec CameraByName(const std::string& name) {
  CameraSpec spec;
  if (name.empty() || name == "grasp") {
    spec.kind = CameraSpec::Kind::kGrasp;
  } else if (name == "fingertip") {
    spec.kind = CameraSpec::Kind::kFingertip;
  } else {
    spec.kind = CameraSpec::Kind::kModel;
    spec.model_camera = name;
  }
  return spec;
}

void RenderOptions::Validate() const {
  for (const auto& [name, value] : {std::pair{"width_px", width_px}, std::pair{"height_px", height_px}}) {
    if (value < kMinSizePx || value > kMaxSizePx) {
      throw std::invalid_argument(std::string(name) + " = " + std::to_string(value) + ": must be in " +
                                  std::to_string(kMinSizePx) + ".." + std::to_string(kMaxSizePx));
    }
  }
  if (!(force_arrow_m_per_n > 0.0) || !std::isfinite(force_arrow_m_per_n)) {
    throw std::invalid_argument("force_arrow_m_per_n = " + std::to_string(force_arrow_m_per_n) +
                                ": must be > 0");
  }
  if (!(object_alpha >= 0.0 && object_alpha <= 1.0)) {
    throw std::invalid_argument("object_alpha = " + std::to_string(object_alpha) + ": must be in [0, 1]");
  }
  if (multisamples < 0 || multisamples > 16) {
    throw std::invalid_argument("multisamples = " + std::to_string(multisamples) + ": must be in 0..16");
  }
  if (!(shear_arrow_m_per_n > 0.0) || !std::isfinite(shear_arrow_m_per_n)) {
    throw std::invalid_argument("shear_arrow_m_per_n = " + std::to_string(shear_arrow_m_per_n) +
                                ": must be > 0");
  }
  if (!(rated_force_n > 0.0) || !std::isfinite(rated_force_n)) {
    throw std::invalid_argument("rated_force_n = " + std::to_string(rated_force_n) + ": must be > 0");
  }
}

std::array<float, 4> UnitColor(double fn_n, sensor::UnitValidity validity, double rated_force_n) {
  switch (validity) {
    case sensor::UnitValidity::kValid: {
      // Square-root scale: a light touch (0.2 .. 1 N of a 10 N range) already shows.
      const float s = static_cast<float>(std::sqrt(std::clamp(fn_n / rated_force_n, 0.0, 1.0)));
      return {kUnloadedGrey[0] + s * (kLoadedRed[0] - kUnloadedGrey[0]),
              kUnloadedGrey[1] + s * (kLoadedRed[1] - kUnloadedGrey[1]),
              kUnloadedGrey[2] + s * (kLoadedRed[2] - kUnloadedGrey[2]), 1.0f};
    }
    case sensor::UnitValidity::kOutOfRange:
      return {0.9f, 0.1f, 0.9f, 1.0f};
    default:
      return {0.05f, 0.05f, 0.05f, 1.0f};
  }
}

bool SensorStarting(const sensor::TactileState& state) {
  if (state.valid_count > 0) return false;
  for (int u = 0; u < state.unit_count; ++u) {
    const sensor::UnitValidity validity = state.validity[static_cast<size_t>(u)];
    if (validity != sensor::UnitValidity::kNotTared && validity != sensor::UnitValidity::kValid) return false;
  }
  return true;
}

std::string PanelText(const PanelInfo& info) {
  char line[160];
  std::string text;
  if (!info.title.empty()) text += info.title + "\t\n";
  std::snprintf(line, sizeof(line), "time\t%.3f s\n", info.time_s);
  text += line;
  // A controller holds while the sensor tares, by design: said so, not flagged like a fault.
  const bool taring = info.telemetry != nullptr && info.telemetry->safe_hold && info.state != nullptr &&
                      SensorStarting(*info.state);
  if (info.telemetry != nullptr) {
    const controller::ControllerTelemetry& t = *info.telemetry;
    std::snprintf(line, sizeof(line), "phase\t%s%s\ngrip target\t%.2f N\n", t.phase,
                  taring ? " (sensor taring)" : "", t.grip_target_n);
    text += line;
  }
  if (info.state != nullptr) {
    std::snprintf(line, sizeof(line), "measured grip\t%.2f N on %d unit%s (%d valid)\n", info.state->total_fn_n,
                  info.state->contact_count, info.state->contact_count == 1 ? "" : "s", info.state->valid_count);
    text += line;
  }
  if (info.telemetry != nullptr) {
    const controller::ControllerTelemetry& t = *info.telemetry;
    const bool stale = info.state != nullptr && info.state->stale;
    std::string flags;
    if (t.slip_detected) {
      flags.append("SLIP ");
      if (t.slip_cues != nullptr && t.slip_cues[0] != '\0')
        flags.append("(").append(t.slip_cues).append(") ");
    }
    if (t.safe_hold) flags.append(taring ? "TARING " : "SAFE-HOLD ");
    if (stale) flags.append("STALE ");
    if (flags.empty()) flags.append("- ");
    flags.pop_back();
    std::snprintf(line, sizeof(line), "friction est.\t%.2f\n", t.friction_estimate);
    text += line;
    text += "slip flags\t" + flags + "\n";
  }
  if (info.last_action)
    text += "last action\t" + (info.last_action->empty() ? std::string("-") : *info.last_action) + "\n";
  text += info.extra;
  while (!text.empty() && text.back() == '\n') text.pop_back();
  return text;
}

Renderer::Renderer(GlContext& gl, const Simulation& simulation, const RenderOptions& options)
    : gl_(gl), options_((options.Validate(), options)), scene_(std::make_unique<Scene>()) {
  const mjModel* source = simulation.model();
  const sensor::Layout& layout = simulation.layout();
  mesa_height_m_ = layout.unit.mesa_height_m;
  unit_footprint_m_ = {layout.unit.beam_length_m, layout.unit.beam_width_m};
  for (int i = 0; i < layout.unit_count(); ++i) {
    const std::string name = "unit_" + std::to_string(i);
    const int geom = mj_name2id(source, mjOBJ_GEOM, name.c_str());
    if (geom < 0) throw std::runtime_error("render: the model has no geom '" + name + "'");
    unit_geoms_.push_back(geom);
  }
  unit_of_geom_.assign(source->ngeom, -1);
  for (int i = 0; i < layout.unit_count(); ++i) unit_of_geom_[unit_geoms_[i]] = i;
  object_body_ = mj_name2id(source, mjOBJ_BODY, "object");
  if (object_body_ < 0) {
    const int object_geom = mj_name2id(source, mjOBJ_GEOM, "object_geom");
    if (object_geom >= 0) object_body_ = source->geom_bodyid[object_geom];
  }

  Scene& s = *scene_;
  s.model.reset(mj_copyModel(nullptr, source));
  if (!s.model) throw std::runtime_error("render: cannot copy the model");
  mjModel* m = s.model.get();
  m->vis.global.offwidth = options_.width_px;
  m->vis.global.offheight = options_.height_px;
  m->vis.quality.offsamples = options_.multisamples;
  // Arrow length = force * map.force / meanmass; width = forcewidth * meansize.
  m->vis.map.force = static_cast<float>(options_.force_arrow_m_per_n * m->stat.meanmass);
  m->vis.scale.forcewidth = static_cast<float>(0.6e-3 / m->stat.meansize);

  mjv_defaultCamera(&s.free_camera);
  mjv_defaultScene(&s.scene);
  mjv_defaultOption(&s.option);
  mjr_defaultContext(&s.context);
  s.option.flags[mjVIS_CONTACTFORCE] = options_.contact_forces ? 1 : 0;
  // Sites are markers for code (e.g. finger_pad), not part of the hand: left out of pictures.
  for (int group = 0; group < mjNGROUP; ++group) s.option.sitegroup[group] = 0;
  gl_.MakeCurrent();
  mjv_makeScene(m, &s.scene, m->ngeom + kExtraSceneGeoms);
  try {
    mjr_makeContext(m, &s.context, mjFONTSCALE_100);
    mjr_setBuffer(mjFB_OFFSCREEN, &s.context);
  } catch (...) {
    mjr_freeContext(&s.context);
    mjv_freeScene(&s.scene);
    throw;
  }
  if (s.context.offWidth < options_.width_px || s.context.offHeight < options_.height_px) {
    const std::string got = std::to_string(s.context.offWidth) + "x" + std::to_string(s.context.offHeight);
    mjr_freeContext(&s.context);
    mjv_freeScene(&s.scene);
    throw std::runtime_error("render: the OpenGL implementation gave a " + got + " offscreen buffer for " +
                             std::to_string(options_.width_px) + "x" + std::to_string(options_.height_px));
  }
  image_.width_px = options_.width_px;
  image_.height_px = options_.height_px;
  image_.rgb.resize(static_cast<size_t>(options_.width_px) * options_.height_px * 3);
  bottom_up_.resize(image_.rgb.size());
}

Renderer::~Renderer() {
  try {
    gl_.MakeCurrent();
  } catch (const std::exception&) {
    // The context is gone with its GL objects; freeing MuJoCo's host-side state is all that is left.
  }
  mjr_freeContext(&scene_->context);
  mjv_freeScene(&scene_->scene);
}

std::array<double, 3> Renderer::UnitCenter(const Simulation& simulation, int unit) const {
  const mjData* d = simulation.data();
  const mjModel* m = scene_->model.get();
  const int geom = unit_geoms_.at(static_cast<size_t>(unit));
  const mjtNum* center = d->geom_xpos + 3 * geom;
  const mjtNum* frame = d->geom_xmat + 9 * geom;  // row-major; columns: beam, cross, outward normal
  // The mesa box reaches from inside its groove to mesa_height above the surface.
  const double above_surface = mesa_height_m_ - m->geom_size[3 * geom + 2];
  return {center[0] - above_surface * frame[2], center[1] - above_surface * frame[5],
          center[2] - above_surface * frame[8]};
}

const image::RgbImage& Renderer::Render(Simulation& simulation, const sensor::TactileState* state,
                                        const CameraSpec& camera, const std::string& label) {
  const std::array<int, 4> pixels = {0, 0, options_.width_px, options_.height_px};
  Draw(simulation, state, camera, label, pixels, /*window=*/false);
  ReadPixels(pixels);
  return image_;
}

void Renderer::RenderToWindow(Simulation& simulation, const sensor::TactileState* state,
                              const CameraSpec& camera, const std::string& label, int width_px,
                              int height_px) {
  Draw(simulation, state, camera, label, {0, 0, width_px, height_px}, /*window=*/true);
}

FreeView Renderer::LastView() const {
  const mjvCamera& cam = scene_->free_camera;
  FreeView view;
  view.azimuth_deg = cam.azimuth;
  view.elevation_deg = cam.elevation;
  view.distance_m = cam.distance;
  for (int k = 0; k < 3; ++k) view.lookat_m[k] = cam.lookat[k];
  return view;
}

void Renderer::MoveCamera(CameraMove move, double dx, double dy, FreeView& view) const {
  mjvCamera cam;
  mjv_defaultCamera(&cam);
  cam.type = mjCAMERA_FREE;
  cam.azimuth = view.azimuth_deg;
  cam.elevation = view.elevation_deg;
  cam.distance = view.distance_m;
  for (int k = 0; k < 3; ++k) cam.lookat[k] = view.lookat_m[k];
  int action = mjMOUSE_ZOOM;
  switch (move) {
    case CameraMove::kRotateVertical:
      action = mjMOUSE_ROTATE_V;
      break;
    case CameraMove::kRotateHorizontal:
      action = mjMOUSE_ROTATE_H;
      break;
    case CameraMove::kMoveVertical:
      action = mjMOUSE_MOVE_V;
      break;
    case CameraMove::kMoveHorizontal:
      action = mjMOUSE_MOVE_H;
      break;
    case CameraMove::kZoom:
      action = mjMOUSE_ZOOM;
      break;
  }
  mjv_moveCamera(scene_->model.get(), action, dx, dy, &scene_->scene, &cam);
  view.azimuth_deg = cam.azimuth;
  view.elevation_deg = cam.elevation;
  view.distance_m = cam.distance;
  for (int k = 0; k < 3; ++k) view.lookat_m[k] = cam.lookat[k];
}

void Renderer::Draw(Simulation& simulation, const sensor::TactileState* state, const CameraSpec& camera,
                    const std::string& label, const std::array<int, 4>& pixels, bool window) {
  Scene& s = *scene_;
  mjModel* m = s.model.get();
  mjData* d = simulation.mutable_data();
  gl_.MakeCurrent();

  // Where the units are and which way they face: the built-in cameras aim from there.
  const int units = static_cast<int>(unit_geoms_.size());
  std::array<double, 3> centroid{};
  std::array<double, 3> normal{};
  for (int i = 0; i < units; ++i) {
    const std::array<double, 3> c = UnitCenter(simulation, i);
    const mjtNum* frame = d->geom_xmat + 9 * unit_geoms_[i];
    for (int k = 0; k < 3; ++k) {
      centroid[k] += c[k] / units;
      normal[k] += frame[3 * k + 2];
    }
  }

  mjvCamera cam;
  mjv_defaultCamera(&cam);
  switch (camera.kind) {
    case CameraSpec::Kind::kModel: {
      const int id = mj_name2id(m, mjOBJ_CAMERA, camera.model_camera.c_str());
      if (id < 0) {
        std::string names;
        for (int c = 0; c < m->ncam; ++c)
          names += std::string(names.empty() ? "" : ", ") + mj_id2name(m, mjOBJ_CAMERA, c);
        throw std::invalid_argument("--camera " + camera.model_camera +
                                    ": no such camera; built in: grasp, fingertip" +
                                    (names.empty() ? "; the model has none" : "; the model has " + names));
      }
      cam.type = mjCAMERA_FIXED;
      cam.fixedcamid = id;
      break;
    }
    case CameraSpec::Kind::kFree:
      cam.type = mjCAMERA_FREE;
      cam.azimuth = camera.free.azimuth_deg;
      cam.elevation = camera.free.elevation_deg;
      cam.distance = camera.free.distance_m;
      for (int k = 0; k < 3; ++k) cam.lookat[k] = camera.free.lookat_m[k];
      break;
    case CameraSpec::Kind::kGrasp:
    case CameraSpec::Kind::kFingertip: {
      const bool grasp = camera.kind == CameraSpec::Kind::kGrasp;
      // Heading of the outward normal; the camera sits beside it, so the units face it at an angle and
      // the opposing digit is not in the line of sight.
      const double normal_heading_deg = std::atan2(normal[1], normal[0]) * kDegPerRad;
      const double side_deg = grasp ? kGraspSideAngleDeg : kFingertipSideAngleDeg;
      cam.type = mjCAMERA_FREE;
      cam.azimuth = normal_heading_deg + side_deg + 180.0;
      cam.elevation = grasp ? kGraspElevationDeg : kFingertipElevationDeg;
      for (int k = 0; k < 3; ++k) cam.lookat[k] = centroid[k];
      cam.distance = kFingertipDistanceM;
      if (grasp) {
        // Between the fingertip and the object (nearer the fingertip, the hand is above it), far
        // enough to show the hand around it.
        double object_size_m = 0.0;
        if (object_body_ >= 0) {
          for (int k = 0; k < 3; ++k)
            cam.lookat[k] = 0.7 * centroid[k] + 0.3 * d->xipos[3 * object_body_ + k];
          for (int g = 0; g < m->ngeom; ++g) {
            if (m->geom_bodyid[g] == object_body_) object_size_m = std::max(object_size_m, m->geom_rbound[g]);
          }
        }
        cam.distance = 0.15 + 2.0 * object_size_m;
      }
      break;
    }
  }

  if (cam.type == mjCAMERA_FREE) s.free_camera = cam;
  mjv_updateScene(m, d, &s.option, nullptr, &cam, mjCAT_ALL, &s.scene);

  // Units coloured by their estimate; the object made see-through (or left out).
  std::vector<std::array<float, 4>> colors(units);
  for (int i = 0; i < units; ++i) {
    colors[i] = state != nullptr && i < state->unit_count
                    ? UnitColor(state->fn_n[i], state->validity[i], options_.rated_force_n)
                    : std::array<float, 4>{kUnloadedGrey[0], kUnloadedGrey[1], kUnloadedGrey[2], 1.0f};
  }
  // The fingertip camera sits inside the object when it is held: left out there.
  const bool leave_out_object = options_.object_alpha <= 0.0 || camera.kind == CameraSpec::Kind::kFingertip;
  int kept = 0;
  for (int g = 0; g < s.scene.ngeom; ++g) {
    mjvGeom& geom = s.scene.geoms[g];
    if (geom.objtype == mjOBJ_GEOM && geom.objid >= 0 && geom.objid < m->ngeom) {
      const int unit = unit_of_geom_[geom.objid];
      if (unit >= 0) {
        SetRgba(geom.rgba, colors[unit]);
        geom.emission = kUnitEmission;
        geom.specular = 0.0f;
      }
      if (object_body_ >= 0 && m->geom_bodyid[geom.objid] == object_body_) {
        if (leave_out_object) continue;
        geom.rgba[3] = static_cast<float>(options_.object_alpha);
        geom.transparent = options_.object_alpha < 1.0;
      }
    }
    if (kept != g) s.scene.geoms[kept] = geom;
    ++kept;
  }
  s.scene.ngeom = kept;
  // A footprint patch per unit: the mesas alone (1 x 2 mm) are a few pixels in a whole-hand view.
  for (int i = 0; i < units && s.scene.ngeom < s.scene.maxgeom; ++i) {
    const std::array<double, 3> c = UnitCenter(simulation, i);
    const mjtNum* frame = d->geom_xmat + 9 * unit_geoms_[i];
    mjtNum pos[3];
    for (int k = 0; k < 3; ++k) pos[k] = c[k] + (kPatchLiftM)*frame[3 * k + 2];
    const mjtNum size[3] = {0.5 * unit_footprint_m_[0], 0.5 * unit_footprint_m_[1], kPatchHalfThicknessM};
    mjvGeom* patch = s.scene.geoms + s.scene.ngeom;
    mjv_initGeom(patch, mjGEOM_BOX, size, pos, frame, colors[i].data());
    patch->category = mjCAT_DECOR;
    patch->emission = kUnitEmission;
    patch->specular = 0.0f;
    ++s.scene.ngeom;
  }
  if (state != nullptr) AddUnitMarks(simulation, *state);

  const mjrRect viewport = {pixels[0], pixels[1], pixels[2], pixels[3]};
  mjr_setBuffer(window ? mjFB_WINDOW : mjFB_OFFSCREEN, &s.context);
  s.scene.flags[mjRND_SHADOW] = options_.shadows ? 1 : 0;
  mjr_render(viewport, &s.scene, &s.context);
  DrawOverlays(pixels, state != nullptr, label);
}

void Renderer::AddUnitMarks(const Simulation& simulation, const sensor::TactileState& state) {
  Scene& s = *scene_;
  const mjData* d = simulation.data();
  const int units = std::min(static_cast<int>(unit_geoms_.size()), state.unit_count);
  for (int i = 0; i < units; ++i) {
    const std::array<double, 3> c = UnitCenter(simulation, i);
    const mjtNum* frame = d->geom_xmat + 9 * unit_geoms_[i];  // columns: beam, cross, outward normal
    const double beam[3] = {frame[0], frame[3], frame[6]};
    const double cross[3] = {frame[1], frame[4], frame[7]};
    const double normal[3] = {frame[2], frame[5], frame[8]};
    if (state.validity[i] == sensor::UnitValidity::kValid) {
      const double ft = state.ft_n[i];
      if (!options_.shear_arrows || !std::isfinite(ft) || std::abs(ft) < kMinShearArrowN) continue;
      if (s.scene.ngeom >= s.scene.maxgeom) return;
      // From the footprint's edge outwards, so the unit's colour stays visible under its arrow.
      const double sign = ft > 0.0 ? 1.0 : -1.0;
      const double start = sign * 0.5 * unit_footprint_m_[0];
      const double end = start + ft * options_.shear_arrow_m_per_n;
      double a[3], b[3];
      for (int k = 0; k < 3; ++k) {
        a[k] = c[k] + kShearArrowLiftM * normal[k] + start * beam[k];
        b[k] = c[k] + kShearArrowLiftM * normal[k] + end * beam[k];
      }
      AddConnector(s.scene, mjGEOM_ARROW, kShearArrowWidthM, a, b, kShearArrowRgba);
      continue;
    }
    if (state.validity[i] == sensor::UnitValidity::kOutOfRange) continue;  // magenta says enough
    // Unusable: a cross corner to corner over the footprint.
    for (const double across : {1.0, -1.0}) {
      if (s.scene.ngeom >= s.scene.maxgeom) return;
      double a[3], b[3];
      for (int k = 0; k < 3; ++k) {
        const double half_diagonal =
            0.5 * unit_footprint_m_[0] * beam[k] + across * 0.5 * unit_footprint_m_[1] * cross[k];
        a[k] = c[k] + 2.0 * kPatchLiftM * normal[k] - half_diagonal;
        b[k] = c[k] + 2.0 * kPatchLiftM * normal[k] + half_diagonal;
      }
      AddConnector(s.scene, mjGEOM_CAPSULE, kInvalidCrossWidthM, a, b, kInvalidCrossRgba);
    }
  }
}

void Renderer::DrawOverlays(const std::array<int, 4>& pixels, bool units_coloured, const std::string& label) {
  const mjrRect viewport = {pixels[0], pixels[1], pixels[2], pixels[3]};
  Scene& s = *scene_;
  if (!label.empty()) {
    std::string names;
    std::string values;
    std::stringstream lines(label);
    for (std::string line; std::getline(lines, line);) {
      const size_t tab = line.find('\t');
      if (!names.empty()) {
        names += '\n';
        values += '\n';
      }
      names.append(line, 0, tab);
      if (tab != std::string::npos) values.append(line, tab + 1);
    }
    mjr_overlay(mjFONT_NORMAL, mjGRID_TOPLEFT, viewport, names.c_str(), values.c_str(), &s.context);
  }
  if (options_.legend && units_coloured) DrawLegend(pixels);
}

void Renderer::DrawLegend(const std::array<int, 4>& pixels) {
  const mjrRect viewport = {pixels[0], pixels[1], pixels[2], pixels[3]};
  Scene& s = *scene_;
  // Bottom right: a vertical bar grey (0 N) to red (rated), on the colour map's square-root scale,
  // ticks at 0, a quarter and the full rated force; swatches for saturated and unusable units.
  const int line_px = s.context.charHeight + 4;
  const int bar_height_px = std::clamp(viewport.height / 3, 3 * line_px, 12 * line_px);
  const int label_width_px = 7 * s.context.charWidth[static_cast<unsigned char>('0')] + 4;
  const int panel_width_px = kLegendBarWidthPx + label_width_px + 3 * kLegendMarginPx;
  const int panel_height_px = bar_height_px + 4 * line_px + 3 * kLegendMarginPx;
  const int left = viewport.left + viewport.width - panel_width_px - kLegendMarginPx;
  const int bottom = viewport.bottom + kLegendMarginPx;
  if (left < viewport.left || bottom + panel_height_px > viewport.bottom + viewport.height)
    return;  // too small
  mjr_rectangle({left, bottom, panel_width_px, panel_height_px}, 0.0f, 0.0f, 0.0f, 0.55f);
  const int bar_left = left + kLegendMarginPx;
  const int bar_bottom = bottom + 2 * line_px + 2 * kLegendMarginPx;
  for (int step = 0; step < kLegendSteps; ++step) {
    // Colour at the force whose square-root fraction is the step's middle.
    const double fraction = (step + 0.5) / kLegendSteps;
    const std::array<float, 4> color = UnitColor(fraction * fraction * options_.rated_force_n,
                                                 sensor::UnitValidity::kValid, options_.rated_force_n);
    const int y0 = bar_bottom + step * bar_height_px / kLegendSteps;
    const int y1 = bar_bottom + (step + 1) * bar_height_px / kLegendSteps;
    mjr_rectangle({bar_left, y0, kLegendBarWidthPx, y1 - y0}, color[0], color[1], color[2], 1.0f);
  }
  // Left-aligned text at a pixel position: mjr_label centres its text in a rectangle sized to it
  // (drawn fully transparent).
  const auto text_at = [&](const std::string& text, int x_px, int y_px) {
    int width_px = 2;
    for (const char c : text) width_px += s.context.charWidth[static_cast<unsigned char>(c)];
    mjr_label({x_px, y_px, width_px, s.context.charHeight + 2}, mjFONT_NORMAL, text.c_str(), 0.0f, 0.0f, 0.0f,
              0.0f, 0.95f, 0.95f, 0.95f, &s.context);
  };
  const int label_left = bar_left + kLegendBarWidthPx + kLegendMarginPx;
  char tick[32];
  for (const double fraction : {0.0, 0.25, 1.0}) {
    std::snprintf(tick, sizeof(tick), "%g N", fraction * options_.rated_force_n);
    // Square-root scale: a quarter of the force sits half way up.
    const int y =
        bar_bottom + static_cast<int>(std::sqrt(fraction) * bar_height_px) - s.context.charHeight / 2;
    text_at(tick, label_left, std::clamp(y, bar_bottom, bar_bottom + bar_height_px - s.context.charHeight));
  }
  text_at("est. Fn", bar_left, bar_bottom + bar_height_px + kLegendMarginPx);
  const std::array<float, 4> saturated =
      UnitColor(0.0, sensor::UnitValidity::kOutOfRange, options_.rated_force_n);
  mjr_rectangle({bar_left, bottom + line_px + kLegendMarginPx, kLegendBarWidthPx, s.context.charHeight},
                saturated[0], saturated[1], saturated[2], 1.0f);
  text_at("sat.", label_left, bottom + line_px + kLegendMarginPx);
  mjr_rectangle({bar_left, bottom + kLegendMarginPx / 2, kLegendBarWidthPx, s.context.charHeight}, 0.05f,
                0.05f, 0.05f, 1.0f);
  mjr_rectangle({bar_left + kLegendBarWidthPx / 2 - 1, bottom + kLegendMarginPx / 2, 3, s.context.charHeight},
                kInvalidCrossRgba[0], kInvalidCrossRgba[1], kInvalidCrossRgba[2], 1.0f);
  text_at("invalid", label_left, bottom + kLegendMarginPx / 2);
}

void Renderer::ReadPixels(const std::array<int, 4>& pixels) {
  const mjrRect viewport = {pixels[0], pixels[1], pixels[2], pixels[3]};
  Scene& s = *scene_;
  mjr_readPixels(bottom_up_.data(), nullptr, viewport, &s.context);
  const size_t row_bytes = static_cast<size_t>(options_.width_px) * 3;
  for (int row = 0; row < options_.height_px; ++row) {
    std::copy_n(bottom_up_.data() + static_cast<size_t>(options_.height_px - 1 - row) * row_bytes, row_bytes,
                image_.rgb.data() + static_cast<size_t>(row) * row_bytes);
  }
  s.camera = mjv_averageCamera(&s.scene.camera[0], &s.scene.camera[1]);
  rendered_ = true;
}

std::optional<std::array<double, 2>> Renderer::Project(const std::array<double, 3>& point_m) const {
  if (!rendered_) return std::nullopt;
  const mjvGLCamera& c = scene_->camera;
  double forward[3], up[3], right[3], rel[3];
  for (int k = 0; k < 3; ++k) {
    forward[k] = c.forward[k];
    up[k] = c.up[k];
    rel[k] = point_m[k] - c.pos[k];
  }
  mju_cross(right, forward, up);
  const double depth = mju_dot3(rel, forward);
  if (depth <= c.frustum_near) return std::nullopt;
  // mjr_render's frustum: vertical extent as given, horizontal from the viewport's aspect ratio.
  const double x = mju_dot3(rel, right) * c.frustum_near / depth;
  const double y = mju_dot3(rel, up) * c.frustum_near / depth;
  const double height = c.frustum_top - c.frustum_bottom;
  const double half_width = 0.5 * height * options_.width_px / options_.height_px;
  const double column = (x - (c.frustum_center - half_width)) / (2.0 * half_width) * options_.width_px;
  const double row_from_bottom = (y - c.frustum_bottom) / height * options_.height_px;
  return std::array<double, 2>{column, options_.height_px - row_from_bottom};
}

}  // namespace graspbed::sim

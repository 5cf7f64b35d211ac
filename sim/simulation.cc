#include "sim/simulation.h"

#include <Eigen/Geometry>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstring>
#include <list>
#include <memory>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <tuple>
#include <type_traits>
#include <vector>

#include "sim/model_generator.h"

namespace graspbed::sim {
namespace {

// MuJoCo's handlers are process-wide C function pointers; the text of the latest warning goes to a
// thread-local buffer that the Simulation stepping on this thread picks up.
thread_local char tls_last_warning[160] = {0};

void WarningHandler(const char* message) {
  std::snprintf(tls_last_warning, sizeof(tls_last_warning), "%s", message);
}

// mju_error must not return into MuJoCo; an exception unwinds to our load/step boundary.
void ErrorHandler(const char* message) { throw std::runtime_error(std::string("MuJoCo error: ") + message); }

void InstallHandlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    mju_user_warning = &WarningHandler;
    mju_user_error = &ErrorHandler;
  });
}

enum GeomSide : int { kOther = 0, kFinger = 1, kThumb = 2, kHandOther = 3 };

int RequireId(const mjModel* m, int type, const char* name) {
  const int id = mj_name2id(m, type, name);
  if (id < 0) throw std::runtime_error(std::string("generated model lacks '") + name + "'");
  return id;
}

// Velocity of the material point at world position `p` of body `body` [m/s], world frame.
void PointVelocity(const mjModel* m, const mjData* d, int body, const mjtNum p[3], mjtNum v[3]) {
  mjtNum vel[6];
  mj_objectVelocity(m, d, mjOBJ_BODY, body, vel, 0);  // [angular; linear] at the body origin
  const mjtNum* origin = d->xpos + 3 * body;
  const mjtNum r[3] = {p[0] - origin[0], p[1] - origin[1], p[2] - origin[2]};
  mjtNum w_cross_r[3];
  mju_cross(w_cross_r, vel, r);
  for (int k = 0; k < 3; ++k) v[k] = vel[3 + k] + w_cross_r[k];
}

// The object's mass [kg] and friction in the MJCF a Simulation compiles; the scene's own are set
// on the compiled model.
constexpr double kCompiledObjectMassKg = 1.0;
constexpr double kCompiledObjectFriction = 1.0;

struct ModelFree {
  void operator()(mjModel* model) const { mj_deleteModel(model); }
};

// Compiled models by MJCF text, most recently used first, shared by every Simulation of the process.
// Few entries suffice: the runs of a suite or sweep repeat a few scenes.
class CompiledModels {
 public:
  static CompiledModels& Instance() {
    static CompiledModels cache;
    return cache;
  }
  // A private copy of the model compiled from `mjcf`, compiling it on first use. Throws
  // std::runtime_error with MuJoCo's message when it does not compile.
  mjModel* Copy(const std::string& mjcf) {
    std::lock_guard<std::mutex> lock(mutex_);
    auto found =
        std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.mjcf == mjcf; });
    if (found == entries_.end()) {
      entries_.push_front({mjcf, std::unique_ptr<mjModel, ModelFree>(CompileMjcf(mjcf))});
      if (entries_.size() > kCapacity) entries_.pop_back();
      found = entries_.begin();
    } else if (found != entries_.begin()) {
      entries_.splice(entries_.begin(), entries_, found);
      found = entries_.begin();
    }
    mjModel* copy = mj_copyModel(nullptr, found->model.get());
    if (copy == nullptr) throw std::runtime_error("MuJoCo could not copy the compiled model");
    return copy;
  }

 private:
  static constexpr size_t kCapacity = 8;
  struct Entry {
    std::string mjcf;
    std::unique_ptr<mjModel, ModelFree> model;
  };

  std::mutex mutex_;
  std::list<Entry> entries_;
};

// Puts the model's contact pairs in the order MuJoCo's dynamic collision would test them: by body
// pair (signature), then by geom ids. The compiler sorts them by signature only, with an unstable
// sort, which scrambles the pairs within a body pair (the holder's 22 geoms against the object); the
// contact order then differs from the dynamic one, and with it the solver's rounding.
void OrderContactPairs(mjModel* m) {
  std::vector<int> order(static_cast<size_t>(m->npair));
  std::iota(order.begin(), order.end(), 0);
  std::ranges::sort(order, [m](int a, int b) {
    return std::tie(m->pair_signature[a], m->pair_geom1[a], m->pair_geom2[a]) <
           std::tie(m->pair_signature[b], m->pair_geom1[b], m->pair_geom2[b]);
  });
  const auto permute = [&order](auto* values, int width) {
    using Value = std::remove_pointer_t<decltype(values)>;
    const std::vector<Value> copy(values, values + order.size() * static_cast<size_t>(width));
    for (size_t to = 0; to < order.size(); ++to) {
      const size_t from = static_cast<size_t>(order[to]);
      std::copy_n(copy.begin() + static_cast<std::ptrdiff_t>(from * width), width,
                  values + to * static_cast<size_t>(width));
    }
  };
  permute(m->pair_dim, 1);
  permute(m->pair_geom1, 1);
  permute(m->pair_geom2, 1);
  permute(m->pair_signature, 1);
  permute(m->pair_solref, mjNREF);
  permute(m->pair_solimp, mjNIMP);
  permute(m->pair_margin, 1);
  permute(m->pair_gap, 1);
  permute(m->pair_friction, 5);
  permute(m->name_pairadr, 1);
}

}  // namespace

mjModel* CompileMjcf(const std::string& mjcf) {
  // mj_defaultVFS clears the 2 MB structure itself: no value-initialisation before it.
  auto vfs = std::make_unique_for_overwrite<mjVFS>();
  mj_defaultVFS(vfs.get());
  constexpr const char* kFileName = "graspbed_scene.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kFileName, static_cast<int>(mjcf.size())) != 0) {
    throw std::runtime_error("cannot create the in-memory model file");
  }
  const int file = mj_findFileVFS(vfs.get(), kFileName);
  std::memcpy(vfs->filedata[file], mjcf.data(), mjcf.size());
  char error[1000] = {0};
  mjModel* model = nullptr;
  {
    // MuJoCo's XML parser keeps global state while it loads: one model at a time, process-wide.
    // Runs then step in parallel on their own mjModel/mjData.
    static std::mutex xml_loader;
    std::lock_guard<std::mutex> lock(xml_loader);
    model = mj_loadXML(kFileName, vfs.get(), error, sizeof(error));
  }
  mj_deleteVFS(vfs.get());
  if (model == nullptr)
    throw std::runtime_error(std::string("MuJoCo could not load the generated model: ") + error);
  OrderContactPairs(model);
  return model;
}

Simulation::Simulation(const sensor::Layout& layout, const SceneConfig& scene)
    : layout_(layout), scene_(scene) {
  InstallHandlers();
  // The object's mass and friction are set after loading, so runs that differ only in them (mass
  // and friction sweeps, a scorecard's variations, a suite's repeated scenes) share one compiled
  // model instead of parsing and compiling the same MJCF again.
  SceneConfig canonical = scene_;
  // A part-filled bottle's water has a mass of its own, not a share of the total: it keeps its mass.
  if (!scene_.object.fill_fraction) canonical.object.mass_kg = kCompiledObjectMassKg;
  canonical.object.friction = kCompiledObjectFriction;
  model_.reset(CompiledModels::Instance().Copy(GenerateMjcf(layout_, canonical)));
  data_.reset(mj_makeData(model_.get()));
  if (data_ == nullptr) throw std::runtime_error("MuJoCo could not allocate mjData");

  const mjModel* m = model_.get();
  object_body_ = RequireId(m, mjOBJ_BODY, "object");
  object_geom_ = RequireId(m, mjOBJ_GEOM, "object_geom");
  geom_is_object_.assign(m->ngeom, 0);
  for (int g = 0; g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] == object_body_ && (m->geom_contype[g] != 0 || m->geom_conaffinity[g] != 0)) {
      geom_is_object_[g] = 1;
      object_geoms_.push_back(g);
    }
  }
  for (int pair = 0; pair < m->npair; ++pair) {
    if (geom_is_object_[m->pair_geom1[pair]] || geom_is_object_[m->pair_geom2[pair]]) object_pairs_.push_back(pair);
  }
  holder_body_ = RequireId(m, mjOBJ_BODY, "holder");
  holder_shell_geom_ = RequireId(m, mjOBJ_GEOM, "holder_shell");
  const int finger_body = RequireId(m, mjOBJ_BODY, "finger");
  const int thumb_body = RequireId(m, mjOBJ_BODY, "thumb");
  wrist_body_ = RequireId(m, mjOBJ_BODY, "wrist");
  finger_pad_site_ = RequireId(m, mjOBJ_SITE, "finger_pad");
  thumb_pad_site_ = RequireId(m, mjOBJ_SITE, "thumb_pad");
  const HandPlacement place = PlaceHand(layout_, scene_);
  const std::vector<std::string> motors = GripMotorNames(scene_.hand.model);
  const std::vector<std::string> brakes = GripBrakeNames(scene_.hand.model);
  for (size_t k = 0; k < motors.size(); ++k) {
    GripDrive drive;
    drive.actuator = RequireId(m, mjOBJ_ACTUATOR, motors[k].c_str());
    drive.brake_equality = RequireId(m, mjOBJ_EQUALITY, brakes[k].c_str());
    if (m->eq_type[drive.brake_equality] == mjEQ_TENDON) {
      drive.brake_tendon = m->eq_obj1id[drive.brake_equality];
    } else {
      drive.brake_joint_qpos = m->jnt_qposadr[m->eq_obj1id[drive.brake_equality]];
    }
    // A motor on a tendon (the wrap's flexor) moves it 2 rad per radian of the free finger's MCP.
    // (The jaw's motor is on a tendon too, the sum of its two slides: 1 m per metre of closure.)
    if (m->actuator_trntype[drive.actuator] == mjTRN_TENDON && scene_.hand.model != HandModel::kJaw)
      drive.transmission = 2.0;
    drive.stall = place.stall_effort[k];
    drive.no_load_speed = place.no_load_speed[k];
    drive.lever_arm_m = place.lever_arm_m[k];
    grip_drives_.push_back(drive);
  }
  if (scene_.hand.model == HandModel::kJaw) {
    digit_joints_ = {{{RequireId(m, mjOBJ_JOINT, "finger_slide"), -1}, {RequireId(m, mjOBJ_JOINT, "thumb_slide"), -1}}};
    digit_drive_ = {0, -1};
  } else {
    digit_joints_ = {{{RequireId(m, mjOBJ_JOINT, "index_mcp"), RequireId(m, mjOBJ_JOINT, "index_pip")},
                      {RequireId(m, mjOBJ_JOINT, "thumb_flexion"), -1}}};
    digit_drive_ = {0, 1};
  }
  const char* servo_names[3] = {"wrist_x_servo", "wrist_y_servo", "wrist_z_servo"};
  const char* joint_names[3] = {"wrist_x", "wrist_y", "wrist_z"};
  for (int k = 0; k < 3; ++k) {
    wrist_actuators_[k] = RequireId(m, mjOBJ_ACTUATOR, servo_names[k]);
    wrist_joint_qpos_[k] = m->jnt_qposadr[RequireId(m, mjOBJ_JOINT, joint_names[k])];
  }

  // geom -> unit and geom -> side tables, built once: a digit is its root body's subtree.
  geom_unit_.assign(m->ngeom, -1);
  geom_side_.assign(m->ngeom, kOther);
  for (int i = 0; i < layout_.unit_count(); ++i) {
    const std::string name = "unit_" + std::to_string(i);
    geom_unit_[RequireId(m, mjOBJ_GEOM, name.c_str())] = i;
  }
  const int palm_body = RequireId(m, mjOBJ_BODY, "palm");
  for (int g = 0; g < m->ngeom; ++g) {
    for (int body = m->geom_bodyid[g]; body > 0; body = m->body_parentid[body]) {
      if (body == finger_body) {
        geom_side_[g] = kFinger;
      } else if (body == thumb_body) {
        geom_side_[g] = kThumb;
      } else if (body == palm_body || body == wrist_body_) {
        if (geom_side_[g] == kOther) geom_side_[g] = kHandOther;
      } else {
        continue;
      }
      break;
    }
  }
  geom_is_link_.assign(m->ngeom, 0);
  for (const char* link : {"finger_proximal", "finger_middle", "finger_link"}) {
    const int geom = mj_name2id(m, mjOBJ_GEOM, link);
    if (geom >= 0) geom_is_link_[geom] = 1;
  }
  unit_frames_.resize(layout_.unit_count());
  for (int i = 0; i < layout_.unit_count(); ++i) {
    const sensor::UnitPose& unit = layout_.units[i];
    const Eigen::Vector3d n = unit.inward_normal.normalized();
    const Eigen::Vector3d beam = unit.beam_axis.normalized();
    const Eigen::Vector3d cross = n.cross(beam);  // UnitLoad: cross shear along normal x beam
    for (int k = 0; k < 3; ++k) {
      unit_frames_[i][k] = n[k];
      unit_frames_[i][3 + k] = beam[k];
      unit_frames_[i][6 + k] = cross[k];
      unit_frames_[i][9 + k] = unit.position_m[k];
    }
  }

  object_mass_ = m->body_mass[object_body_];
  for (int k = 0; k < 3; ++k) object_inertia_[k] = m->body_inertia[3 * object_body_ + k];
  object_dof_ = m->jnt_dofadr[m->body_jntadr[object_body_]];
  for (int k = 0; k < 6; ++k) {
    object_dof_m0_[k] = m->dof_M0[object_dof_ + k];
    object_dof_invweight0_[k] = m->dof_invweight0[object_dof_ + k];
  }
  for (int k = 0; k < 2; ++k) object_body_invweight0_[k] = m->body_invweight0[2 * object_body_ + k];
  SetObjectMass(scene_.object.mass_kg);
  SetObjectFriction(scene_.object.friction);
  hand_weight_n_ = m->body_subtreemass[wrist_body_] * scene_.physics.gravity_m_s2;
  for (int k = 0; k < 3; ++k) wrist_target_[k] = m->body_pos[3 * wrist_body_ + k];
  mj_forward(model_.get(), data_.get());
  initial_aperture_m_ =
      mju_dist3(data_->site_xpos + 3 * finger_pad_site_, data_->site_xpos + 3 * thumb_pad_site_);
}

void Simulation::ModelDeleter::operator()(mjModel_* model) const { mj_deleteModel(model); }
void Simulation::DataDeleter::operator()(mjData_* data) const { mj_deleteData(data); }

Simulation::~Simulation() = default;

double Simulation::time_s() const { return data_->time; }
double Simulation::timestep_s() const { return model_->opt.timestep; }

void Simulation::SetGripEffort(double effort) {
  grip_effort_ = std::isfinite(effort) ? std::clamp(effort, -1.0, 1.0) : 0.0;
}

void Simulation::SetGripBrake(bool engaged) {
  for (const GripDrive& drive : grip_drives_) {
    if (engaged && !brake_engaged_) {
      // Joint (tendon) equality with only joint1 (tendon1): joint = qpos0 + polycoef[0] (the tendon's
      // length = its length at qpos0 + polycoef[0]).
      model_->eq_data[drive.brake_equality * mjNEQDATA + 0] =
          drive.brake_tendon >= 0
              ? data_->ten_length[drive.brake_tendon] - model_->tendon_length0[drive.brake_tendon]
              : data_->qpos[drive.brake_joint_qpos] - model_->qpos0[drive.brake_joint_qpos];
    }
    model_->eq_active[drive.brake_equality] = engaged ? 1 : 0;
  }
  brake_engaged_ = engaged;
}

void Simulation::SetWristTarget(const std::array<double, 3>& position_m) { wrist_target_ = position_m; }

void Simulation::SetObjectExternalForce(const std::array<double, 3>& force_n) {
  for (double component : force_n) {
    if (!std::isfinite(component))
      throw std::invalid_argument("object external force: components must be finite");
  }
  for (int k = 0; k < 3; ++k) {
    data_->xfrc_applied[6 * object_body_ + k] = force_n[k];
    external_force_[k] = force_n[k];
  }
}

void Simulation::SetObjectMass(double mass_kg) {
  if (!(mass_kg > 0.0) || !std::isfinite(mass_kg)) {
    throw std::invalid_argument("object mass = " + std::to_string(mass_kg) + " kg: must be > 0");
  }
  // Mass and inertia scale together (same shape and density distribution), so do the free joint's
  // diagonal mass at qpos0 (dof_M0: MuJoCo fills the mass matrix of such "simple" dofs from it, not
  // from body_mass) and, inversely, the inverse weights that scale the contacts' regularisation.
  mjModel* m = model_.get();
  const double scale = mass_kg / object_mass_;
  const double added_kg = mass_kg - m->body_mass[object_body_];
  double added_diagonal = 0.0;
  for (int k = 0; k < 6; ++k) {
    const double m0 = object_dof_m0_[k] * scale;
    added_diagonal += m0 - m->dof_M0[object_dof_ + k];
    m->dof_M0[object_dof_ + k] = m0;
    m->dof_invweight0[object_dof_ + k] = object_dof_invweight0_[k] / scale;
  }
  for (int k = 0; k < 2; ++k) m->body_invweight0[2 * object_body_ + k] = object_body_invweight0_[k] / scale;
  for (int body = object_body_; body >= 0; body = body > 0 ? m->body_parentid[body] : -1)
    m->body_subtreemass[body] += added_kg;
  m->stat.meanmass += added_kg / (m->nbody - 1);
  m->stat.meaninertia += added_diagonal / m->nv;  // mean diagonal of M at qpos0
  m->body_mass[object_body_] = mass_kg;
  for (int k = 0; k < 3; ++k) m->body_inertia[3 * object_body_ + k] = object_inertia_[k] * scale;
}

double Simulation::object_mass_kg() const { return model_->body_mass[object_body_]; }

void Simulation::SetObjectFriction(double friction) {
  if (!(friction > 0.0) || !std::isfinite(friction)) {
    throw std::invalid_argument("object friction = " + std::to_string(friction) + ": must be > 0");
  }
  // The soft finger's spin friction follows the sliding friction (its patch does not change).
  const double torsional = scene_.TorsionalFrictionM(friction);
  for (const int geom : object_geoms_) {
    model_->geom_friction[3 * geom] = friction;
    model_->geom_friction[3 * geom + 1] = torsional;
  }
  // The listed contact pairs carry their own friction (sliding along both tangents, then spin).
  for (const int pair : object_pairs_) {
    model_->pair_friction[5 * pair] = friction;
    model_->pair_friction[5 * pair + 1] = friction;
    model_->pair_friction[5 * pair + 2] = torsional;
  }
}

void Simulation::ApplyControls() {
  for (const GripDrive& drive : grip_drives_)
    data_->ctrl[drive.actuator] = brake_engaged_ ? 0.0 : grip_effort_;
  for (int k = 0; k < 3; ++k) {
    // Joint zero is the initial wrist position; z carries the hand's weight in the target.
    double target = wrist_target_[k] - model_->body_pos[3 * wrist_body_ + k];
    if (k == 2) target += hand_weight_n_ / scene_.hand.wrist_stiffness_n_m;
    data_->ctrl[wrist_actuators_[k]] = target;
  }
  for (int k = 0; k < 3; ++k) data_->xfrc_applied[6 * object_body_ + k] = external_force_[k];
}

void Simulation::Step() {
  step_start_time_s_ = data_->time;
  // The clock advances by one step whatever happens, so no `while (time < end) Step()` loop can
  // wait forever: after a fault the physics stays frozen (MuJoCo has reset the state) and only
  // the clock moves; in the step that faults, MuJoCo's reset of the clock to 0 is undone.
  const double next_time_s = step_start_time_s_ + model_->opt.timestep;
  if (fault_.occurred) {
    data_->time = next_time_s;
    return;
  }
  ApplyControls();
  tls_last_warning[0] = '\0';
  mj_step(model_.get(), data_.get());
  CheckFault();
  if (fault_.occurred || !(data_->time > step_start_time_s_)) {
    if (!(next_time_s > step_start_time_s_)) RecordFault("simulation time does not advance");
    data_->time = next_time_s;
  }
}

void Simulation::StepUntil(double time_s) {
  // Half a step of slack so floating-point time sums do not add a step. A fault ends the stepping.
  while (!fault_.occurred && data_->time < time_s - 0.5 * model_->opt.timestep) Step();
}

void Simulation::RecordFault(const char* cause) {
  if (fault_.occurred) return;
  fault_.occurred = true;
  // MuJoCo resets the state (and the clock) on a bad number, so the step's start time is kept.
  fault_.time_s = step_start_time_s_;
  std::snprintf(fault_.cause.data(), fault_.cause.size(), "%.150s", cause);
}

void Simulation::CheckFault() {
  for (int w = 0; w < mjNWARNING; ++w) {
    const uint64_t count = static_cast<uint64_t>(data_->warning[w].number);
    if (count > warning_seen_[w]) {
      fault_.warning_count += count - warning_seen_[w];
      warning_seen_[w] = count;
      char cause[200];
      // The handler's text when MuJoCo printed one (first occurrence), else the stock text.
      std::snprintf(
          cause, sizeof(cause), "MuJoCo warning: %.150s",
          tls_last_warning[0] != '\0' ? tls_last_warning : mju_warningText(w, data_->warning[w].lastinfo));
      RecordFault(cause);
    }
  }
  for (int i = 0; i < model_->nq; ++i) {
    if (!std::isfinite(data_->qpos[i])) {
      RecordFault("NaN/inf in qpos");
      return;
    }
  }
  for (int i = 0; i < model_->nv; ++i) {
    if (!std::isfinite(data_->qvel[i])) {
      RecordFault("NaN/inf in qvel");
      return;
    }
  }
}

void Simulation::ComputeUnitLoads(std::span<sensor::UnitLoad> loads) const {
  const int n_units = layout_.unit_count();
  if (static_cast<int>(loads.size()) != n_units) {
    throw std::invalid_argument("ComputeUnitLoads: " + std::to_string(loads.size()) + " loads for " +
                                std::to_string(n_units) + " units");
  }
  std::array<double, sensor::kMaxUnits> moment{};  // sum of Fn x offset per unit [N m]
  for (auto& load : loads) load = sensor::UnitLoad{};
  const mjtNum* holder_rot = data_->xmat + 9 * holder_body_;  // holder -> world, row-major
  const mjtNum* holder_pos = data_->xpos + 3 * holder_body_;
  for (int c = 0; c < data_->ncon; ++c) {
    const mjContact& contact = data_->contact[c];
    const int unit1 = geom_unit_[contact.geom1];
    const int unit2 = geom_unit_[contact.geom2];
    if (unit1 < 0 && unit2 < 0) continue;
    if (unit1 >= 0 && unit2 >= 0) continue;  // mesa on mesa: internal to the finger
    mjtNum local[6];
    mj_contactForce(model_.get(), data_.get(), c, local);
    // Rows of contact.frame are the contact axes (normal from geom1 to geom2, then the tangents);
    // the force acts on geom2 along +normal, on geom1 opposite.
    mjtNum world[3];
    mju_mulMatTVec(world, contact.frame, local, 3, 3);
    const int unit = unit1 >= 0 ? unit1 : unit2;
    const double sign = unit1 >= 0 ? -1.0 : 1.0;
    mjtNum force_holder[3];
    mju_mulMatTVec(force_holder, holder_rot, world, 3, 3);  // world -> holder frame
    mjtNum rel[3] = {contact.pos[0] - holder_pos[0], contact.pos[1] - holder_pos[1],
                     contact.pos[2] - holder_pos[2]};
    mjtNum pos_holder[3];
    mju_mulMatTVec(pos_holder, holder_rot, rel, 3, 3);
    const auto& f = unit_frames_[unit];
    const double fn = sign * mju_dot3(force_holder, f.data());
    sensor::UnitLoad& load = loads[unit];
    load.fn_n += fn;
    load.ft_n += sign * mju_dot3(force_holder, f.data() + 3);
    load.cross_shear_n += sign * mju_dot3(force_holder, f.data() + 6);
    const mjtNum offset_vec[3] = {pos_holder[0] - f[9], pos_holder[1] - f[10], pos_holder[2] - f[11]};
    moment[unit] += fn * mju_dot3(offset_vec, f.data() + 3);
  }
  for (int i = 0; i < n_units; ++i) {
    if (loads[i].fn_n > 1e-9) loads[i].offset_along_beam_m = moment[i] / loads[i].fn_n;
  }
}

std::array<DigitTruth, 2> Simulation::ReadDigits() const {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  std::array<DigitTruth, 2> digits{};
  for (int k = 0; k < 2; ++k) {
    DigitTruth& digit = digits[k];
    for (const int joint : digit_joints_[k]) {
      if (joint < 0) continue;
      const int qpos = m->jnt_qposadr[joint];
      const int dof = m->jnt_dofadr[joint];
      digit.linear = m->jnt_type[joint] == mjJNT_SLIDE;
      digit.position[digit.joint_count] = d->qpos[qpos] - m->qpos0[qpos];
      digit.velocity[digit.joint_count] = d->qvel[dof];
      if (digit.joint_count == 0) {
        const bool limited = m->jnt_limited[joint] != 0;
        const double inf = std::numeric_limits<double>::infinity();
        digit.open_stop = limited ? m->jnt_range[2 * joint] - m->qpos0[qpos] : -inf;
        digit.closed_stop = limited ? m->jnt_range[2 * joint + 1] - m->qpos0[qpos] : inf;
      }
      ++digit.joint_count;
    }
    if (digit_drive_[k] < 0) continue;
    const GripDrive& drive = grip_drives_[digit_drive_[k]];
    // Torque at the driven joint: stall x effort (the actuator) less the back-EMF term the joint's
    // damping carries, over the stall torque: the winding current's share of its stall current.
    digit.has_motor = true;
    digit.motor_torque_share = (drive.transmission * d->actuator_force[drive.actuator] -
                                drive.stall * d->actuator_velocity[drive.actuator] /
                                    (drive.transmission * drive.no_load_speed)) /
                               drive.stall;
    if (brake_engaged_) digit.motor_torque_share = 0.0;
  }
  return digits;
}

double Simulation::LowestObjectPointM() const {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  double lowest = std::numeric_limits<double>::infinity();
  for (const int g : object_geoms_) {
    const mjtNum* rot = d->geom_xmat + 9 * g;  // row-major; row 2 = world z in geom axes
    const mjtNum* size = m->geom_size + 3 * g;
    const double centre_z = d->geom_xpos[3 * g + 2];
    double below = 0.0;
    switch (m->geom_type[g]) {
      case mjGEOM_BOX:
        below = std::abs(rot[6]) * size[0] + std::abs(rot[7]) * size[1] + std::abs(rot[8]) * size[2];
        break;
      case mjGEOM_SPHERE:
        below = size[0];
        break;
      case mjGEOM_CAPSULE:
        below = std::abs(rot[8]) * size[1] + size[0];
        break;
      case mjGEOM_CYLINDER:
        below = std::abs(rot[8]) * size[1] + size[0] * std::sqrt(std::max(0.0, 1.0 - rot[8] * rot[8]));
        break;
      case mjGEOM_MESH: {
        const int mesh = m->geom_dataid[g];
        const float* vertex = m->mesh_vert + 3 * m->mesh_vertadr[mesh];
        double lowest_offset = std::numeric_limits<double>::infinity();
        for (int v = 0; v < m->mesh_vertnum[mesh]; ++v, vertex += 3)
          lowest_offset = std::min(lowest_offset, rot[6] * vertex[0] + rot[7] * vertex[1] + rot[8] * vertex[2]);
        below = -lowest_offset;
        break;
      }
      default:
        below = m->geom_rbound[g];
        break;
    }
    lowest = std::min(lowest, centre_z - below);
  }
  return lowest;
}

GroundTruth Simulation::truth() const {
  const mjModel* m = model_.get();
  const mjData* d = data_.get();
  GroundTruth t;
  t.time_s = d->time;
  mjtNum object_vel[6];
  mj_objectVelocity(m, d, mjOBJ_BODY, object_body_, object_vel, 0);
  for (int k = 0; k < 3; ++k) {
    t.object_position_m[k] = d->xipos[3 * object_body_ + k];
    t.object_angular_velocity_rad_s[k] = object_vel[k];
    t.object_velocity_m_s[k] = object_vel[3 + k];
    t.wrist_position_m[k] = d->xpos[3 * wrist_body_ + k];
  }
  // Lowest point of the object's geoms: each centre's z minus its half extent along world z (the
  // same arithmetic for a box, cylinder or sphere as the single geom always had).
  t.object_height_above_table_m = LowestObjectPointM();
  {
    const mjtNum* pad = d->site_xpos + 3 * finger_pad_site_;
    const mjtNum* tip = d->site_xpos + 3 * thumb_pad_site_;
    mjtNum across[3] = {tip[0] - pad[0], tip[1] - pad[1], tip[2] - pad[2]};
    const mjtNum aperture = mju_normalize3(across);
    t.grip_closure_m = initial_aperture_m_ - aperture;
    mjtNum pad_vel[6];
    mjtNum tip_vel[6];
    mj_objectVelocity(m, d, mjOBJ_SITE, finger_pad_site_, pad_vel, 0);
    mj_objectVelocity(m, d, mjOBJ_SITE, thumb_pad_site_, tip_vel, 0);
    const mjtNum rel[3] = {tip_vel[3] - pad_vel[3], tip_vel[4] - pad_vel[4], tip_vel[5] - pad_vel[5]};
    t.grip_velocity_m_s = -mju_dot3(rel, across);
  }
  // Stall x effort minus the back-EMF term carried by the driven joint's damping, as pinch force.
  const GripDrive& drive = grip_drives_.front();
  t.grip_motor_force_n = (drive.transmission * d->actuator_force[drive.actuator] -
                          drive.stall * d->actuator_velocity[drive.actuator] /
                              (drive.transmission * drive.no_load_speed)) /
                         drive.lever_arm_m;

  double finger_on_object = 0.0;
  double thumb_on_object = 0.0;
  double finger_sliding_normal = 0.0;
  double thumb_sliding_normal = 0.0;
  double slip_weighted = 0.0;
  double slip_weight = 0.0;
  // Tangential force of each digit on the object, world frame [N].
  mjtNum finger_tangential[3] = {0.0, 0.0, 0.0};
  mjtNum thumb_tangential[3] = {0.0, 0.0, 0.0};
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& contact = d->contact[c];
    const int side1 = geom_side_[contact.geom1];
    const int side2 = geom_side_[contact.geom2];
    const bool digit1 = side1 == kFinger || side1 == kThumb;
    const bool digit2 = side2 == kFinger || side2 == kThumb;
    if ((side1 == kHandOther && geom_is_object_[contact.geom2]) ||
        (side2 == kHandOther && geom_is_object_[contact.geom1])) {
      mjtNum palm[6];
      mj_contactForce(m, d, c, palm);
      t.palm_normal_force_n += palm[0];
      continue;
    }
    if (digit1 == digit2) continue;  // hand on hand, or nothing of the digits
    if (side1 == kHandOther || side2 == kHandOther) continue;
    const int digit_geom = digit1 ? contact.geom1 : contact.geom2;
    const int other_geom = digit1 ? contact.geom2 : contact.geom1;
    const int side = digit1 ? side1 : side2;
    mjtNum local[6];
    mj_contactForce(m, d, c, local);
    const double normal = local[0];
    if (side == kFinger) {
      t.finger_normal_force_n += normal;
      if (geom_unit_[digit_geom] >= 0) {
        t.sensed_normal_force_n += normal;
        t.holder_normal_force_n += normal;
      } else if (digit_geom == holder_shell_geom_) {
        t.holder_normal_force_n += normal;
      }
    } else {
      t.thumb_normal_force_n += normal;
    }
    if (!geom_is_object_[other_geom]) continue;
    if (side == kFinger) {
      finger_on_object += normal;
      ++t.finger_contacts;
      if (geom_is_link_[digit_geom]) t.finger_links_normal_force_n += normal;
      if (geom_unit_[digit_geom] >= 0) t.sensed_object_normal_force_n += normal;
      if (geom_unit_[digit_geom] >= 0) {
        t.max_mesa_penetration_m = std::max(t.max_mesa_penetration_m, -contact.dist);
      } else if (digit_geom == holder_shell_geom_ && contact.dist < 0.0) {
        t.object_touches_holder_shell = true;
      }
    } else {
      thumb_on_object += normal;
      ++t.thumb_contacts;
    }
    // contact.frame rows are the normal (from geom1 to geom2) and the two tangent directions, world
    // frame; mj_contactForce gives the force on geom2 in it. MuJoCo orders the pair by geom type,
    // so the object may be either: flip the sign when it is geom1 to get the force on the object.
    const double on_object = geom_is_object_[contact.geom2] ? 1.0 : -1.0;
    mjtNum* tangential = side == kFinger ? finger_tangential : thumb_tangential;
    for (int k = 0; k < 3; ++k) {
      const double along_tangents = local[1] * contact.frame[3 + k] + local[2] * contact.frame[6 + k];
      tangential[k] += on_object * along_tangents;
      t.hand_load_n[k] += on_object * (local[0] * contact.frame[k] + along_tangents);
    }
    mjtNum v_object[3];
    mjtNum v_digit[3];
    PointVelocity(m, d, object_body_, contact.pos, v_object);
    PointVelocity(m, d, m->geom_bodyid[digit_geom], contact.pos, v_digit);
    mjtNum rel[3] = {v_object[0] - v_digit[0], v_object[1] - v_digit[1], v_object[2] - v_digit[2]};
    const mjtNum along_normal = mju_dot3(rel, contact.frame);
    for (int k = 0; k < 3; ++k) rel[k] -= along_normal * contact.frame[k];
    const double slip = mju_norm3(rel);
    t.slip_speed_m_s = std::max(t.slip_speed_m_s, slip);
    // local = [Fn, Ft1, Ft2, ...]; contact.friction[0] is the pair's sliding friction coefficient.
    if (normal > 0.0 &&
        std::hypot(local[1], local[2]) >= sliding_friction_fraction_ * contact.friction[0] * normal) {
      t.sliding_speed_m_s = std::max(t.sliding_speed_m_s, slip);
      double& digit_sliding = side == kFinger ? t.finger_sliding_speed_m_s : t.thumb_sliding_speed_m_s;
      digit_sliding = std::max(digit_sliding, slip);
      (side == kFinger ? finger_sliding_normal : thumb_sliding_normal) += normal;
    }
    slip_weighted += slip * std::max(normal, 0.0);
    slip_weight += std::max(normal, 0.0);
  }
  if (slip_weight > 0.0) t.mean_slip_speed_m_s = slip_weighted / slip_weight;
  if (t.holder_normal_force_n > 1e-9) t.sensed_share = t.sensed_normal_force_n / t.holder_normal_force_n;
  t.object_squeeze_n = std::max(finger_on_object, thumb_on_object);
  t.finger_object_normal_force_n = finger_on_object;
  if (finger_on_object > 0.0) t.sliding_load_share = finger_sliding_normal / finger_on_object;
  if (thumb_on_object > 0.0)
    t.sliding_load_share = std::max(t.sliding_load_share, thumb_sliding_normal / thumb_on_object);
  for (int k = 0; k < 3; ++k) t.object_tangential_force_n[k] = finger_tangential[k] + thumb_tangential[k];
  t.object_tangential_load_n = mju_norm3(t.object_tangential_force_n.data());
  // The full contact forces summed: the squeeze of one digit cancels the other's, what remains is
  // the load (weight, inertia, pulls) the hand carries.
  const double friction = m->geom_friction[3 * object_geom_];
  if (friction > 0.0) t.load_bound_grip_n = mju_norm3(t.hand_load_n.data()) / (2.0 * friction);
  return t;
}

}  // namespace graspbed::sim

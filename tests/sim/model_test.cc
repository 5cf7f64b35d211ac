// The generated model: checked-in copy current, names and poses of the mesas, loads for every
// shipped layout and object shape, the grip motor's stall force.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "sim/model_generator.h"
#include "tests/sim/sim_fixture.h"
#include "tests/support/files.h"

namespace graspbed::sim {
namespace {

using graspbed::test_support::ReadText;
using graspbed::test_support::SourcePath;

constexpr double kPoseTolM = 1e-9;
/// The MJCF carries 8 significant digits, so a unit axis comes back within a few 1e-9.
constexpr double kAxisTol = 1e-7;
constexpr double kForceTolN = 0.05;

class ModelTest : public test_support::MujocoTest {};

TEST_F(ModelTest, CheckedInModelIsCurrent) {
  const std::string path = SourcePath("models/hand_default.xml");
  const std::string checked_in = ReadText(path);
  ASSERT_FALSE(checked_in.empty()) << path;
  const std::string generated = GenerateMjcf(DefaultLayout(), SceneConfig{});
  if (checked_in == generated) return;
  // Name the first line that differs rather than dumping both models.
  std::istringstream a(checked_in);
  std::istringstream b(generated);
  std::string line_a;
  std::string line_b;
  int line = 0;
  while (true) {
    ++line;
    const bool more_a = static_cast<bool>(std::getline(a, line_a));
    const bool more_b = static_cast<bool>(std::getline(b, line_b));
    if (line_a != line_b || more_a != more_b) break;
  }
  ADD_FAILURE() << "models/hand_default.xml is stale (first difference at line " << line
                << "); regenerate: graspbed model -o models/hand_default.xml\n  checked in: " << line_a
                << "\n  generated:  " << line_b;
}

// A Simulation compiles the object with a nominal mass and friction (one compiled model for the
// runs that differ only in them) and sets the scene's own afterwards: the result is the model
// compiled directly from the scene's MJCF, to rounding.
TEST_F(ModelTest, TheObjectsMassAndFrictionSetAfterLoadingGiveTheModelCompiledWithThem) {
  SceneConfig scene;
  scene.object.mass_kg = 0.237;
  scene.object.friction = 0.43;
  const std::string mjcf = GenerateMjcf(DefaultLayout(), scene);
  mjModel* direct = CompileMjcf(mjcf);
  const Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
  const mjModel* patched = simulation.model();
  ASSERT_EQ(patched->nbody, direct->nbody);
  ASSERT_EQ(patched->nv, direct->nv);
  ASSERT_EQ(patched->ngeom, direct->ngeom);
  constexpr double kRelTol = 1e-12;
  auto expect_same = [&](const char* what, const mjtNum* a, const mjtNum* b, int n) {
    for (int i = 0; i < n; ++i)
      EXPECT_NEAR(a[i], b[i], kRelTol * std::max(1.0, std::abs(b[i]))) << what << "[" << i << "]";
  };
  expect_same("body_mass", patched->body_mass, direct->body_mass, direct->nbody);
  expect_same("body_inertia", patched->body_inertia, direct->body_inertia, 3 * direct->nbody);
  expect_same("body_invweight0", patched->body_invweight0, direct->body_invweight0, 2 * direct->nbody);
  expect_same("dof_invweight0", patched->dof_invweight0, direct->dof_invweight0, direct->nv);
  expect_same("dof_M0", patched->dof_M0, direct->dof_M0, direct->nv);
  // The model text carries 8 significant digits: the soft finger's spin friction, (2/3) mu a, is
  // rounded there and exact when set.
  constexpr double kTextRelTol = 1e-7;  // half a unit of the 8th digit, relative, with margin
  auto expect_as_written = [&](const char* what, const mjtNum* a, const mjtNum* b, int n) {
    for (int i = 0; i < n; ++i)
      EXPECT_NEAR(a[i], b[i], kTextRelTol * std::max(1e-3, std::abs(b[i]))) << what << "[" << i << "]";
  };
  expect_as_written("geom_friction", patched->geom_friction, direct->geom_friction, 3 * direct->ngeom);
  ASSERT_EQ(patched->npair, direct->npair);
  expect_as_written("pair_friction", patched->pair_friction, direct->pair_friction, 5 * direct->npair);
  expect_same("body_subtreemass", patched->body_subtreemass, direct->body_subtreemass, direct->nbody);
  // The solver scales its convergence tests by the mean inertia.
  expect_same("stat.meaninertia", &patched->stat.meaninertia, &direct->stat.meaninertia, 1);
  expect_same("stat.meanmass", &patched->stat.meanmass, &direct->stat.meanmass, 1);
  mj_deleteModel(direct);
}

// The generated model lists its contact pairs (collision="predefined": no broad phase) with the
// parameters MuJoCo's dynamic collision mixes from the geoms. The model generated with
// physics.contact_pairs false (dynamic collision: the geoms' contype / conaffinity decide) must
// then give the same contacts, in the same
// order, with the same parameters, and the same trajectory to the last bit: a grasp closing on the
// object on the table and lifting it, for both hands, three shapes and the wrap.
TEST_F(ModelTest, ThePredefinedPairsGiveTheContactsOfDynamicCollision) {
  struct Case {
    const char* name;
    SceneConfig scene;
  };
  std::vector<Case> cases;
  for (ObjectShape shape : {ObjectShape::kBox, ObjectShape::kCylinder, ObjectShape::kSphere}) {
    SceneConfig scene;
    scene.object.shape = shape;
    scene.object.friction = 0.6;
    cases.push_back({ToString(shape), scene});
  }
  SceneConfig wrap;
  wrap.object.shape = ObjectShape::kCylinder;
  wrap.object.size_m = {0.05, 0.05, 0.1};
  wrap.hand.grasp = GraspType::kWrap;
  cases.push_back({"wrap", wrap});
  SceneConfig jaw;
  jaw.hand.model = HandModel::kJaw;
  jaw.hand.open_gap_m = 0.065;
  cases.push_back({"jaw", jaw});

  for (const Case& c : cases) {
    SceneConfig broad_phase = c.scene;
    broad_phase.physics.contact_pairs = false;
    mjModel* models[2] = {CompileMjcf(GenerateMjcf(DefaultLayout(), c.scene)),
                          CompileMjcf(GenerateMjcf(DefaultLayout(), broad_phase))};
    mjData* data[2] = {mj_makeData(models[0]), mj_makeData(models[1])};
    EXPECT_GT(models[0]->npair, 20) << c.name;
    EXPECT_EQ(models[0]->opt.collision, mjCOL_PAIR) << c.name;
    EXPECT_EQ(models[1]->opt.collision, mjCOL_DYNAMIC) << c.name;
    const int wrist_z = mj_name2id(models[0], mjOBJ_ACTUATOR, "wrist_z_servo");
    const int object_geom = mj_name2id(models[0], mjOBJ_GEOM, "object_geom");
    int steps_with_mesa_contact = 0;
    int steps_on_table = 0;
    constexpr int kSteps = 1200;  // 0.6 s closing at half effort on the table, 0.6 s lifting 30 mm
    for (int step = 0; step < kSteps; ++step) {
      for (int k = 0; k < 2; ++k) {
        for (const std::string& motor : GripMotorNames(c.scene.hand.model))
          data[k]->ctrl[mj_name2id(models[k], mjOBJ_ACTUATOR, motor.c_str())] = 0.5;
        data[k]->ctrl[wrist_z] = step < kSteps / 2 ? 0.0 : 0.03 * (step - kSteps / 2) / (kSteps / 2);
        mj_step(models[k], data[k]);
      }
      ASSERT_EQ(data[0]->ncon, data[1]->ncon) << c.name << " step " << step;
      bool mesa = false;
      bool table = false;
      for (int i = 0; i < data[0]->ncon; ++i) {
        const mjContact& a = data[0]->contact[i];
        const mjContact& b = data[1]->contact[i];
        ASSERT_EQ(a.geom1, b.geom1) << c.name << " step " << step << " contact " << i;
        ASSERT_EQ(a.geom2, b.geom2) << c.name << " step " << step << " contact " << i;
        ASSERT_EQ(a.dim, b.dim) << c.name;
        EXPECT_EQ(a.dist, b.dist) << c.name;
        for (int k = 0; k < 5; ++k) EXPECT_EQ(a.friction[k], b.friction[k]) << c.name << " friction " << k;
        for (int k = 0; k < mjNREF; ++k) EXPECT_EQ(a.solref[k], b.solref[k]) << c.name << " solref " << k;
        for (int k = 0; k < mjNIMP; ++k) EXPECT_EQ(a.solimp[k], b.solimp[k]) << c.name << " solimp " << k;
        // MuJoCo puts the geom of the lower type first: the object may be either.
        const int other = a.geom1 == object_geom ? a.geom2 : a.geom2 == object_geom ? a.geom1 : -1;
        const char* name = other >= 0 ? mj_id2name(models[0], mjOBJ_GEOM, other) : nullptr;
        mesa |= name != nullptr && std::string(name).rfind("unit_", 0) == 0;
        table |= other >= 0 && models[0]->geom_bodyid[other] == 0;
      }
      steps_with_mesa_contact += mesa;
      steps_on_table += table;
    }
    for (int q = 0; q < models[0]->nq; ++q)
      EXPECT_EQ(data[0]->qpos[q], data[1]->qpos[q]) << c.name << " qpos " << q;
    // Not vacuous: the sensor touched the object, and the object stood on the table (no wrap: its
    // pad may meet the cylinder where no unit is).
    if (std::string(c.name) != "wrap") {
      EXPECT_GT(steps_with_mesa_contact, kSteps / 4) << c.name;
    }
    EXPECT_GT(steps_on_table, kSteps / 4) << c.name;
    for (int k = 0; k < 2; ++k) {
      mj_deleteData(data[k]);
      mj_deleteModel(models[k]);
    }
  }
}

// A mass set while the simulation runs (add_mass, pouring) is the object's inertial mass too: a
// free-floating box pushed with 1 N accelerates at 1 N / m after its mass changed from 0.1 to 0.5 kg.
TEST_F(ModelTest, AMassChangedMidRunIsTheMassThatAccelerates) {
  SceneConfig scene;
  scene.physics.gravity_m_s2 = 0.0;
  scene.physics.table = false;
  scene.object.mass_kg = 0.1;
  Simulation& simulation = MakeSimulation(DefaultLayout(), scene);  // open hand: no contact
  simulation.StepUntil(0.05);
  simulation.SetObjectMass(0.5);
  constexpr double kForceN = 1.0;
  constexpr double kPushS = 0.1;
  simulation.SetObjectExternalForce({0.0, kForceN, 0.0});  // along y, out of the hand
  const double v0 = simulation.truth().object_velocity_m_s[1];
  const double t0 = simulation.time_s();
  simulation.StepUntil(t0 + kPushS);
  const GroundTruth truth = simulation.truth();
  ASSERT_EQ(truth.finger_contacts + truth.thumb_contacts, 0);
  const double acceleration = (truth.object_velocity_m_s[1] - v0) / (simulation.time_s() - t0);
  // Euler integration of a constant force is exact, but the velocity truth() reads (MuJoCo's cvel)
  // is the one the last step started from: one step of the push short.
  const double expected = kForceN / 0.5;
  EXPECT_NEAR(acceleration, expected, expected * simulation.timestep_s() / kPushS + 1e-9)
      << "m/s^2; 1 N / 0.1 kg would be 10";
}

TEST_F(ModelTest, MesaGeomsFollowTheLayoutInOrder) {
  const sensor::Layout& layout = DefaultLayout();
  Simulation& simulation = MakeSimulation(layout, SceneConfig{});
  const mjModel* m = simulation.model();
  const mjData* d = simulation.data();
  const int holder = mj_name2id(m, mjOBJ_BODY, "holder");
  ASSERT_GE(holder, 0);
  for (int i = 0; i < layout.unit_count(); ++i) {
    const std::string name = "unit_" + std::to_string(i);
    const int geom = mj_name2id(m, mjOBJ_GEOM, name.c_str());
    ASSERT_GE(geom, 0) << name;
    EXPECT_EQ(m->geom_bodyid[geom], holder) << name;
    // The mesa top centre, brought back into the holder frame, is mesa_height outside the unit's
    // surface point along its outward normal.
    const mjtNum* rot = d->geom_xmat + 9 * geom;  // geom axes as columns, row-major
    mjtNum top_world[3];
    for (int k = 0; k < 3; ++k)
      top_world[k] = d->geom_xpos[3 * geom + k] + rot[3 * k + 2] * m->geom_size[3 * geom + 2];
    const mjtNum* holder_rot = d->xmat + 9 * holder;
    mjtNum rel[3];
    for (int k = 0; k < 3; ++k) rel[k] = top_world[k] - d->xpos[3 * holder + k];
    mjtNum top_holder[3];
    mju_mulMatTVec(top_holder, holder_rot, rel, 3, 3);
    const sensor::UnitPose& unit = layout.units[i];
    const Eigen::Vector3d expected = unit.position_m - unit.inward_normal * layout.unit.mesa_height_m;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(top_holder[k], expected[k], kPoseTolM) << name << " axis " << k;
    // Geom x axis = beam axis (holder frame).
    mjtNum x_world[3] = {rot[0], rot[3], rot[6]};
    mjtNum x_holder[3];
    mju_mulMatTVec(x_holder, holder_rot, x_world, 3, 3);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(x_holder[k], unit.beam_axis[k], kAxisTol) << name;
  }
  EXPECT_LT(mj_name2id(m, mjOBJ_GEOM, ("unit_" + std::to_string(layout.unit_count())).c_str()), 0);
}

TEST_F(ModelTest, EveryShippedLayoutAndShapeLoadsAndSettles) {
  for (const char* layout_file : {"default_20.yaml", "paper_3x3.yaml"}) {
    const sensor::Layout layout =
        sensor::LoadLayout(SourcePath(std::string("sensor/layouts/") + layout_file));
    for (ObjectShape shape : {ObjectShape::kBox, ObjectShape::kCylinder, ObjectShape::kSphere}) {
      SceneConfig scene;
      scene.object.shape = shape;
      Simulation& simulation = MakeSimulation(layout, scene);
      simulation.StepUntil(0.2);
      const GroundTruth truth = simulation.truth();
      EXPECT_NEAR(truth.object_height_above_table_m, 0.0, 1e-4) << layout_file << " " << ToString(shape);
      EXPECT_EQ(truth.finger_contacts + truth.thumb_contacts, 0) << "open hand must not touch the object";
    }
  }
}

TEST_F(ModelTest, StallEffortPinchesAtLeastFifteenNewtons) {
  // The default pinch posture (50 mm box, pad square to it): both motors at stall.
  SceneConfig scene;
  Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
  simulation.SetGripEffort(1.0);
  simulation.StepUntil(1.2);
  const GroundTruth truth = simulation.truth();
  EXPECT_GE(truth.object_squeeze_n, 15.0);
  // The motors are sized from the pad's and the thumb's lever arms in this posture, so the squeeze
  // is the configured stall pinch force up to the posture's drift while closing (measured < 2 %).
  const double stall = scene.hand.digit_motor.stall_pinch_force_n;
  EXPECT_NEAR(truth.object_squeeze_n, stall, 0.05 * stall);
  // 20 N on the 0.5 mm mesas of one row: the object stays on them, far from the holder shell.
  EXPECT_LT(truth.max_mesa_penetration_m, 0.1e-3);
  EXPECT_FALSE(truth.object_touches_holder_shell);
  EXPECT_GT(truth.sensed_share, 0.95);
}

TEST_F(ModelTest, TheJawFixtureStillPinchesAtItsStallForce) {
  SceneConfig scene;
  scene.hand.model = HandModel::kJaw;
  scene.hand.open_gap_m = 0.065;
  Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
  simulation.SetGripEffort(1.0);
  simulation.StepUntil(1.2);
  const GroundTruth truth = simulation.truth();
  EXPECT_NEAR(truth.object_squeeze_n, scene.hand.motor.stall_force_n,
              kForceTolN * scene.hand.motor.stall_force_n);
  EXPECT_LT(truth.max_mesa_penetration_m, 0.05e-3);
}

TEST_F(ModelTest, TheFingerClosesFromOpenToClosedInAboutASecondAtFullEffort) {
  // Hand high above the object, opened as wide as it goes; full effort closes the index from its
  // extension stop towards its flexion stop at the no-load speed.
  SceneConfig scene;
  scene.hand.initial_wrist_position_m = {0.0, 0.0, 0.35};
  scene.hand.open_gap_m = 0.12;
  Simulation& simulation = MakeSimulation(DefaultLayout(), scene);
  const mjModel* m = simulation.model();
  const int mcp = mj_name2id(m, mjOBJ_JOINT, "index_mcp");
  const int pip = mj_name2id(m, mjOBJ_JOINT, "index_pip");
  ASSERT_GE(mcp, 0);
  const double start = simulation.data()->qpos[m->jnt_qposadr[mcp]];
  simulation.SetGripEffort(0.5);
  simulation.StepUntil(0.2);
  // Half effort: half the no-load speed (back-EMF as damping; armature and linkage add < 2 %).
  const double speed = scene.hand.digit_motor.no_load_speed_rad_s;
  EXPECT_NEAR(simulation.data()->qvel[m->jnt_dofadr[mcp]], 0.5 * speed, 0.03 * speed);
  // The linkage: PIP flexes ratio x MCP.
  const double mcp_moved = simulation.data()->qpos[m->jnt_qposadr[mcp]] - m->qpos0[m->jnt_qposadr[mcp]];
  const double pip_moved = simulation.data()->qpos[m->jnt_qposadr[pip]] - m->qpos0[m->jnt_qposadr[pip]];
  EXPECT_NEAR(pip_moved, scene.hand.finger.pip_mcp_ratio * mcp_moved, 0.01 * std::abs(pip_moved));
  // Full effort from the wide pre-shape to the flexion stop: about a second.
  SceneConfig wide = scene;
  Simulation& full = MakeSimulation(DefaultLayout(), wide);
  full.SetGripEffort(1.0);
  const double stop = m->jnt_range[2 * mcp + 1] - 0.02;
  while (full.data()->qpos[m->jnt_qposadr[mcp]] < stop && full.time_s() < 3.0) full.Step();
  const double travel = stop - start;
  EXPECT_GT(travel, 1.0) << "open to closed spans most of the MCP range";
  EXPECT_GT(full.time_s(), 0.6);
  EXPECT_LT(full.time_s(), 1.3);
}

}  // namespace
}  // namespace graspbed::sim

// The object library and the shapes beyond primitives: every library object compiles with the
// library's mass and the inertia computed apart from MuJoCo; a centre-of-mass offset gives the
// gravity torque a hand computation gives; the compliance mapping holds; a user's mesh loads and a
// broken one is refused by name; each object gets the grasp its size and shape call for; an egg
// squeezed past its crush force is reported crushed; a soft object loads more units than a rigid one
// of the same size, the foam brick's condim 6 keeps it from rolling about the point contacts, and
// the marker tips against a tilted pad, not against an upright one.
#include <mujoco/mujoco.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "common/config_error.h"
#include "common/yaml_map.h"
#include "sensor/layout.h"
#include "sim/model_generator.h"
#include "sim/object_library.h"
#include "sim/object_shapes.h"
#include "sim/scene_config.h"
#include "sim/simulation.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "sim/sim_rig.h"
#include "tests/support/cli_runner.h"
#include "tests/support/temp_dir.h"
#include "tests/testbed/scenario_test_util.h"

namespace graspbed {
namespace {

using ::testing::HasSubstr;

// The model text carries each part's mass to 8 significant digits (Simulation then sets the body's
// total exactly).
constexpr double kMassRelTol = 5e-8;
constexpr double kCentreTolM = 1e-5;
// Principal moments: the analytic capsule and polygonal-frustum formulas against MuJoCo's.
constexpr double kInertiaRelTol = 0.01;
constexpr double kGravity = 9.81;

struct ModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
using ModelPtr = std::unique_ptr<mjModel, ModelDeleter>;

ModelPtr CompileScene(const sim::SceneConfig& scene) {
  const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  return ModelPtr(sim::CompileMjcf(sim::GenerateMjcf(layout, scene)));
}

TEST(ObjectModelTest, TheLibraryHasTheIssuesObjects) {
  const sim::ObjectLibrary& library = sim::ShippedObjectLibrary();
  for (const char* name : {"can", "bottle", "bottle_half", "mug", "marker", "card", "banana", "tennis_ball",
                           "apple", "egg", "plastic_cup", "foam_brick", "wine_glass"}) {
    const sim::LibraryObject* object = library.Find(name);
    ASSERT_NE(object, nullptr) << name;
    EXPECT_FALSE(object->source.empty()) << name;
  }
  EXPECT_GT(library.Find("egg")->object.crush_limit_n, 0.0);
  EXPECT_GT(library.Find("wine_glass")->object.crush_limit_n, 0.0);
  EXPECT_LE(library.Find("plastic_cup")->object.crush_limit_n, 5.0);
}

TEST(ObjectModelTest, EveryLibraryObjectCompilesWithTheLibrarysMassCentreAndInertia) {
  for (const sim::LibraryObject& entry : sim::ShippedObjectLibrary().objects()) {
    SCOPED_TRACE(entry.name);
    sim::SceneConfig scene;
    scene.object = entry.object;
    const ModelPtr model = CompileScene(scene);
    ASSERT_NE(model, nullptr);
    const int body = mj_name2id(model.get(), mjOBJ_BODY, "object");
    ASSERT_GE(body, 0);
    const sim::MassProperties expected = sim::ComputeMassProperties(sim::ObjectParts(entry.object));
    EXPECT_NEAR(expected.mass_kg, entry.object.mass_kg, kMassRelTol * entry.object.mass_kg);
    EXPECT_NEAR(model->body_mass[body], entry.object.mass_kg, kMassRelTol * entry.object.mass_kg);
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(model->body_ipos[3 * body + k], expected.centre_of_mass_m[k], kCentreTolM) << "axis " << k;
    std::vector<double> compiled(model->body_inertia + 3 * body, model->body_inertia + 3 * body + 3);
    std::sort(compiled.begin(), compiled.end());
    const Eigen::Vector3d principal = expected.PrincipalMomentsKgM2();
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(compiled[k], principal[k], kInertiaRelTol * principal[k]) << "principal moment " << k;
  }
}

// The mug's handle on +y: gravity's torque about the pinch axis (world x) through the body's axis,
// by hand. Ceramic volumes (sim/object_shapes.cc: 5 mm wall, 5 mm handle capsules), R = 40 mm,
// H = 82 mm, handle reach 117 - 80 = 37 mm:
//   wall   = pi (0.040^2 - 0.035^2) 0.082 + pi 0.035^2 0.005 = pi 3.6875e-5 m^3
//   handle = pi 0.005^2 (grip 0.041 + 2 arms x 0.037)       = pi 2.875e-6 m^3
//   handle share = 2.875 / 39.75 = 0.072327
//   handle centroid y: grip at 0.040 + 0.037 - 0.005 = 0.072, arms centred at (0.035 + 0.072) / 2 =
//   0.0535: (0.041 x 0.072 + 0.074 x 0.0535) / 0.115 = 0.060096 m
//   centre of mass y = 0.072327 x 0.060096 = 4.3466 mm; torque = 0.118 x 9.81 x 0.0043466 = 5.0315e-3 N m
TEST(ObjectModelTest, TheMugsHandleTwistsItAboutThePinchAxisByHandComputation) {
  constexpr double kExpectedCentreY = 0.0043466;
  constexpr double kExpectedTorqueNm = 0.118 * kGravity * kExpectedCentreY;
  sim::SceneConfig scene;
  scene.object = sim::ShippedObjectLibrary().Find("mug")->object;
  const ModelPtr model = CompileScene(scene);
  const int body = mj_name2id(model.get(), mjOBJ_BODY, "object");
  EXPECT_NEAR(model->body_ipos[3 * body + 1], kExpectedCentreY, 1e-6);
  std::unique_ptr<mjData, void (*)(mjData*)> data(mj_makeData(model.get()), mj_deleteData);
  mj_forward(model.get(), data.get());
  // The free joint's rotational dofs act about the body origin (the mug's axis), body axes = world
  // axes at rest: qfrc_bias there is minus gravity's torque about world x.
  const int dof = model->jnt_dofadr[model->body_jntadr[body]];
  const double torque_about_x = -data->qfrc_bias[dof + 3];
  EXPECT_NEAR(std::abs(torque_about_x), kExpectedTorqueNm, 0.01 * kExpectedTorqueNm);
  EXPECT_LT(torque_about_x, 0.0) << "weight on +y tips the top towards +y: negative about +x";
}

TEST(ObjectModelTest, APartFilledBottleHasItsCentreOfMassLower) {
  const sim::ObjectLibrary& library = sim::ShippedObjectLibrary();
  const auto centre_z = [](const sim::ObjectConfig& o) {
    return sim::ComputeMassProperties(sim::ObjectParts(o)).centre_of_mass_m.z();
  };
  EXPECT_LT(centre_z(library.Find("bottle_half")->object), centre_z(library.Find("bottle")->object) - 0.01);
}

// A ball on the table: one contact, whose penetration is its weight over the stated stiffness.
TEST(ObjectModelTest, AStatedStiffnessGivesThatPenetrationUnderTheWeight) {
  test_support::TempDir dir;
  const std::string file = dir.Write("ball.yaml", R"(
object: {name: tennis_ball, stiffness_n_m: 1000}
)");
  const sim::SceneConfig scene = sim::LoadSceneConfigFile(file);
  EXPECT_EQ(scene.object.solimp[0], sim::kStiffnessImpedance);
  const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  sim::Simulation simulation(layout, scene);
  simulation.StepUntil(1.5);
  ASSERT_FALSE(simulation.fault().occurred) << simulation.fault().cause_text();
  const double penetration = -simulation.truth().object_height_above_table_m;
  const double expected = 0.058 * kGravity / 1000.0;  // 0.57 mm
  EXPECT_NEAR(penetration, expected, 0.05 * expected);
}

TEST(ObjectModelTest, OverridesBesideTheNameWin) {
  test_support::TempDir dir;
  const sim::SceneConfig scene =
      sim::LoadSceneConfigFile(dir.Write("can.yaml", "object: {name: can, mass_kg: 0.2, friction: 0.3}\n"));
  EXPECT_EQ(scene.object.shape, sim::ObjectShape::kCylinder);
  EXPECT_DOUBLE_EQ(scene.object.mass_kg, 0.2);
  EXPECT_DOUBLE_EQ(scene.object.friction, 0.3);
  EXPECT_DOUBLE_EQ(scene.object.size_m[0], 0.066);
  // The stiffness is kept and re-derived for the new mass.
  EXPECT_NEAR(sim::StiffnessOfSolref(scene.object), 3.0e5, 1.0);
}

TEST(ObjectModelTest, AnUnknownNameListsTheKnownOnes) {
  test_support::TempDir dir;
  const std::string file = dir.Write("bad.yaml", "object:\n  name: teapot\n");
  try {
    sim::LoadSceneConfigFile(file);
    FAIL() << "loaded";
  } catch (const common::ConfigError& error) {
    EXPECT_THAT(error.what(), HasSubstr("bad.yaml:2"));
    EXPECT_THAT(error.what(), HasSubstr("object.name = teapot"));
    EXPECT_THAT(error.what(), HasSubstr("unknown object"));
    EXPECT_THAT(error.what(), HasSubstr("can, bottle"));
  }
}

// `--set object.name=apple` on scenarios/default.yaml, whose object is a box: the name comes with the
// file's shape, so the object is a box with the apple's other keys. It loads (a key beside a name is
// allowed) and says so; a name alone, or with keys of its own shape, says nothing.
TEST(ObjectModelTest, ANameBesideAnotherShapeIsWarnedAbout) {
  test_support::TempDir dir;
  const std::string hybrid = dir.Write("hybrid.yaml", "object: {shape: box, size_m: [0.05, 0.05, 0.08], name: apple}\n");
  testing::internal::CaptureStderr();
  const sim::SceneConfig scene = sim::LoadSceneConfigFile(hybrid);
  const std::string warned = testing::internal::GetCapturedStderr();
  EXPECT_EQ(scene.object.shape, sim::ObjectShape::kBox);
  EXPECT_THAT(warned, HasSubstr("hybrid.yaml"));
  EXPECT_THAT(warned, HasSubstr("object.name = apple beside object.shape = box"));
  EXPECT_THAT(warned, HasSubstr("the library's apple is a sphere"));
  for (const char* quiet : {"object: {name: apple}\n", "object: {name: can, size_m: [0.03, 0, 0.101]}\n",
                            "object: {name: apple, shape: sphere}\n"}) {
    const std::string file = dir.Write("quiet.yaml", quiet);
    testing::internal::CaptureStderr();
    sim::LoadSceneConfigFile(file);
    EXPECT_EQ(testing::internal::GetCapturedStderr(), "") << quiet;
  }
}

TEST(ObjectModelTest, TooStiffForTheStepIsRefusedWithTheMostItTakes) {
  test_support::TempDir dir;
  const std::string file = dir.Write("stiff.yaml", "object: {name: marker, stiffness_n_m: 1e8}\n");
  try {
    sim::LoadSceneConfigFile(file);
    FAIL() << "loaded";
  } catch (const common::ConfigError& error) {
    EXPECT_THAT(error.what(), HasSubstr("object.stiffness_n_m"));
    EXPECT_THAT(error.what(), HasSubstr("too stiff"));
    EXPECT_THAT(error.what(), HasSubstr("at most"));
  }
}

// Binary STL of the given triangles.
void WriteStl(const std::string& path, const std::vector<std::array<Eigen::Vector3f, 3>>& triangles) {
  std::ofstream out(path, std::ios::binary);
  char header[80] = {0};
  out.write(header, 80);
  const uint32_t count = static_cast<uint32_t>(triangles.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  for (const auto& t : triangles) {
    const float normal[3] = {0, 0, 0};
    out.write(reinterpret_cast<const char*>(normal), 12);
    for (const Eigen::Vector3f& v : t) out.write(reinterpret_cast<const char*>(v.data()), 12);
    const uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
}

// A closed box [0, x] x [0, y] x [0, z] as 12 outward-facing triangles.
std::vector<std::array<Eigen::Vector3f, 3>> BoxTriangles(Eigen::Vector3f lo, Eigen::Vector3f hi) {
  std::vector<std::array<Eigen::Vector3f, 3>> t;
  const auto corner = [&](int i) {
    return Eigen::Vector3f(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  };
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    t.push_back({corner(f[0]), corner(f[1]), corner(f[2])});
    t.push_back({corner(f[0]), corner(f[2]), corner(f[3])});
  }
  return t;
}

TEST(ObjectMeshModelTest, AnStlInMillimetresLoadsWithItsSizeAndMass) {
  test_support::TempDir dir;
  WriteStl(dir.Path("cube.stl"), BoxTriangles({0, 0, 0}, {30, 40, 50}));
  const std::string file = dir.Write("mesh.yaml", "object: {mesh: cube.stl, scale: 0.001, mass_kg: 0.2}\n");
  const sim::SceneConfig scene = sim::LoadSceneConfigFile(file);
  EXPECT_EQ(scene.object.shape, sim::ObjectShape::kMesh);
  EXPECT_NEAR(scene.object.size_m[0], 0.030, 1e-9);
  EXPECT_NEAR(scene.object.size_m[2], 0.050, 1e-9);
  const ModelPtr model = CompileScene(scene);
  const int body = mj_name2id(model.get(), mjOBJ_BODY, "object");
  EXPECT_NEAR(model->body_mass[body], 0.2, 1e-9);
  // A box is its own hull: no warning.
  EXPECT_EQ(sim::MeshHullWarning(scene.object.mesh, 0.001), "");
}

TEST(ObjectMeshModelTest, AConcaveMeshWarnsWhatItsHullAdds) {
  test_support::TempDir dir;
  // Two 10 mm cubes touching only along an edge region: an L whose hull is much larger.
  std::vector<std::array<Eigen::Vector3f, 3>> l_shape = BoxTriangles({0, 0, 0}, {30, 10, 10});
  for (const auto& t : BoxTriangles({0, 0, 10}, {10, 10, 40})) l_shape.push_back(t);
  WriteStl(dir.Path("l.stl"), l_shape);
  const std::string warning = sim::MeshHullWarning(dir.Path("l.stl"), 0.001);
  EXPECT_THAT(warning, HasSubstr("l.stl"));
  EXPECT_THAT(warning, HasSubstr("convex hull"));
  EXPECT_THAT(warning, HasSubstr("mesh 6 cm^3"));
}

TEST(ObjectMeshModelTest, ABrokenOrMissingFileIsRefusedByName) {
  test_support::TempDir dir;
  {
    WriteStl(dir.Path("cut.stl"), BoxTriangles({0, 0, 0}, {30, 40, 50}));
    std::ifstream in(dir.Path("cut.stl"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir.Path("cut.stl"), std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() - 20);
  }
  const auto error_of = [&](const std::string& yaml) -> std::string {
    try {
      sim::LoadSceneConfigFile(dir.Write("m.yaml", yaml));
    } catch (const common::ConfigError& error) {
      return error.what();
    }
    return "loaded";
  };
  const std::string cut = error_of("object: {mesh: cut.stl, scale: 0.001}\n");
  EXPECT_THAT(cut, HasSubstr("object.mesh = cut.stl"));
  EXPECT_THAT(cut, HasSubstr("truncated"));
  const std::string missing = error_of("object: {mesh: nowhere.stl}\n");
  EXPECT_THAT(missing, HasSubstr("nowhere.stl"));
  EXPECT_THAT(missing, HasSubstr("cannot open"));
  WriteStl(dir.Path("cube.stl"), BoxTriangles({0, 0, 0}, {30, 40, 50}));
  const std::string shaped = error_of("object: {shape: box, mesh: cube.stl, scale: 0.001}\n");
  EXPECT_THAT(shaped, HasSubstr("object.shape = box"));
  EXPECT_THAT(shaped, HasSubstr("has shape mesh"));
  const std::string format = error_of("object: {mesh: part.msh}\n");
  EXPECT_THAT(format, HasSubstr("part.msh"));
  EXPECT_THAT(format, HasSubstr("unsupported format"));
}

// The egg between the prosthetic hand's digits, squeezed by the open-loop controller with motors
// strong enough to pass its 30 N crush force.
// The grasp a scenario gets when it names a library object and no grasp: the prosthetic hand wraps
// the can, the bottles and the mug by their 65-80 mm bodies and pinches everything else (the marker
// and the card are small and thin, the balls and fruit round, the cup, glass and banana shapes the
// wrap does not take). Each default builds a hand that meets the object (PlaceHand does not refuse it).
TEST(ObjectGraspTest, EachLibraryObjectGetsTheGraspItsSizeAndShapeCallFor) {
  const std::map<std::string, sim::GraspType> expected = {
      {"can", sim::GraspType::kWrap},           {"bottle", sim::GraspType::kWrap},
      {"bottle_half", sim::GraspType::kWrap},   {"mug", sim::GraspType::kWrap},
      {"marker", sim::GraspType::kPinch},       {"card", sim::GraspType::kPinch},
      {"banana", sim::GraspType::kPinch},       {"tennis_ball", sim::GraspType::kPinch},
      {"apple", sim::GraspType::kPinch},        {"egg", sim::GraspType::kPinch},
      {"plastic_cup", sim::GraspType::kPinch},  {"foam_brick", sim::GraspType::kPinch},
      {"wine_glass", sim::GraspType::kPinch},
  };
  const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  const sim::ObjectLibrary& library = sim::ShippedObjectLibrary();
  ASSERT_EQ(library.objects().size(), expected.size()) << "a new object needs its expected grasp here";
  for (const sim::LibraryObject& entry : library.objects()) {
    SCOPED_TRACE(entry.name);
    ASSERT_TRUE(expected.count(entry.name));
    const sim::SceneConfig scene =
        sim::LoadSceneConfig(common::YamlMap::LoadString("object: {name: " + entry.name + "}\n", "<test>"));
    EXPECT_EQ(sim::ToString(scene.hand.grasp), std::string(sim::ToString(expected.at(entry.name))));
    EXPECT_EQ(sim::DefaultGrasp(entry.object, sim::HandConfig{}), expected.at(entry.name));
    EXPECT_NO_THROW(sim::PlaceHand(layout, scene));
    EXPECT_NE(CompileScene(scene), nullptr);
  }
}

TEST(ObjectGraspTest, TheScenariosOwnGraspWins) {
  const auto load = [](const std::string& yaml) {
    return sim::LoadSceneConfig(common::YamlMap::LoadString(yaml, "<test>")).hand.grasp;
  };
  EXPECT_EQ(load("object: {name: can}\nhand: {grasp: pinch}\n"), sim::GraspType::kPinch);
  EXPECT_EQ(load("object: {name: bottle}\nhand: {grasp: pinch}\n"), sim::GraspType::kPinch);
  // An aperture is a pinch's: stating one keeps the pinch.
  EXPECT_EQ(load("object: {name: can}\nhand: {open_gap_m: 0.09}\n"), sim::GraspType::kPinch);
  // The jaw fixture only pinches.
  EXPECT_EQ(load("object: {name: can}\nhand: {model: jaw}\n"), sim::GraspType::kPinch);
  // Overrides beside the name change the choice: a can made 30 mm across is pinched.
  EXPECT_EQ(load("object: {name: can, size_m: [0.03, 0, 0.101]}\n"), sim::GraspType::kPinch);
  // A primitive object without a name keeps the pinch the scene has always had.
  EXPECT_EQ(load("object: {shape: cylinder, size_m: [0.066, 0, 0.101]}\n"), sim::GraspType::kPinch);
}

// The wrap's diameter range is one the hand can wrap: a can at either end of it builds (the
// kinematics solve the wrap), and just outside it, or squatter than it is wide, it is pinched.
TEST(ObjectGraspTest, TheWrapRangeIsOneTheHandWraps) {
  const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  const auto load = [](double diameter_m, double height_m) {
    std::ostringstream yaml;
    yaml << "object: {name: can, size_m: [" << diameter_m << ", 0, " << height_m << "]}\n";
    return sim::LoadSceneConfig(common::YamlMap::LoadString(yaml.str(), "<test>"));
  };
  for (const double diameter : {sim::kMinDefaultWrapDiameterM, sim::kMaxDefaultWrapDiameterM}) {
    SCOPED_TRACE(diameter);
    const sim::SceneConfig scene = load(diameter, 0.12);
    EXPECT_EQ(scene.hand.grasp, sim::GraspType::kWrap);
    EXPECT_NO_THROW(sim::PlaceHand(layout, scene));
  }
  EXPECT_EQ(load(sim::kMinDefaultWrapDiameterM - 0.001, 0.12).hand.grasp, sim::GraspType::kPinch);
  EXPECT_EQ(load(sim::kMaxDefaultWrapDiameterM + 0.001, 0.12).hand.grasp, sim::GraspType::kPinch);
  EXPECT_EQ(load(0.066, 0.05).hand.grasp, sim::GraspType::kPinch) << "a squat tin";
}

// A run's config.yaml states the grasp the object got, so reading it back gives the same scene even
// were the default to change.
TEST(ObjectGraspTest, TheChosenGraspIsWrittenOutAndReadsBack) {
  const sim::SceneConfig scene =
      sim::LoadSceneConfig(common::YamlMap::LoadString("object: {name: bottle}\n", "<test>"));
  ASSERT_EQ(scene.hand.grasp, sim::GraspType::kWrap);
  YAML::Emitter out;
  out << YAML::BeginMap;
  sim::EmitSceneConfig(scene, out);
  out << YAML::EndMap;
  const std::string text = out.c_str();
  EXPECT_THAT(text, HasSubstr("grasp: wrap"));
  const sim::SceneConfig again = sim::LoadSceneConfig(common::YamlMap::LoadString(text, "<config.yaml>"));
  EXPECT_EQ(again.hand.grasp, sim::GraspType::kWrap);
  EXPECT_EQ(again.ObjectWidthM(), scene.ObjectWidthM());
  EXPECT_DOUBLE_EQ(scene.ObjectWidthM(), 0.065) << "the bottle's body, not its 28 mm neck";
}

// The table `graspbed objects` prints reads a cylinder as diameter x height, not "66 x 0 x 101".
TEST(ObjectGraspTest, TheTableReadsSizesAsTheShapeHasThem) {
  const std::vector<sim::ObjectSummary> rows = sim::SummarizeObjects(sim::ShippedObjectLibrary());
  const auto row = [&rows](const std::string& name) {
    for (const sim::ObjectSummary& r : rows)
      if (r.name == name) return r;
    ADD_FAILURE() << name;
    return sim::ObjectSummary{};
  };
  EXPECT_EQ(sim::SizeTextMm(row("can")), "dia 66 x 101");
  EXPECT_EQ(sim::SizeTextMm(row("tennis_ball")), "dia 65");
  EXPECT_EQ(sim::SizeTextMm(row("card")), "1 x 86 x 54");
  EXPECT_EQ(sim::SizeTextMm(row("bottle")), "dia 65 x 220, neck 28");
  const std::string markdown = sim::ObjectTableMarkdown(rows);
  EXPECT_THAT(markdown, HasSubstr("| `can` | cylinder | dia 66 x 101 |"));
  EXPECT_THAT(markdown, ::testing::Not(HasSubstr(" x 0 x ")));
  EXPECT_THAT(markdown, HasSubstr("| wrap |"));
}

// `graspbed objects` through the real executable: --json gives each object's default grasp,
// --markdown the table as docs/scenarios.md carries it.
TEST(ObjectGraspTest, TheObjectsCommandListsEachObjectsGrasp) {
  if (test_support::CliBinary().empty()) GTEST_FAIL() << "GRASPBED_BINARY not set (run through ctest)";
  const test_support::CliResult json = test_support::RunCli("objects --json");
  ASSERT_EQ(json.exit_code, 0) << json.err;
  const nlohmann::json rows = nlohmann::json::parse(json.out);
  ASSERT_EQ(rows.size(), sim::ShippedObjectLibrary().objects().size());
  for (const nlohmann::json& row : rows) {
    SCOPED_TRACE(row["name"].get<std::string>());
    const sim::LibraryObject* entry = sim::ShippedObjectLibrary().Find(row["name"]);
    ASSERT_NE(entry, nullptr);
    EXPECT_EQ(row["default_grasp"], sim::ToString(sim::DefaultGrasp(entry->object, sim::HandConfig{})));
  }
  const test_support::CliResult markdown = test_support::RunCli("objects --markdown");
  ASSERT_EQ(markdown.exit_code, 0) << markdown.err;
  EXPECT_EQ(markdown.out, sim::ObjectTableMarkdown(sim::SummarizeObjects(sim::ShippedObjectLibrary())));
}

std::string EggScenario(double close_effort) {
  return "duration_s: 0.6\n"
         "object: {name: egg}\n"
         "hand: {digit_motor: {stall_pinch_force_n: 80}}\n"
         "controller: {name: open_loop, params: {close_effort: " +
         std::to_string(close_effort) +
         "}}\n"
         "script:\n"
         "  - {at_s: 0.05, action: close}\n";
}

TEST(ObjectScenarioTest, AnEggSqueezedPastItsCrushForceIsCrushedAndBelowItIsNot) {
  test_support::TempDir dir;
  const auto hard = testbed::test_support::RunScenarioText(dir, "hard", EggScenario(0.8));
  EXPECT_TRUE(hard.result.metrics.crushed) << "peak grip " << hard.result.metrics.peak_grip_n << " N";
  EXPECT_GT(hard.result.metrics.peak_grip_n, 30.0);
  const auto gentle = testbed::test_support::RunScenarioText(dir, "gentle", EggScenario(0.2));
  EXPECT_FALSE(gentle.result.metrics.crushed) << "peak grip " << gentle.result.metrics.peak_grip_n << " N";
  EXPECT_GT(gentle.result.metrics.peak_grip_n, 5.0) << "it was held";
}

// The foam brick and a rigid brick of the same size, squeezed alike (about 4 N; at 10 N the thumb
// pushes the foam brick down into the table and only the pad's tip row meets it): the pad sinks into
// the foam and more of its units bear.
std::string BrickScenario(const std::string& stiffness) {
  return "duration_s: 0.6\n"
         "object: {name: foam_brick, stiffness_n_m: " +
         stiffness +
         "}\n"
         "controller: {name: open_loop, params: {close_effort: 0.2}}\n"
         "script:\n"
         "  - {at_s: 0.05, action: close}\n";
}

TEST(ObjectScenarioTest, ASoftObjectLoadsMoreUnitsThanARigidOneAtTheSameGrip) {
  test_support::TempDir dir;
  const auto soft = testbed::test_support::RunScenarioText(dir, "soft", BrickScenario("500"));
  const auto rigid = testbed::test_support::RunScenarioText(dir, "rigid", BrickScenario("5e5"));
  const auto loaded_units = [](const testbed::test_support::Signals& s) {
    int count = 0;
    for (int unit = 0; unit < 20; ++unit) {
      if (s.AtTime("fn_true_n_" + std::to_string(unit), 0.55) > 0.05) ++count;
    }
    return count;
  };
  const int soft_units = loaded_units(soft.signals);
  const int rigid_units = loaded_units(rigid.signals);
  EXPECT_GT(soft_units, rigid_units) << "soft " << soft_units << ", rigid " << rigid_units;
  EXPECT_GT(rigid_units, 0);
}

// The foam brick held at a constant 1 N through a 40 mm lift at condim 3 (point contacts, no spin
// or rolling friction): with friction 1000 times harder than its 500 N/m contacts (physics.impratio
// 1000, every object's until 2026-11-28) the friction locks in the tangential motion of the pad
// sinking into it, and the brick rolls about the two contacts while the lift accelerates and brakes
// (its finger-side contact slides mm); with impratio auto (10 for it) it stays put.
std::string LiftedBrickScenario(const std::string& physics) {
  return "duration_s: 2.0\n"
         "object: {name: foam_brick, condim: 3}\n" +
         physics +
         "sensor: {profile: ideal}\n"
         "controller: {name: constant_grip, params: {grip_n: 1.0}}\n"
         "script:\n"
         "  - {at_s: 0.15, action: close}\n"
         "  - {at_s: 0.8, action: lift, height_m: 0.04, duration_s: 0.8}\n";
}

TEST(ObjectScenarioTest, TheFoamBrickRollsAboutPointContactsOnlyUnderFrictionHarderThanItsFlesh) {
  test_support::TempDir dir;
  const auto hard = testbed::test_support::RunScenarioText(dir, "hard", LiftedBrickScenario("physics: {impratio: 1000}\n"));
  const auto automatic = testbed::test_support::RunScenarioText(dir, "auto", LiftedBrickScenario(""));
  std::printf("[ measure ] foam brick at 1 N, condim 3: slip %.2f mm at impratio 1000, %.2f mm at auto\n",
              hard.result.metrics.max_slip_mm, automatic.result.metrics.max_slip_mm);
  EXPECT_FALSE(automatic.result.metrics.dropped);
  EXPECT_FALSE(automatic.result.metrics.physics_fault);
  EXPECT_LT(automatic.result.metrics.max_slip_mm, 0.5);  // micro-slip at most
  EXPECT_GT(hard.result.metrics.max_slip_mm, 3.0);       // the scenario's own limit
}

// The finger's contacts with the object at one instant: the sum of their tangential forces' magnitudes
// and the magnitude of their sum (world frame) [N], and the largest share of its friction limit one uses.
struct PadFriction {
  double sum_of_magnitudes_n = 0.0;
  double magnitude_of_sum_n = 0.0;
  double max_utilisation = 0.0;
  int contacts = 0;
};

PadFriction FingerFrictionOnTheObject(const mjModel* m, const mjData* d) {
  const int object = mj_name2id(m, mjOBJ_BODY, "object");
  PadFriction f;
  double sum[3] = {0.0, 0.0, 0.0};
  for (int c = 0; c < d->ncon; ++c) {
    const mjContact& contact = d->contact[c];
    const bool first = m->geom_bodyid[contact.geom1] == object;
    const int other = first ? contact.geom2 : contact.geom1;
    if (!first && m->geom_bodyid[contact.geom2] != object) continue;
    const char* name = mj_id2name(m, mjOBJ_GEOM, other);
    if (name == nullptr || std::strncmp(name, "unit_", 5) != 0) continue;  // the pad's mesas only
    double local[6];
    mj_contactForce(m, d, c, local);
    double world[3];
    for (int k = 0; k < 3; ++k) world[k] = local[1] * contact.frame[3 + k] + local[2] * contact.frame[6 + k];
    const double tangential = std::hypot(local[1], local[2]);
    f.sum_of_magnitudes_n += tangential;
    for (int k = 0; k < 3; ++k) sum[k] += world[k];
    if (local[0] > 0.0) f.max_utilisation = std::max(f.max_utilisation, tangential / (contact.friction[0] * local[0]));
    ++f.contacts;
  }
  f.magnitude_of_sum_n = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
  return f;
}

// The apple (180 g, 5e4 N/m) pinched at a constant 8 N, sunk 0.1 to 0.4 mm into six mesas whose
// normals differ by up to 12 degrees: with friction 1000 times harder than its contacts
// (physics.impratio 1000, every object's until 2026-11-28) the friction locks in the tangential
// motion of its sinking, so before the lift the mesas pull against one another near their friction
// limits and what they have left does not carry the weight (a gross slip as the lift starts, at every
// grip). With impratio auto (20 for it) they share the weight: docs/simulation.md, "Friction on a
// sunk pad".
TEST(ObjectScenarioTest, TheApplesMesasSpendTheirFrictionOnEachOtherOnlyUnderFrictionHarderThanItsFlesh) {
  const auto run = [](const std::string& physics) {
    const testbed::ScenarioConfig config = testbed::LoadScenarioFromString(
        "duration_s: 2.0\nobject: {name: apple}\n" + physics +
            "sensor: {profile: ideal}\ncontroller: {name: constant_grip, params: {grip_n: 8.0}}\n"
            "script:\n  - {at_s: 0.15, action: close}\n  - {at_s: 0.8, action: lift, height_m: 0.05, duration_s: 0.8}\n",
        "apple.yaml");
    testbed::RunOptions options;
    options.write_plots = false;
    PadFriction before_lift;
    options.instants_s = {0.79};
    options.at_instant = [&](double, sim::SimRig& rig) {
      before_lift = FingerFrictionOnTheObject(rig.simulation().model(), rig.simulation().data());
    };
    const testbed::RunResult result = testbed::RunScenario(config, options);
    return std::pair{before_lift, result};
  };
  const auto [hard, hard_run] = run("physics: {impratio: 1000}\n");
  const auto [soft, soft_run] = run("");
  for (const auto& [label, f, r] : {std::tuple{"impratio 1000", hard, &hard_run}, {"impratio auto", soft, &soft_run}}) {
    std::printf("[ measure ] apple at 8 N, %s, before the lift: mesas' |ft| summed %.2f N, their sum %.2f N, "
                "the most used %.2f of its friction limit (%d mesas); gross slips %d, slip %.2f mm\n",
                label, f.sum_of_magnitudes_n, f.magnitude_of_sum_n, f.max_utilisation, f.contacts, r->metrics.gross.events,
                r->metrics.max_slip_mm);
  }
  ASSERT_GE(hard.contacts, 4);
  ASSERT_GE(soft.contacts, 4);
  EXPECT_GT(hard.sum_of_magnitudes_n, 3.0 * hard.magnitude_of_sum_n);  // mostly internal
  EXPECT_GT(hard_run.metrics.gross.events, 0);
  EXPECT_LT(soft.sum_of_magnitudes_n, 1.5 * soft.magnitude_of_sum_n);  // mostly the weight's share
  EXPECT_EQ(soft_run.metrics.gross.events, 0);
  EXPECT_FALSE(soft_run.metrics.dropped);
}

// The marker (18 mm, 15.8 g, standing) pinched at a constant 1 N and lifted: met by a pad tilted 17
// degrees (the centred pinch) it tips against the pad as the hand closes and slides mm; met by the
// upright pad (hand.pinch_square_pad, as pick_marker has it) it does not.
std::string MarkerScenario(bool square_pad) {
  return std::string("duration_s: 1.6\n"
                     "object: {name: marker}\n"
                     "hand: {pinch_square_pad: ") +
         (square_pad ? "true" : "false") +
         "}\n"
         "sensor: {profile: ideal}\n"
         "controller: {name: constant_grip, params: {grip_n: 1.0}}\n"
         "script:\n"
         "  - {at_s: 0.15, action: close}\n"
         "  - {at_s: 0.8, action: lift, height_m: 0.06, duration_s: 0.8}\n";
}

// The tilted pad tips the marker while the digits close: acquisition, which the metrics report as
// acquisition_shift_mm apart from the held slip.
TEST(ObjectScenarioTest, TheMarkerTipsAgainstATiltedPadAndNotAgainstAnUprightOne) {
  test_support::TempDir dir;
  const auto tilted = testbed::test_support::RunScenarioText(dir, "centred", MarkerScenario(false));
  const auto upright = testbed::test_support::RunScenarioText(dir, "square", MarkerScenario(true));
  const testbed::Metrics& t = tilted.result.metrics;
  const testbed::Metrics& u = upright.result.metrics;
  std::printf("[ measure ] marker at 1 N: centred (pad tilted) acquisition shift %.2f mm, slip %.2f mm; square "
              "pad %.2f mm, %.2f mm\n",
              t.acquisition_shift_mm, t.max_slip_mm, u.acquisition_shift_mm, u.max_slip_mm);
  EXPECT_FALSE(u.dropped);
  EXPECT_LT(u.max_slip_mm, 1.0);
  EXPECT_LT(u.acquisition_shift_mm, 2.0);
  EXPECT_GT(t.acquisition_shift_mm, 5.0);
}

}  // namespace
}  // namespace graspbed

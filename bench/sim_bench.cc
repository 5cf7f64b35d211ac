// Cost of the simulated pipeline against bare physics (prosthetic hand, and the jaw fixture that was
// the default hand before it), and the force coverage of the fingertip.
//   BM_PhysicsOnly:   Simulation::Step (mj_step + the NaN/warning check) on the default scene, the
//                     default box held in a 10 N pinch (effort 0.5 of a 20 N stall).
//   BM_FullPipeline:  the same scene through SimRig::Step: physics, contact mapping + strain model at
//                     1 kHz, readout + inversion + grip_slip controller (holding 9.5 N) + actuator at 1 kHz.
// After the Google Benchmark runs, main() times both again, interleaved in rounds of one simulated
// second so machine load hits both alike, and prints the ratio (design budget <= 1.15) and the force
// coverage (sensed share of the finger's contact force) for a 10 N pinch of each object shape, and the
// real-time factor of each everyday object's shipped scenario.
// Run: build/bench/sim_bench   (docs/simulation.md)
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <memory>
#include <vector>

#include "common/data_dir.h"
#include "common/process.h"
#include "controller/grasp_controller.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "sim/physics_checks.h"
#include "sim/sim_rig.h"
#include "sim/simulation.h"
#include "sim/step_profile.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"
#include "testbed/suite.h"

namespace graspbed::sim {
namespace {

constexpr double kCloseEffort = 0.5;  // 10 N pinch at the default 20 N stall force
constexpr double kSettleS = 1.2;      // closed and at rest by then
constexpr double kHeldGripN = 9.5;    // grip_slip's hold target in the pipeline case [N]

const sensor::Layout& Layout() {
  static const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
  return layout;
}

std::unique_ptr<Simulation> HeldPhysics(const SceneConfig& scene = {}) {
  auto simulation = std::make_unique<Simulation>(Layout(), scene);
  simulation->SetGripEffort(kCloseEffort);
  simulation->StepUntil(kSettleS);
  return simulation;
}

std::unique_ptr<SimRig> HeldRig(const SceneConfig& scene = {}) {
  // The reference controller holding about the same pinch as the bare-physics case, so both step
  // the same contact configuration and the difference is the sensing and control path.
  SimRigConfig config;
  config.scene = scene;
  auto rig = std::make_unique<SimRig>(
      Layout(), sensor::PaperCalibration(Layout().unit_count()), config,
      controller::MakeController("grip_slip", {{"initial_grip_n", kHeldGripN}, {"min_grip_n", kHeldGripN}}));
  rig->controller().SetIntent(controller::GraspIntent::kClose);
  rig->AdvanceTo(kSettleS);
  return rig;
}

void BM_PhysicsOnly(benchmark::State& bench) {
  auto simulation = HeldPhysics();
  const double start = simulation->time_s();
  for (auto _ : bench) simulation->Step();
  bench.counters["sim_s_per_wall_s"] =
      benchmark::Counter(simulation->time_s() - start, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_PhysicsOnly)->Unit(benchmark::kMicrosecond);

void BM_FullPipeline(benchmark::State& bench) {
  auto rig = HeldRig();
  const double start = rig->time_s();
  for (auto _ : bench) rig->Step();
  bench.counters["sim_s_per_wall_s"] = benchmark::Counter(rig->time_s() - start, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FullPipeline)->Unit(benchmark::kMicrosecond);

// A scenario run's fixed cost before its first step: generate the MJCF, compile it, allocate mjData.
void BM_BuildSimulation(benchmark::State& bench) {
  for (auto _ : bench) {
    Simulation simulation(Layout(), SceneConfig{});
    benchmark::DoNotOptimize(simulation.time_s());
  }
}
BENCHMARK(BM_BuildSimulation)->Unit(benchmark::kMillisecond);

double WallSeconds(const std::chrono::steady_clock::time_point& start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void PrintRatio(const char* label, const SceneConfig& scene) {
  constexpr int kRounds = 6;
  constexpr double kRoundS = 1.0;
  auto physics = HeldPhysics(scene);
  auto rig = HeldRig(scene);
  double physics_wall = 0.0;
  double pipeline_wall = 0.0;
  double physics_cpu = 0.0;
  double pipeline_cpu = 0.0;
  for (int round = 0; round < kRounds; ++round) {
    auto start = std::chrono::steady_clock::now();
    double cpu_start = common::ThreadCpuSeconds();
    physics->StepUntil(physics->time_s() + kRoundS);
    physics_wall += WallSeconds(start);
    physics_cpu += common::ThreadCpuSeconds() - cpu_start;
    start = std::chrono::steady_clock::now();
    cpu_start = common::ThreadCpuSeconds();
    rig->AdvanceTo(rig->time_s() + kRoundS);
    pipeline_wall += WallSeconds(start);
    pipeline_cpu += common::ThreadCpuSeconds() - cpu_start;
  }
  const double simulated = kRounds * kRoundS;
  std::printf("\nPipeline cost, %s, 10 N pinch hold, %.0f s simulated each, interleaved:\n", label,
              simulated);
  std::printf("  bare physics   : %7.2f sim s per wall s, %7.2f per CPU s\n", simulated / physics_wall,
              simulated / physics_cpu);
  std::printf("  full pipeline  : %7.2f sim s per wall s, %7.2f per CPU s\n", simulated / pipeline_wall,
              simulated / pipeline_cpu);
  std::printf("  ratio full / bare: %.3f wall, %.3f CPU   (budget <= 1.15)\n", pipeline_wall / physics_wall,
              pipeline_cpu / physics_cpu);
  if (physics->fault().occurred || rig->simulation().fault().occurred)
    std::printf("  PHYSICS FAULT during timing\n");
}

void PrintCoverage() {
  std::printf("\nForce coverage, 10 N pinch (sensed = on mesas; share of all finger contact force):\n");
  std::printf("  %-28s %9s %9s %9s %8s %12s\n", "object", "finger N", "mesas N", "holder N", "share",
              "mesa pen um");
  struct Case {
    const char* name;
    ObjectShape shape;
    std::array<double, 3> size_m;
    double solref_timeconst_s;
  };
  const Case cases[] = {
      {"box 50 mm (flat face)", ObjectShape::kBox, {0.05, 0.05, 0.08}, 0.002},
      {"box 50 mm, soft (20 ms)", ObjectShape::kBox, {0.05, 0.05, 0.08}, 0.02},
      {"box 50 mm, very soft (80 ms)", ObjectShape::kBox, {0.05, 0.05, 0.08}, 0.08},
      {"cylinder d 50 mm", ObjectShape::kCylinder, {0.05, 0.0, 0.08}, 0.002},
      {"sphere d 50 mm", ObjectShape::kSphere, {0.05, 0.0, 0.0}, 0.002},
  };
  for (const Case& c : cases) {
    SceneConfig scene;
    scene.object.shape = c.shape;
    scene.object.size_m = c.size_m;
    scene.object.solref_timeconst_s = c.solref_timeconst_s;
    auto simulation = HeldPhysics(scene);
    const GroundTruth truth = simulation->truth();
    const double share =
        truth.finger_normal_force_n > 0.0 ? truth.sensed_normal_force_n / truth.finger_normal_force_n : 0.0;
    std::printf("  %-28s %9.3f %9.3f %9.3f %8.3f %12.1f%s\n", c.name, truth.finger_normal_force_n,
                truth.sensed_normal_force_n, truth.holder_normal_force_n, share,
                truth.max_mesa_penetration_m * 1e6, simulation->fault().occurred ? "  FAULT" : "");
  }
}

// One physics option against its speed and its fidelity: the held 10 N pinch profiled stage by
// stage (CPU time per step; the stages are wall-timed shares of it), and the contact model's
// promises measured with it: creep under half Coulomb's load (bound 5 um/s), pull / Coulomb at the
// onset of slip (bound 1 +- 0.05) and the sensed share of the pinch (bound 0.95).
struct PhysicsOption {
  const char* name;
  SceneConfig scene;
};

void PrintPhysicsOptions(const std::vector<PhysicsOption>& options) {
  std::printf(
      "\nPhysics options, held 10 N pinch of the default box (per step [us]; per simulated second [ms "
      "CPU]):\n");
  std::printf("  %-34s %6s %6s %6s %6s %6s %7s %5s %5s %5s %8s %7s %6s %5s\n", "option", "cpu", "coll",
              "make", "proj", "solve", "ms/s", "con", "rows", "iter", "creep", "slip/C", "cover", "fault");
  for (const PhysicsOption& option : options) {
    auto simulation = HeldPhysics(option.scene);
    const StepProfile p = ProfileSteps(*simulation, 1.0);
    const double share = p.step_cpu_us / p.step_us;  // wall-timed stages scaled to CPU time
    const CreepCheck creep = MeasureCreep(Layout(), option.scene);
    const double onset = MeasureSlipOnset(Layout(), option.scene).ratio;
    const PinchCheck pinch = MeasurePinch(Layout(), option.scene, 0.8, 0.2);
    const bool fault = simulation->fault().occurred || creep.fault || pinch.fault;
    std::printf("  %-34s %6.1f %6.1f %6.1f %6.1f %6.1f %7.1f %5.1f %5.1f %5.1f %6.2fum %7.4f %6.3f %5s\n",
                option.name, p.step_cpu_us, share * p.collision_us, share * p.make_constraint_us,
                share * p.project_constraint_us, share * p.solver_us,
                p.step_cpu_us * 1e-3 / option.scene.physics.timestep_s, p.contacts, p.constraint_rows,
                p.solver_iterations, creep.drift_m_s * 1e6, onset, pinch.sensed_share, fault ? "yes" : "-");
  }
}

// The physics settings before the speed work: 0.5 ms steps, 3 noslip iterations, impratio 10.
PhysicsConfig PhysicsBefore() {
  PhysicsConfig physics;
  physics.timestep_s = 0.0005;
  physics.noslip_iterations = 3;
  physics.impratio = 10.0;
  return physics;
}

std::vector<testbed::Override> PhysicsOverrides(const PhysicsConfig& physics) {
  std::vector<testbed::Override> overrides = {
      {"physics.timestep_s", std::to_string(physics.timestep_s)},
      {"physics.noslip_iterations", std::to_string(physics.noslip_iterations)},
      {"physics.contact_pairs", physics.contact_pairs ? "true" : "false"}};
  // NaN is auto (the scene's object decides), which a scenario says by leaving the key out.
  if (!std::isnan(physics.impratio)) overrides.push_back({"physics.impratio", std::to_string(physics.impratio)});
  return overrides;
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

// `graspbed run scenarios/default.yaml --no-plots` as a user starts it, whole process: the median of
// `repeats` runs' wall and CPU (user + system) time [s].
struct ProcessTime {
  double wall_s = 0.0;
  double cpu_s = 0.0;
  bool ok = false;
};
ProcessTime TimeProcess(const std::vector<std::string>& argv, int repeats) {
  std::vector<double> walls;
  std::vector<double> cpus;
  bool ok = true;
  for (int i = 0; i < repeats; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const int pid = common::SpawnProcess(argv, -1, "", "");
    int status = 0;
    rusage usage{};
    if (::wait4(pid, &status, 0, &usage) != pid) return {};
    walls.push_back(WallSeconds(start));
    cpus.push_back(static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
                   1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec));
    ok = ok && WIFEXITED(status) && WEXITSTATUS(status) == 0;
  }
  return {Median(walls), Median(cpus), ok};
}

// One physics setting of the scenario-speed table and what was measured for it.
struct SpeedRow {
  std::string label;
  PhysicsConfig physics;
  testbed::ScenarioConfig config;                  ///< the default scenario
  std::vector<testbed::ScenarioConfig> suite;      ///< the shipped suite
  std::vector<std::string> process_argv;            ///< `graspbed run` of the default scenario
  std::vector<double> walls, cpus;                  ///< in-process runs [s]
  std::vector<double> process_walls, process_cpus;  ///< whole-process runs [s]
  std::vector<double> runs_per_min[2];              ///< suite on 1 and 2 worker threads
  bool passed = true;
  bool process_ok = true;
  int suite_passed = 0;
};

// Real-time factors of the default scenario and the shipped suite's runs per minute, with the
// contact model's figures beside them, for each set of physics settings. The settings take turns
// round by round, so this VM's changes of speed (it runs at two speeds, about 1.45x apart, and
// switches between them within seconds) fall on all of them alike rather than on one row.
void PrintScenarioSpeedRows(std::vector<SpeedRow>& rows, const std::string& cli) {
  const std::string out = (std::filesystem::temp_directory_path() / "graspbed_sim_bench").string();
  const std::string default_yaml = common::DataPath("scenarios/default.yaml");
  for (SpeedRow& row : rows) {
    const std::vector<testbed::Override> overrides = PhysicsOverrides(row.physics);
    row.config = testbed::LoadScenario(default_yaml, overrides);
    row.suite =
        testbed::LoadScenarios(testbed::ListScenarioFiles(common::DataPath("scenarios")), overrides);
    row.process_argv = {cli, "run", default_yaml, "--no-plots", "--out", out + "/process"};
    for (const testbed::Override& o : overrides) {
      row.process_argv.push_back("--set");
      row.process_argv.push_back(o.key + "=" + o.value);
    }
  }
  constexpr int kRunRounds = 5;    // default scenario, in process and as a process
  constexpr int kSuiteRounds = 3;  // the suite on 1 and 2 threads
  for (int round = 0; round < kRunRounds; ++round) {
    for (SpeedRow& row : rows) {
      // In this process: the run as a suite or sweep makes it (outputs written, no plots).
      testbed::RunOptions options;
      options.out_dir = out + "/default";
      options.write_plots = false;
      const auto start = std::chrono::steady_clock::now();
      const double cpu_start = common::ThreadCpuSeconds();
      const testbed::RunResult result = testbed::RunScenario(row.config, options);
      row.cpus.push_back(common::ThreadCpuSeconds() - cpu_start);
      row.walls.push_back(WallSeconds(start));
      row.passed = row.passed && result.passed;
      // The whole process, as a user starts it.
      if (!cli.empty()) {
        const ProcessTime process = TimeProcess(row.process_argv, 1);
        row.process_walls.push_back(process.wall_s);
        row.process_cpus.push_back(process.cpu_s);
        row.process_ok = row.process_ok && process.ok;
      }
      if (round >= kSuiteRounds) continue;
      for (int jobs = 1; jobs <= 2; ++jobs) {
        testbed::SuiteOptions suite_options;
        suite_options.jobs = jobs;
        suite_options.out_dir = out + "/suite";
        suite_options.write_plots = false;
        const testbed::SuiteResult suite = testbed::RunSuite(row.suite, suite_options);
        row.runs_per_min[jobs - 1].push_back(60.0 * static_cast<double>(row.suite.size()) / suite.wall_s);
        row.suite_passed = suite.passed;
      }
    }
  }
  for (SpeedRow& row : rows) {
    SceneConfig scene;
    scene.physics = row.physics;
    const CreepCheck creep = MeasureCreep(Layout(), scene);
    const double onset = MeasureSlipOnset(Layout(), scene).ratio;
    const PinchCheck pinch = MeasurePinch(Layout(), scene, 0.8, 0.2);
    const double duration = row.config.duration_s;
    const auto factor = [duration](const std::vector<double>& seconds) {
      return seconds.empty() ? 0.0 : duration / Median(seconds);
    };
    std::printf("  %-44s %7.1fx %7.1fx %7.1fx %7.1fx %9.1f %9.1f %4d/%-3zu %6.2fum %7.4f %6.3f %s\n",
                row.label.c_str(), factor(row.walls), factor(row.cpus), factor(row.process_walls),
                factor(row.process_cpus), Median(row.runs_per_min[0]), Median(row.runs_per_min[1]),
                row.suite_passed, row.suite.size(), creep.drift_m_s * 1e6, onset, pinch.sensed_share,
                row.passed && (cli.empty() || row.process_ok) ? "" : " (default scenario FAILED)");
  }
}

void PrintScenarioSpeeds(const std::string& cli) {
  std::printf(
      "\nScenario speed: the default scenario's real-time factor (outputs written, no plots; median of 5) "
      "in\n"
      "this process and as a whole `graspbed run` process, wall and CPU; the shipped suite's runs per\n"
      "minute on 1 and 2 worker threads (median of 3) and how many passed; the rows take turns round by\n"
      "round; the contact model's figures beside them:\n");
  std::printf("  %-44s %8s %8s %8s %8s %9s %9s %8s %8s %7s %6s\n", "physics", "run wall", "run CPU",
              "proc wall", "proc CPU", "suite/min", "2 cores", "passed", "creep", "slip/C", "cover");
  PhysicsConfig half_ms;
  half_ms.timestep_s = 0.0005;
  PhysicsConfig broad_phase;
  broad_phase.contact_pairs = false;
  std::vector<SpeedRow> rows(4);
  rows[0].label = "before: 0.5 ms, noslip 3, impratio 10";
  rows[0].physics = PhysicsBefore();
  rows[1].label = "0.5 ms, noslip 0, impratio auto";
  rows[1].physics = half_ms;
  rows[2].label = "1 ms, ..., broad phase (contact_pairs false)";
  rows[2].physics = broad_phase;
  rows[3].label = "now: 1 ms, noslip 0, impratio auto, pairs";
  rows[3].physics = PhysicsConfig{};
  PrintScenarioSpeedRows(rows, cli);
  if (cli.empty()) return;
  // What a user waits for by default: the same run writing its PNG plots too.
  const std::string default_yaml = common::DataPath("scenarios/default.yaml");
  const double duration = testbed::LoadScenario(default_yaml).duration_s;
  const std::string out = (std::filesystem::temp_directory_path() / "graspbed_sim_bench").string();
  const ProcessTime with_plots = TimeProcess({cli, "run", default_yaml, "--out", out + "/plots"}, 5);
  std::printf(
      "  the default scenario as a whole process with its plots (median of 5): %.3f s wall, %.3f s CPU "
      "(%.1fx / %.1fx real time)%s\n",
      with_plots.wall_s, with_plots.cpu_s, duration / with_plots.wall_s, duration / with_plots.cpu_s,
      with_plots.ok ? "" : " (FAILED)");
}

// The real-time factor of each shipped scenario of an everyday object (a library object by name:
// meshes, compound bodies, soft contacts), run in this process with nothing written, the median of 3.
// Their target is 10x real time.
void PrintObjectScenarioSpeeds() {
  constexpr int kRounds = 3;
  std::printf("\nEveryday objects' scenarios (in process, nothing written, median of %d; target >= 10x):\n",
              kRounds);
  std::printf("  %-18s %-12s %9s %12s %12s\n", "scenario", "object", "sim [s]", "x real time", "x CPU time");
  for (const std::string& file : testbed::ListScenarioFiles(common::DataPath("scenarios"))) {
    const testbed::ScenarioConfig config = testbed::LoadScenario(file);
    if (config.scene.object.name.empty()) continue;
    std::vector<double> walls, cpus;
    for (int round = 0; round < kRounds; ++round) {
      const auto start = std::chrono::steady_clock::now();
      const double cpu_start = common::ThreadCpuSeconds();
      testbed::RunScenario(config, testbed::RunOptions{});
      cpus.push_back(common::ThreadCpuSeconds() - cpu_start);
      walls.push_back(WallSeconds(start));
    }
    std::printf("  %-18s %-12s %9.2f %12.1f %12.1f\n", config.name.c_str(), config.scene.object.name.c_str(),
                config.duration_s, config.duration_s / Median(walls), config.duration_s / Median(cpus));
  }
}

}  // namespace
}  // namespace graspbed::sim

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  {
    using graspbed::sim::SceneConfig;
    std::vector<graspbed::sim::PhysicsOption> options;
    auto add = [&](const char* name, auto edit) {
      SceneConfig scene;
      edit(scene);
      options.push_back({name, scene});
    };
    // The defaults, then one change at a time from them (docs/simulation.md, "Where a step's time goes").
    add("default: 1 ms, noslip 0, impratio auto", [](SceneConfig&) {});
    add("before: 0.5 ms, noslip 3, impratio 10",
        [](SceneConfig& s) { s.physics = graspbed::sim::PhysicsBefore(); });
    add("broad phase (contact_pairs false)", [](SceneConfig& s) { s.physics.contact_pairs = false; });
    add("timestep 0.5 ms", [](SceneConfig& s) { s.physics.timestep_s = 0.0005; });
    add("timestep 2 ms, object solref 4 ms", [](SceneConfig& s) {
      s.physics.timestep_s = 0.002;
      s.object.solref_timeconst_s = 0.004;
    });
    add("noslip 1, impratio 10", [](SceneConfig& s) {
      s.physics.noslip_iterations = 1;
      s.physics.impratio = 10;
    });
    add("noslip 0, impratio 10", [](SceneConfig& s) { s.physics.impratio = 10; });
    add("noslip 0, impratio 100", [](SceneConfig& s) { s.physics.impratio = 100; });
    add("noslip 0, impratio 300", [](SceneConfig& s) { s.physics.impratio = 300; });
    add("noslip 3 (impratio 1000)", [](SceneConfig& s) { s.physics.noslip_iterations = 3; });
    add("tolerance 1e-6", [](SceneConfig& s) { s.physics.tolerance = 1e-6; });
    add("iterations 10", [](SceneConfig& s) { s.physics.solver_iterations = 10; });
    add("pyramidal cones, impratio 1", [](SceneConfig& s) {
      s.physics.elliptic_cones = false;
      s.physics.impratio = 1;
    });
    add("pyramidal cones, impratio 10", [](SceneConfig& s) {
      s.physics.elliptic_cones = false;
      s.physics.impratio = 10;
    });
    add("solimp 0.99 0.9999 (stiffer)", [](SceneConfig& s) {
      s.object.solimp[0] = 0.99;
      s.object.solimp[1] = 0.9999;
    });
    graspbed::sim::PrintPhysicsOptions(options);
  }
  graspbed::sim::PrintRatio("prosthetic hand (default scene)", graspbed::sim::SceneConfig{});
  // The slide-joint jaw fixture: the default hand before the prosthetic one, for comparison.
  graspbed::sim::SceneConfig jaw;
  jaw.hand.model = graspbed::sim::HandModel::kJaw;
  jaw.hand.open_gap_m = 0.065;
  graspbed::sim::PrintRatio("jaw fixture (the previous default hand)", jaw);
  graspbed::sim::PrintCoverage();
  graspbed::sim::PrintObjectScenarioSpeeds();
#ifdef GRASPBED_CLI
  graspbed::sim::PrintScenarioSpeeds(GRASPBED_CLI);
#else
  graspbed::sim::PrintScenarioSpeeds("");
#endif
  return 0;
}

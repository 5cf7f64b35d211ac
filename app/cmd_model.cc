// `graspbed model`: prints (or writes) the MJCF scene generated from a layout and a scene file.
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "app/command_registry.h"
#include "sensor/layout.h"
#include "sim/model_generator.h"
#include "sim/scene_config.h"
#include "sim/simulation.h"

namespace graspbed::app {
namespace {

struct ModelOptions {
  std::string layout_path;
  std::string scene_path;
  std::string output_path;
  double check_s = 0.0;
  bool kinematics = false;
};

void RunModel(const ModelOptions& options) {
  const sensor::Layout layout =
      sensor::LoadLayout(options.layout_path.empty() ? sensor::DefaultLayoutPath() : options.layout_path);
  const sim::SceneConfig scene =
      options.scene_path.empty() ? sim::SceneConfig{} : sim::LoadSceneConfigFile(options.scene_path);
  if (options.kinematics) {
    std::cout << sim::DescribeHand(layout, scene);
    return;
  }
  const std::string mjcf = sim::GenerateMjcf(layout, scene);
  if (options.check_s > 0.0) {
    // Load it in MuJoCo and let it settle; a warning or NaN fails the check.
    sim::Simulation simulation(layout, scene);
    simulation.StepUntil(options.check_s);
    if (simulation.fault().occurred) {
      std::cerr << "graspbed model: physics fault at t = " << simulation.fault().time_s
                << " s: " << simulation.fault().cause_text() << '\n';
      throw CLI::RuntimeError(kExitFailed);
    }
    std::cerr << "graspbed model: loaded and stepped " << options.check_s << " s without warnings ("
              << layout.unit_count() << " mesa geoms)\n";
  }
  if (options.output_path.empty()) {
    std::cout << mjcf;
    return;
  }
  // Write to a temporary file first so a failure never leaves a half-written model behind.
  const std::string temporary = options.output_path + ".tmp";
  {
    std::ofstream out(temporary, std::ios::binary);
    out << mjcf;
    if (!out) throw std::runtime_error("cannot write " + temporary);
  }
  if (std::rename(temporary.c_str(), options.output_path.c_str()) != 0) {
    throw std::runtime_error("cannot rename " + temporary + " to " + options.output_path);
  }
}

void AddModelCommand(CLI::App& root) {
  auto options = std::make_shared<ModelOptions>();
  CLI::App* command = root.add_subcommand(
      "model", "Print the MuJoCo scene (MJCF) generated from a sensor layout and a scene file");
  command->add_option("--layout", options->layout_path, "layout YAML (default: the shipped 20-unit layout)")
      ->check(CLI::ExistingFile);
  command->add_option("--scene", options->scene_path, "scene YAML: object, hand, physics (default: built-in)")
      ->check(CLI::ExistingFile);
  command->add_option("-o,--output", options->output_path, "write to this file instead of stdout");
  command
      ->add_option("--check", options->check_s,
                   "also load the model in MuJoCo and step it this many seconds; exit 1 on a warning/NaN")
      ->check(CLI::NonNegativeNumber);
  command->add_flag("--kinematics", options->kinematics,
                    "print the hand's design and its placement for the scene (joints, pre-shape, lever arms, "
                    "motors) instead of the MJCF");
  command->callback([options] { RunModel(*options); });
}

const bool kRegistered = RegisterCommands(&AddModelCommand);

}  // namespace
}  // namespace graspbed::app

#pragma once
/// Shared test helpers for sim/: the default layout and a fixture that owns the simulations of a
/// test and fails the test on any MuJoCo warning or NaN any of them recorded.

#include <gtest/gtest.h>

#include <memory>
#include <utility>
#include <vector>

#include "controller/grasp_controller.h"
#include "sensor/calibration.h"
#include "sensor/layout.h"
#include "sim/sim_rig.h"
#include "sim/simulation.h"

namespace graspbed::sim::test_support {

class MujocoTest : public ::testing::Test {
 protected:
  /// A simulation owned by the fixture (checked for faults in TearDown).
  Simulation& MakeSimulation(const sensor::Layout& layout, const SceneConfig& scene) {
    simulations_.push_back(std::make_unique<Simulation>(layout, scene));
    return *simulations_.back();
  }
  /// A rig with `controller_name` owned by the fixture (checked for faults in TearDown).
  SimRig& MakeRig(const SimRigConfig& config, const std::string& controller_name,
                  const controller::ControllerParams& params) {
    const sensor::Layout& layout = DefaultLayout();
    rigs_.push_back(std::make_unique<SimRig>(layout, sensor::PaperCalibration(layout.unit_count()), config,
                                             controller::MakeController(controller_name, params)));
    return *rigs_.back();
  }
  /// Tests that provoke faults on purpose take their simulation out of the check.
  void ExpectFault(const Simulation& simulation) { expected_faults_.push_back(&simulation); }

  void TearDown() override {
    auto check = [this](const Simulation& simulation) {
      for (const Simulation* expected : expected_faults_) {
        if (expected == &simulation) return;
      }
      EXPECT_FALSE(simulation.fault().occurred)
          << "MuJoCo fault at t = " << simulation.fault().time_s << " s: " << simulation.fault().cause_text();
    };
    for (const auto& simulation : simulations_) check(*simulation);
    for (const auto& rig : rigs_) check(rig->simulation());
  }

  static const sensor::Layout& DefaultLayout() {
    static const sensor::Layout layout = sensor::LoadLayout(sensor::DefaultLayoutPath());
    return layout;
  }

 private:
  std::vector<std::unique_ptr<Simulation>> simulations_;
  std::vector<std::unique_ptr<SimRig>> rigs_;
  std::vector<const Simulation*> expected_faults_;
};

}  // namespace graspbed::sim::test_support

#include "tests/testbed/scenario_test_util.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "testbed/scenario_config.h"

namespace graspbed::testbed::test_support {

// The scenario-machinery tests (actions, faults, metrics, expectations) run on the slide-joint jaw
// fixture: its pinch is symmetric and its closing slow and exact, so their timelines and figures
// test the machinery, not the hand. The prosthetic hand has its own tests (tests/sim) and the
// shipped scenarios.
std::string HeldBoxScenario(double duration_s, const std::string& extra_script, const std::string& extra) {
  return "duration_s: " + std::to_string(duration_s) + R"(
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {model: jaw, open_gap_m: 0.055}
controller: {name: open_loop}
script:
  - {at_s: 0.04, action: close}
  - {at_s: 0.15, action: lift, height_m: 0.05, duration_s: 0.2}
)" + extra_script +
         extra;
}

Signals::Signals(const std::string& csv_path) {
  std::ifstream stream(csv_path);
  if (!stream) {
    ADD_FAILURE() << "cannot read " << csv_path;
    return;
  }
  std::string line;
  std::getline(stream, line);
  std::stringstream header(line);
  std::string name;
  while (std::getline(header, name, ',')) header_.push_back(name);
  std::vector<std::vector<double>*> numeric(header_.size(), nullptr);
  std::vector<std::vector<std::string>*> text(header_.size(), nullptr);
  for (size_t c = 0; c < header_.size(); ++c) {
    if (header_[c] == "intent" || header_[c] == "phase" || header_[c] == "slip_cues" ||
        header_[c] == "recorded_phase") {
      text[c] = &text_[header_[c]];
    } else {
      numeric[c] = &numeric_[header_[c]];
    }
  }
  while (std::getline(stream, line)) {
    std::stringstream cells(line);
    std::string cell;
    for (size_t c = 0; c < header_.size() && std::getline(cells, cell, ','); ++c) {
      if (text[c] != nullptr) {
        text[c]->push_back(cell);
      } else {
        numeric[c]->push_back(std::strtod(cell.c_str(), nullptr));
      }
    }
  }
  time_ = numeric_["time_s"];
}

const std::vector<double>& Signals::Column(const std::string& name) const {
  const auto it = numeric_.find(name);
  if (it == numeric_.end()) {
    ADD_FAILURE() << "signals.csv has no column " << name;
    static const std::vector<double> kZeros(1000000, 0.0);
    return kZeros;
  }
  return it->second;
}

size_t Signals::RowAt(double time_s) const {
  for (size_t r = 0; r < time_.size(); ++r) {
    if (time_[r] >= time_s - 1e-9) return r;
  }
  return time_.empty() ? 0 : time_.size() - 1;
}

ScenarioRun RunScenarioText(const graspbed::test_support::TempDir& dir, const std::string& name,
                            const std::string& yaml) {
  const std::string file = dir.Write(name + ".yaml", yaml);
  const ScenarioConfig config = LoadScenario(file);
  RunOptions options;
  options.out_dir = dir.Path(name + "_out");
  options.write_plots = false;
  RunResult result = RunScenario(config, options);
  return {std::move(result), Signals(options.out_dir + "/signals.csv")};
}

}  // namespace graspbed::testbed::test_support

#include "tests/scenario/scenario_test_util.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "sim/scenario/scenario_config.h"

namespace graspbed::scenario::testing {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  path_ = std::filesystem::temp_directory_path() /
          ("graspbed_scenario_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::string TempDir::Write(const std::string& name, const std::string& text) const {
  const std::filesystem::path full = path_ / name;
  std::filesystem::create_directories(full.parent_path());
  std::ofstream out(full);
  if (!out) throw std::runtime_error("cannot write " + full.string());
  out << text;
  return full.string();
}

std::string ReadText(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) return "";
  std::stringstream text;
  text << stream.rdbuf();
  return text.str();
}

std::string HeldBoxScenario(double duration_s, const std::string& extra_script, const std::string& extra) {
  return "duration_s: " + std::to_string(duration_s) + R"(
object: {shape: box, size_m: [0.05, 0.05, 0.08], mass_kg: 0.1, friction: 0.7}
hand: {open_gap_m: 0.055}
controller: {name: open_loop}
script:
  - {at_s: 0.04, action: close}
  - {at_s: 0.15, action: lift, height_m: 0.05, duration_s: 0.2}
)" + extra_script + extra;
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
    if (header_[c] == "intent" || header_[c] == "phase") {
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

ScenarioRun RunScenarioText(const TempDir& dir, const std::string& name, const std::string& yaml) {
  const std::string file = dir.Write(name + ".yaml", yaml);
  const ScenarioConfig config = LoadScenario(file);
  RunOptions options;
  options.out_dir = dir.Path(name + "_out");
  options.write_plots = false;
  RunResult result = RunScenario(config, options);
  return {std::move(result), Signals(options.out_dir + "/signals.csv")};
}

std::string CliBinary() {
  const char* binary = std::getenv("GRASPBED_BINARY");
  return binary == nullptr ? "" : binary;
}

CliResult RunCli(const std::string& arguments) {
  CliResult result;
  const std::string binary = CliBinary();
  if (binary.empty()) {
    result.err = "GRASPBED_BINARY not set";
    return result;
  }
  TempDir capture;
  const std::string out_path = capture.Path("stdout");
  const std::string err_path = capture.Path("stderr");
  const std::string command = binary + " " + arguments + " >" + out_path + " 2>" + err_path + " </dev/null";
  const int status = std::system(command.c_str());
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = ReadText(out_path);
  result.err = ReadText(err_path);
  return result;
}

}  // namespace graspbed::scenario::testing

// libFuzzer target for the scenario loader: the input is a scenario file followed by `--set`-style
// overrides, which go through LoadScenarioFromString (parsing, overrides, loading, validation) and,
// when the scenario loads and runs on the simulation, through model generation, the MuJoCo compile
// and 20 ms of simulated time of RunScenario (script, sensor, readout, inversion, controller, metrics).
//
// Input format: YAML text; a line that is exactly "#--set" (a YAML comment, so a broken separator
// still leaves YAML) ends it; every non-empty line after it is one override "key=value", parsed by
// ParseOverride as `graspbed run --set` parses its argument. fuzz/make_scenario_seeds.cc writes the
// seed corpus in this format from scenarios/**/*.yaml, fuzz/scenario.dict lists the keys.
//
// What counts as a finding: anything that aborts, trips ASan/UBSan/LeakSanitizer or runs over
// libFuzzer's -timeout. Bad input is an expected outcome: std::invalid_argument (common::ConfigError
// among them) is what app/main.cc reports as bad input (exit 2). Any other exception is a finding
// here, reported and aborted on: the CLI would print it and exit 1 ("failed"), but on this path (the
// simulation, no device, no outputs) nothing but bad input can legitimately fail.
//
// Safety: scenarios name files by path. Layout and FEA config files are only read. Controller
// plugins (`plugin: LIBRARY`, `name: plugin:...`) would be dlopen'ed, i.e. the fuzzer could run any
// shared object's constructors that a mutated path happens to name; the target is linked with
// -Wl,--wrap=dlopen, so the plugin loader's dlopen is __wrap_dlopen below, which loads nothing and
// makes the loader refuse the plugin as it refuses one that does not load (std::invalid_argument).
// Nothing is written: RunScenario gets no out_dir (no files), never computes the oracle grip (its disk
// cache writes files and its search runs dozens of simulations), and only backend sim runs (serial
// would open devices and write a frame log, replay reads a recording).
// Build, seed corpus and run: docs/hardware.md "Fuzzing".
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "common/data_dir.h"
#include "testbed/runner.h"
#include "testbed/scenario_config.h"

namespace {

using graspbed::testbed::Override;

/// The line between the scenario text and the override lines.
constexpr std::string_view kSeparator = "#--set";
/// Simulated time each loaded sim scenario runs [s].
constexpr double kRunS = 0.02;
/// Overrides beyond this many are ignored: the loader reloads the scenario once per override to
/// blame the one that broke it, which costs time quadratic in their number; a command line has a few.
constexpr size_t kMaxOverrides = 16;

struct Input {
  std::string yaml;
  std::vector<std::string> overrides;
};

Input Split(std::string_view text) {
  Input input;
  size_t position = 0;
  bool in_overrides = false;
  while (position <= text.size()) {
    size_t end = text.find('\n', position);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(position, end - position);
    if (in_overrides) {
      if (!line.empty() && input.overrides.size() < kMaxOverrides) input.overrides.emplace_back(line);
    } else if (line == kSeparator) {
      in_overrides = true;
    } else {
      input.yaml.append(line);
      input.yaml.push_back('\n');
    }
    position = end + 1;
  }
  return input;
}

[[noreturn]] void Finding(const char* what, const std::string& message) {
  std::fprintf(stderr, "scenario_fuzz: %s: %s\n", what, message.c_str());
  std::abort();
}

}  // namespace

// See the file comment: the plugin loader's dlopen, which loads nothing (dlerror() stays null, and
// the loader refuses the plugin with "cannot load: unknown reason").
extern "C" void* __wrap_dlopen(const char* /*path*/, int /*flags*/) { return nullptr; }

extern "C" int LLVMFuzzerInitialize(int* /*argc*/, char*** /*argv*/) {
  // Bare plugin names are looked up on this path; nothing is loaded either way (see above).
  unsetenv("GRASPBED_PLUGIN_PATH");
  graspbed::common::DataDir();  // found once, before any input (throws when the data is missing)
  // The loader analyses each FEA unit once per process (`sensitivities: fea`); the shipped unit's
  // analysis takes over 10 s in this build, so it is done here rather than charged to an input.
  graspbed::testbed::LoadScenarioFromString("sensor: {sensitivities: fea}\n", "warm_up.yaml");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const Input input = Split(std::string_view(reinterpret_cast<const char*>(data), size));
  // A path inside the shipped scenarios/, as a shipped scenario's: relative paths in it (layouts, FEA
  // configs) resolve as they would for one. The file itself is never opened.
  static const std::string source_name = graspbed::common::DataPath("scenarios/fuzz_input.yaml");
  graspbed::testbed::ScenarioConfig config;
  try {
    std::vector<Override> overrides;
    for (const std::string& line : input.overrides) overrides.push_back(graspbed::testbed::ParseOverride(line));
    config = graspbed::testbed::LoadScenarioFromString(input.yaml, source_name, overrides);
  } catch (const std::invalid_argument&) {
    return 0;  // bad input, refused with a message: exit 2 on the command line
  } catch (const std::exception& error) {
    Finding("loading threw", error.what());
  }
  if (config.backend != graspbed::testbed::Backend::kSim) return 0;

  // Only the first kRunS of the run (its signal storage is sized by duration_s).
  config.duration_s = std::min(config.duration_s, kRunS);
  graspbed::testbed::RunOptions run;
  run.out_dir = "";
  run.write_plots = false;
  run.oracle = graspbed::testbed::OracleMode::kNever;
  try {
    const graspbed::testbed::RunResult result = graspbed::testbed::RunScenario(config, run);
    if (!result.completed) Finding("run", "did not complete");
  } catch (const std::invalid_argument&) {
    return 0;  // a scene the rig refuses (e.g. bodies that start inside each other): exit 2
  } catch (const std::exception& error) {
    Finding("the run threw", error.what());
  }
  return 0;
}

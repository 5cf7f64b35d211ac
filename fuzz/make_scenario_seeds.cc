// Seed corpus of fuzz/scenario_fuzz.cc, written from the shipped scenario library:
//   make_scenario_seeds SCENARIO_DIR OUT_DIR
// Every *.yaml under SCENARIO_DIR becomes seeds in the target's input format (scenario text, a line
// "#--set", one key=value override per line):
//   a scenario file               its text, no overrides
//   a sweep spec (scenario:, parameters:)     the scenario it names with the first, and with the
//                                 last, value of each parameter (a random one's min, max)
//   a scorecard set (bases:)      each base scenario with the set's and the base's `vary` entries:
//                                 the first and the last choice of each `choose`, a range's min, max
// Prints the number of seeds written. Exits 1 on a file it cannot read.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;

using Overrides = std::vector<std::pair<std::string, std::string>>;

std::string ReadFile(const fs::path& path) {
  std::ifstream stream(path);
  if (!stream) throw std::runtime_error(path.string() + ": cannot read");
  std::stringstream text;
  text << stream.rdbuf();
  return text.str();
}

// A value as `--set` takes it: a scalar's text, anything else in YAML flow style.
std::string ValueText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

class SeedWriter {
 public:
  explicit SeedWriter(fs::path out_dir) : out_dir_(std::move(out_dir)) { fs::create_directories(out_dir_); }

  void Write(const std::string& name, const std::string& scenario_text, const Overrides& overrides) {
    std::string seed = scenario_text;
    if (!seed.empty() && seed.back() != '\n') seed.push_back('\n');
    if (!overrides.empty()) {
      seed += "#--set\n";
      for (const auto& [key, value] : overrides) seed += key + "=" + value + "\n";
    }
    std::ofstream(out_dir_ / name) << seed;
    ++count_;
  }
  int count() const { return count_; }

 private:
  fs::path out_dir_;
  int count_ = 0;
};

// The overrides of a `vary` list at one end: the first (end 0) or last (end 1) choice, a range's min
// or max.
void AddVary(const YAML::Node& vary, int end, Overrides* overrides) {
  if (!vary.IsSequence()) return;
  for (const YAML::Node& entry : vary) {
    if (entry["choose"] && entry["choose"].IsSequence() && entry["choose"].size() > 0) {
      const YAML::Node& choices = entry["choose"];
      const YAML::Node group = choices[end == 0 ? 0 : choices.size() - 1];
      for (const auto& item : group) overrides->emplace_back(item.first.Scalar(), ValueText(item.second));
    } else if (entry["key"]) {
      overrides->emplace_back(entry["key"].Scalar(), ValueText(entry[end == 0 ? "min" : "max"]));
    }
  }
}

std::string Stem(const fs::path& root, const fs::path& file) {
  std::string name = fs::relative(file, root).replace_extension().string();
  std::replace(name.begin(), name.end(), '/', '_');
  return name;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: make_scenario_seeds SCENARIO_DIR OUT_DIR\n";
    return 2;
  }
  const fs::path root = fs::absolute(argv[1]);
  try {
    SeedWriter writer(argv[2]);
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
      if (entry.is_regular_file() && entry.path().extension() == ".yaml") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    for (const fs::path& file : files) {
      const std::string text = ReadFile(file);
      const YAML::Node spec = YAML::Load(text);
      const std::string stem = Stem(root, file);
      if (spec["bases"]) {
        int base_index = 0;
        for (const YAML::Node& base : spec["bases"]) {
          const std::string scenario = ReadFile(file.parent_path() / base["scenario"].Scalar());
          for (int end = 0; end < 2; ++end) {
            Overrides overrides;
            AddVary(spec["vary"], end, &overrides);
            AddVary(base["vary"], end, &overrides);
            writer.Write(stem + "_base" + std::to_string(base_index) + "_" + std::to_string(end), scenario,
                         overrides);
          }
          ++base_index;
        }
      } else if (spec["scenario"] && spec["parameters"]) {
        const std::string scenario = ReadFile(file.parent_path() / spec["scenario"].Scalar());
        for (int end = 0; end < 2; ++end) {
          Overrides overrides;
          for (const auto& parameter : spec["parameters"]) {
            const YAML::Node& values = parameter.second;
            if (values.IsSequence() && values.size() > 0) {
              overrides.emplace_back(parameter.first.Scalar(), ValueText(values[end == 0 ? 0 : values.size() - 1]));
            } else if (values.IsMap()) {
              overrides.emplace_back(parameter.first.Scalar(), ValueText(values[end == 0 ? "min" : "max"]));
            }
          }
          writer.Write(stem + "_" + std::to_string(end), scenario, overrides);
        }
      } else {
        writer.Write(stem, text, {});
      }
    }
    std::cout << writer.count() << " seeds in " << argv[2] << "\n";
  } catch (const std::exception& error) {
    std::cerr << "make_scenario_seeds: " << error.what() << "\n";
    return 1;
  }
  return 0;
}

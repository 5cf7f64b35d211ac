// `graspbed objects`: lists the object library (name, size, mass, centre of mass, friction,
// stiffness, crush force, source), as a table or as JSON.
#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>
#include <string>

#include "app/command_registry.h"
#include "sim/object_library.h"

namespace graspbed::app {
namespace {

struct ObjectsOptions {
  std::string library_path;
  bool json = false;
  bool markdown = false;
};

nlohmann::json ToJson(const sim::ObjectSummary& s) {
  nlohmann::json row;
  row["name"] = s.name;
  row["shape"] = s.shape;
  row["description"] = s.description;
  row["size_m"] = s.size_m;
  row["mass_kg"] = s.mass_kg;
  row["centre_of_mass_m"] = s.centre_of_mass_m;
  row["principal_inertia_kg_m2"] = s.principal_inertia_kg_m2;
  row["friction"] = s.friction;
  row["stiffness_n_m"] = s.stiffness_n_m;
  row["solref_timeconst_s"] = s.solref_timeconst_s;
  row["crush_limit_n"] = s.crush_limit_n;
  if (s.fill_fraction) row["fill_fraction"] = *s.fill_fraction;
  row["parts"] = s.part_count;
  row["default_grasp"] = sim::ToString(s.default_grasp);
  row["source"] = s.source;
  row["notes"] = s.notes;
  return row;
}

void RunObjects(const ObjectsOptions& options) {
  const sim::ObjectLibrary library = options.library_path.empty()
                                         ? sim::ShippedObjectLibrary()
                                         : sim::ObjectLibrary::LoadFile(options.library_path);
  const std::vector<sim::ObjectSummary> rows = sim::SummarizeObjects(library);
  if (options.json) {
    nlohmann::json out = nlohmann::json::array();
    for (const sim::ObjectSummary& row : rows) out.push_back(ToJson(row));
    std::cout << out.dump(2) << '\n';
    return;
  }
  std::cout << (options.markdown ? sim::ObjectTableMarkdown(rows) : sim::ObjectTableText(rows));
}

void AddObjectsCommand(CLI::App& root) {
  auto options = std::make_shared<ObjectsOptions>();
  CLI::App* command = root.add_subcommand(
      "objects",
      "List the object library a scenario picks from with `object: {name: NAME}`: size, mass, centre of mass, "
      "friction, stiffness, crush force and the source of the figures");
  command->add_option("--library", options->library_path, "library YAML (default: the shipped models/objects.yaml)")
      ->check(CLI::ExistingFile);
  command->add_flag("--json", options->json, "one JSON object per library object, SI units");
  command->add_flag("--markdown", options->markdown, "the table as docs/scenarios.md shows it");
  command->callback([options] { RunObjects(*options); });
}

const bool kRegistered = RegisterCommands(&AddObjectsCommand);

}  // namespace
}  // namespace graspbed::app

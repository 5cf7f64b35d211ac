// `graspbed config-reference`: prints the reference table of each config section (key, unit,
// default, allowed, meaning), derived from the structs' field tables; docs/ carries the same tables.
#include <iostream>
#include <memory>
#include <string>

#include "app/command_registry.h"
#include "testbed/config_reference.h"

namespace graspbed::app {
namespace {

void RunConfigReference(const std::string& section) {
  if (!section.empty()) {
    std::cout << testbed::ConfigReferenceMarkdown(section);
    return;
  }
  bool first = true;
  for (const testbed::ConfigSection& entry : testbed::ConfigReference()) {
    std::cout << (first ? "" : "\n") << "### `" << entry.path << "`\n\n"
              << common::ReferenceMarkdown(entry.rows);
    first = false;
  }
}

void AddConfigReferenceCommand(CLI::App& root) {
  auto section = std::make_shared<std::string>();
  CLI::App* command = root.add_subcommand(
      "config-reference",
      "Print the keys of the config sections (unit, default, allowed values, meaning) as Markdown");
  std::string sections;
  for (const testbed::ConfigSection& entry : testbed::ConfigReference()) {
    sections += (sections.empty() ? "" : ", ") + entry.path;
  }
  command->add_option("section", *section, "one section (" + sections + "); default: all");
  command->callback([section] { RunConfigReference(*section); });
}

const bool kRegistered = RegisterCommands(&AddConfigReferenceCommand);

}  // namespace
}  // namespace graspbed::app

#pragma once
/// The reference tables of a scenario's config sections (key, unit, default, allowed, meaning),
/// each derived from its struct's field table (common/field_table.h). `graspbed config-reference`
/// prints them; docs/scenarios.md and docs/hardware.md carry them between
/// `<!-- config-reference SECTION -->` and `<!-- /config-reference -->`, and a test keeps those
/// copies equal to what the tables say.

#include <string>
#include <vector>

#include "common/field_table.h"

namespace graspbed::testbed {

/// One section of a scenario file with a field table (and "fea", the FEA config file of
/// sensor.fea_config).
struct ConfigSection {
  std::string path;  ///< where it sits in a scenario file ("object", "sensor.readout", "serial", "fea")
  std::vector<common::FieldReference> rows;
};

/// Every section with a field table, in file order.
std::vector<ConfigSection> ConfigReference();

/// The Markdown table of the section at `path`.
/// @throws common::ConfigError (key "section") for an unknown path, listing the known ones.
std::string ConfigReferenceMarkdown(const std::string& path);

}  // namespace graspbed::testbed

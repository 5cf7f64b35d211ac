#pragma once
/// Where graspbed's shipped data live (sensor layouts, the FEA config, scenarios, models), found at
/// run time so that an installed graspbed never depends on the tree it was built from.

#include <string>

namespace graspbed::common {

/// Root of the shipped data, laid out as in the source tree (sensor/layouts/, sensor/fea/,
/// scenarios/, models/). In order: $GRASPBED_DATA_DIR if set (it must exist); else the first
/// `share/graspbed` found in a directory that holds the running binary or module, walking up from
/// it (<prefix>/bin/graspbed and <prefix>/lib/python3/dist-packages/graspbed/ both find
/// <prefix>/share/graspbed; the build tree has its own share/graspbed pointing at the sources).
/// Found once and cached. Throws std::runtime_error naming the places tried.
const std::string& DataDir();

/// DataDir() + "/" + relative_path (no check that the file exists).
std::string DataPath(const std::string& relative_path);

/// Directory of the running program or of the shared object that holds graspbed's code (the
/// Python module), resolved through symlinks; empty if unknown.
std::string ProgramDir();

}  // namespace graspbed::common

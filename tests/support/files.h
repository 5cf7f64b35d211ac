#pragma once
// Reading files, and finding the shipped ones in the source tree.

#include <string>

namespace graspbed::test_support {

/// Whole file as a string, byte for byte ("" when it cannot be read).
std::string ReadText(const std::string& path);

/// Absolute path of `relative` (e.g. "sensor/layouts/paper_3x3.yaml") in the source tree.
std::string SourcePath(const std::string& relative);

}  // namespace graspbed::test_support

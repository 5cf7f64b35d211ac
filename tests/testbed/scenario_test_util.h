#pragma once
// Helpers for scenario tests: scenario files built from a shared held-object scene, and in-process runs
// with their signals.csv read back. Temporary directories, file reads and CLI runs are in tests/support.

#include <map>
#include <string>
#include <vector>

#include "testbed/runner.h"
#include "tests/support/temp_dir.h"

namespace graspbed::testbed::test_support {

/// A box of 100 g (friction 0.7) between the fingers of a hand pre-shaped 5 mm wider than it, under the
/// open-loop controller at its default effort: closed at 0.04 s, touched after the readout's tare
/// (0.1 s), held (about 10 N squeeze) from about 0.13 s, lifted 50 mm from 0.15 s to 0.35 s. Followed by
/// `extra_script` (YAML list items, indented two spaces) and `extra` top-level YAML. The open-loop controller
/// is blind to the sensor, so sensor faults leave the physics untouched and runs can be compared tick by
/// tick.
std::string HeldBoxScenario(double duration_s, const std::string& extra_script = "",
                            const std::string& extra = "");
/// Time by which HeldBoxScenario's object hangs still in the hand, 50 mm above the table [s].
inline constexpr double kHeldInAirS = 0.45;

/// signals.csv read back: numeric columns by name (text columns intent/phase kept as text).
class Signals {
 public:
  explicit Signals(const std::string& csv_path);
  size_t rows() const { return time_.size(); }
  /// Values of numeric column `name`; fails the test (and returns zeros) when there is none.
  const std::vector<double>& Column(const std::string& name) const;
  bool Has(const std::string& name) const { return numeric_.count(name) > 0; }
  double At(const std::string& name, size_t row) const { return Column(name)[row]; }
  /// First row with time_s >= `time_s` (rows() - 1 when none).
  size_t RowAt(double time_s) const;
  /// Value of `name` at the first row with time_s >= `time_s`.
  double AtTime(const std::string& name, double time_s) const { return At(name, RowAt(time_s)); }
  const std::vector<std::string>& Text(const std::string& name) const { return text_.at(name); }
  const std::vector<std::string>& header() const { return header_; }

 private:
  std::vector<std::string> header_;
  std::vector<double> time_;
  std::map<std::string, std::vector<double>> numeric_;
  std::map<std::string, std::vector<std::string>> text_;
};

/// One in-process run of a scenario text: loaded (as DIR/<name>.yaml), run with outputs in DIR/out
/// (no plots), signals read back.
struct ScenarioRun {
  RunResult result;
  Signals signals;
};
ScenarioRun RunScenarioText(const graspbed::test_support::TempDir& dir, const std::string& name,
                            const std::string& yaml);

}  // namespace graspbed::testbed::test_support

#pragma once
// Runs of the real `graspbed` executable, which ctest names in $GRASPBED_BINARY (see
// graspbed_add_test in tests/CMakeLists.txt).

#include <string>

namespace graspbed::test_support {

/// The CLI binary, or "" when GRASPBED_BINARY is not set (the test was not started by ctest). Each
/// fixture decides whether that skips or fails its tests.
std::string CliBinary();

/// Outcome of one CLI run.
struct CliResult {
  int exit_code = -1;      ///< -1 when it did not exit normally (or could not be started)
  std::string out;         ///< everything written to stdout
  std::string err;         ///< everything written to stderr
  bool timed_out = false;  ///< RunCliWithin only: killed at its time limit
};

/// Runs `$GRASPBED_BINARY <arguments>` to completion through the shell (arguments must be
/// shell-safe), in the test's working directory, with stdin from /dev/null and stdout and stderr
/// captured to files (neither is a terminal). Without GRASPBED_BINARY: exit code -1 and a message
/// in `err`.
CliResult RunCli(const std::string& arguments);

/// RunCli, but the process is killed (SIGKILL, coreutils `timeout`) after `limit_s` seconds of wall
/// time; then `timed_out` is set. A process that dies of a signal gets exit code 128 + signal.
CliResult RunCliWithin(const std::string& arguments, double limit_s);

/// RunCli with `prefix` (shell-safe words ending in a space) before the binary, e.g. "xvfb-run -a ".
CliResult RunCliUnder(const std::string& prefix, const std::string& arguments);

}  // namespace graspbed::test_support

#pragma once
/// Ctrl-C and SIGTERM for the long-running commands (run, suite, sweep, hw, emulate): while a
/// StopSignalGuard lives, the first SIGINT or SIGTERM only sets StopRequested(), so the command ends
/// cleanly (finished results kept, stream stopped, motor off, port restored); a second SIGINT ends
/// the process the usual way.

#include <atomic>
#include <csignal>

namespace graspbed::app {

/// Set by SIGINT/SIGTERM while a StopSignalGuard is installed; cleared when one is installed.
std::atomic<bool>& StopRequested();

/// Installs the handlers for its lifetime and restores the previous ones after.
class StopSignalGuard {
 public:
  StopSignalGuard();
  ~StopSignalGuard();
  StopSignalGuard(const StopSignalGuard&) = delete;
  StopSignalGuard& operator=(const StopSignalGuard&) = delete;

 private:
  struct sigaction previous_int_ {};
  struct sigaction previous_term_ {};
};

}  // namespace graspbed::app

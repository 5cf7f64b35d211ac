#include "app/stop_signal.h"

namespace graspbed::app {
namespace {

std::atomic<bool> stop_requested{false};

extern "C" void OnStopSignal(int signal_number) {
  stop_requested.store(true);
  // A second Ctrl-C ends the process the usual way.
  if (signal_number == SIGINT) std::signal(SIGINT, SIG_DFL);
}

}  // namespace

std::atomic<bool>& StopRequested() { return stop_requested; }

StopSignalGuard::StopSignalGuard() {
  stop_requested.store(false);
  struct sigaction action {};
  action.sa_handler = &OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, &previous_int_);
  sigaction(SIGTERM, &action, &previous_term_);
}

StopSignalGuard::~StopSignalGuard() {
  sigaction(SIGINT, &previous_int_, nullptr);
  sigaction(SIGTERM, &previous_term_, nullptr);
}

}  // namespace graspbed::app

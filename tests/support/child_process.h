#pragma once
// A child process started with posix_spawn (no shell), stdout and stderr in files, stdin from /dev/null
// or from a descriptor the test holds (a pipe's read end, a pseudo-terminal's slave). For tests that
// run several CLI processes at once (`graspbed emulate` beside a host). Ended by its pid only
// (SIGTERM, then SIGKILL) when the test does not wait for it.

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace graspbed::test_support {

class ChildProcess {
 public:
  /// Starts `args` (args[0] is the executable's path). `stdin_fd` < 0: stdin is /dev/null.
  ChildProcess(const std::vector<std::string>& args, const std::string& out_path, const std::string& err_path,
               int stdin_fd = -1);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  bool started() const { return pid_ > 0; }
  /// Waits up to `timeout_s` for the exit; the exit code (128 + signal when killed), or nullopt.
  std::optional<int> Wait(double timeout_s);
  std::string out() const;
  std::string err() const;

 private:
  pid_t pid_ = -1;
  std::optional<int> exit_code_;
  std::string out_path_;
  std::string err_path_;
};

}  // namespace graspbed::test_support

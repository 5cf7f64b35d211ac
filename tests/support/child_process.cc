#include "tests/support/child_process.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "common/process.h"
#include "tests/support/files.h"

namespace graspbed::test_support {

ChildProcess::ChildProcess(const std::vector<std::string>& args, const std::string& out_path,
                           const std::string& err_path, int stdin_fd)
    : out_path_(out_path), err_path_(err_path) {
  try {
    pid_ = common::SpawnProcess(args, stdin_fd, out_path, err_path);
  } catch (const std::runtime_error&) {
    pid_ = -1;  // started() says so; the test decides what that means
  }
}

ChildProcess::~ChildProcess() {
  if (pid_ <= 0 || exit_code_) return;
  ::kill(pid_, SIGTERM);
  if (!Wait(5.0)) {
    ::kill(pid_, SIGKILL);
    Wait(5.0);
  }
}

std::optional<int> ChildProcess::Wait(double timeout_s) {
  if (exit_code_ || pid_ <= 0) return exit_code_;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return exit_code_;
    }
    if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

std::string ChildProcess::out() const { return ReadText(out_path_); }
std::string ChildProcess::err() const { return ReadText(err_path_); }

}  // namespace graspbed::test_support

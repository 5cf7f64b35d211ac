#include "common/process.h"

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <thread>

extern char** environ;

namespace graspbed::common {
namespace {

void OpenOutput(posix_spawn_file_actions_t* actions, int fd, const std::string& path) {
  if (path.empty()) {
    posix_spawn_file_actions_addopen(actions, fd, "/dev/null", O_WRONLY, 0);
  } else {
    posix_spawn_file_actions_addopen(actions, fd, path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  }
}

}  // namespace

int SpawnProcess(const std::vector<std::string>& argv, int stdin_fd, const std::string& stdout_path,
                 const std::string& stderr_path) {
  if (argv.empty()) throw std::runtime_error("cannot start a program without a name");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdin_fd >= 0) {
    posix_spawn_file_actions_adddup2(&actions, stdin_fd, STDIN_FILENO);
  } else {
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  }
  OpenOutput(&actions, STDOUT_FILENO, stdout_path);
  OpenOutput(&actions, STDERR_FILENO, stderr_path);
  std::vector<char*> args;
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  const int error = posix_spawn(&pid, argv[0].c_str(), &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(error));
  return pid;
}

int WaitExit(int pid, double timeout_s) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    int status = 0;
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (done < 0) return -2;
    if (std::chrono::steady_clock::now() >= deadline) return -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

int EndChild(int pid) {
  ::kill(pid, SIGTERM);
  int code = WaitExit(pid, 10.0);
  if (code == -1) {
    ::kill(pid, SIGKILL);
    code = WaitExit(pid, 10.0);
  }
  return code;
}

std::string SelfExecutablePath() {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) throw std::runtime_error("cannot find this executable (/proc/self/exe): " + error.message());
  return self.string();
}

double LoadAverage1Min() {
  double load = -1.0;
  if (std::FILE* file = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(file, "%lf", &load) != 1) load = -1.0;
    std::fclose(file);
  }
  return load;
}

void UseRealTimePriority(int priority) {
  sched_param parameters{};
  parameters.sched_priority = priority;
  if (::sched_setscheduler(0, SCHED_FIFO, &parameters) != 0) {
    const int error = errno;
    throw std::runtime_error(
        std::string("SCHED_FIFO refused (") + std::strerror(error) +
        "): needs the CAP_SYS_NICE capability (root has it unless a container drops it; for a user, setcap "
        "cap_sys_nice+ep on the binary) or an rtprio limit of at least " +
        std::to_string(priority) + " for your user (/etc/security/limits.conf)");
  }
}

double ThreadCpuSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

}  // namespace graspbed::common

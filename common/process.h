#pragma once
/// Starting a child program with its standard streams redirected (posix_spawn), for the pieces that
/// drive another program: the video writer (ffmpeg) and the tests' child processes; and the CPU
/// clock the benchmarks read.

#include <string>
#include <vector>

namespace graspbed::common {

/// Starts `argv` (argv[0] a path to the program) with stdin from `stdin_fd` (-1: /dev/null) and
/// stdout and stderr written to the files `stdout_path` and `stderr_path` (created or truncated;
/// empty: /dev/null); the environment is the caller's. Returns the child's pid.
/// @throws std::runtime_error naming the program when it cannot be started.
int SpawnProcess(const std::vector<std::string>& argv, int stdin_fd, const std::string& stdout_path,
                 const std::string& stderr_path);

/// CPU time the calling thread has used [s] (CLOCK_THREAD_CPUTIME_ID): unlike wall time, not
/// inflated when other processes share the cores.
double ThreadCpuSeconds();

}  // namespace graspbed::common

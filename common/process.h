#pragma once
/// Starting a child program with its standard streams redirected (posix_spawn), for the pieces that
/// drive another program: the video writer (ffmpeg) and the tests' child processes.

#include <string>
#include <vector>

namespace graspbed::common {

/// Starts `argv` (argv[0] a path to the program) with stdin from `stdin_fd` (-1: /dev/null) and
/// stdout and stderr written to the files `stdout_path` and `stderr_path` (created or truncated;
/// empty: /dev/null); the environment is the caller's. Returns the child's pid.
/// @throws std::runtime_error naming the program when it cannot be started.
int SpawnProcess(const std::vector<std::string>& argv, int stdin_fd, const std::string& stdout_path,
                 const std::string& stderr_path);

}  // namespace graspbed::common

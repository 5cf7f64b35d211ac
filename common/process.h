#pragma once
/// Starting a child program with its standard streams redirected (posix_spawn), for the pieces that
/// drive another program: the video writer (ffmpeg), the soak's two graspbed children and the tests'
/// child processes; waiting for and ending such a child; this process's own executable, the
/// machine's load and the real-time scheduling the serial loop asks for; and the CPU clock the
/// benchmarks read.

#include <string>
#include <vector>

namespace graspbed::common {

/// Starts `argv` (argv[0] a path to the program) with stdin from `stdin_fd` (-1: /dev/null) and
/// stdout and stderr written to the files `stdout_path` and `stderr_path` (created or truncated;
/// empty: /dev/null); the environment is the caller's. Returns the child's pid.
/// @throws std::runtime_error naming the program when it cannot be started.
int SpawnProcess(const std::vector<std::string>& argv, int stdin_fd, const std::string& stdout_path,
                 const std::string& stderr_path);

/// Waits up to `timeout_s` [s] for the child `pid` to exit (0: only looks). Returns its exit code
/// (128 + the signal's number when a signal ended it), -1 when it is still running, -2 when it is
/// no child of this process (waitpid failed).
int WaitExit(int pid, double timeout_s);

/// Ends a child this process started: SIGTERM (graspbed's long commands end cleanly on it), SIGKILL
/// when it is still running 10 s later. Returns its exit code as WaitExit does.
int EndChild(int pid);

/// The path of this process's executable (/proc/self/exe), to start another instance of it.
/// @throws std::runtime_error when /proc cannot tell it.
std::string SelfExecutablePath();

/// The machine's load average over the last minute (/proc/loadavg); -1 when it cannot be read.
double LoadAverage1Min();

/// Runs the calling thread, and the threads it starts from now on (they inherit it), under
/// SCHED_FIFO at `priority` (1-99), so other processes on the cores cannot delay it.
/// @throws std::runtime_error when refused, naming what the machine must allow (the message starts
/// with "SCHED_FIFO refused"; callers put the option that asked for it in front).
void UseRealTimePriority(int priority);

/// CPU time the calling thread has used [s] (CLOCK_THREAD_CPUTIME_ID): unlike wall time, not
/// inflated when other processes share the cores.
double ThreadCpuSeconds();

}  // namespace graspbed::common

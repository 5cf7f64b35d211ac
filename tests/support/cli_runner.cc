#include "tests/support/cli_runner.h"

#include <sys/wait.h>

#include <cstdlib>
#include <string>

#include "tests/support/files.h"
#include "tests/support/temp_dir.h"

namespace graspbed::test_support {

std::string CliBinary() {
  const char* binary = std::getenv("GRASPBED_BINARY");
  return binary == nullptr ? "" : binary;
}

namespace {

// `prefix` goes before the binary (e.g. a `timeout` command), `arguments` after it.
CliResult Run(const std::string& prefix, const std::string& arguments) {
  CliResult result;
  const std::string binary = CliBinary();
  if (binary.empty()) {
    result.err = "GRASPBED_BINARY not set";
    return result;
  }
  // Files rather than a pipe: stdout and stderr are both kept, and neither can fill up and block.
  const TempDir capture("cli_capture");
  const std::string out_path = capture.Path("stdout");
  const std::string err_path = capture.Path("stderr");
  const std::string command =
      prefix + binary + " " + arguments + " >" + out_path + " 2>" + err_path + " </dev/null";
  const int status = std::system(command.c_str());
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = ReadText(out_path);
  result.err = ReadText(err_path);
  return result;
}

}  // namespace

CliResult RunCli(const std::string& arguments) { return Run("", arguments); }

CliResult RunCliUnder(const std::string& prefix, const std::string& arguments) {
  return Run(prefix, arguments);
}

CliResult RunCliWithin(const std::string& arguments, double limit_s) {
  // timeout exits 128 + 9 when it had to kill; the shell reports a child killed by signal N as 128 + N.
  CliResult result = Run("timeout -s KILL " + std::to_string(limit_s) + " ", arguments);
  result.timed_out = result.exit_code == 128 + 9;
  return result;
}

}  // namespace graspbed::test_support

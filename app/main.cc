// graspbed: simulation-in-the-loop grasp testbed for a prosthetic hand with a tactile fingertip.
#include <exception>
#include <iostream>
#include <stdexcept>
#include <string>

#include "app/command_registry.h"
#include "testbed/oracle.h"

int main(int argc, char** argv) {
  CLI::App root{
      "graspbed: simulation-in-the-loop grasp testbed for a prosthetic hand with a tactile "
      "fingertip (elastic steel frame units, piezoresistive R1/R2)"};
  root.require_subcommand(1);
  root.set_version_flag("--version", std::string("graspbed ") + GRASPBED_VERSION);
  // Given before or after the subcommand (fallthrough): the oracle searches of this process are
  // neither read from nor written to the disk cache (docs/scenarios.md, "The oracle grip").
  root.add_flag_callback("--no-oracle-cache", [] { graspbed::testbed::SetOracleDiskCacheOff(); },
                         "do not read or keep oracle searches in the disk cache ($XDG_CACHE_HOME/graspbed/oracle)");
  root.fallthrough();
  try {
    // Inside the try: some options' defaults are data files, and a missing data directory is an
    // error message, not std::terminate.
    graspbed::app::InstallCommands(root);
    root.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    // Usage errors are bad input (exit 2); --help and --version exit 0; a subcommand that throws
    // CLI::RuntimeError(code) ends with that code.
    const int code = root.exit(error);
    if (dynamic_cast<const CLI::RuntimeError*>(&error) != nullptr) return code;
    return code == 0 ? 0 : graspbed::app::kExitBadInput;
  } catch (const std::invalid_argument& error) {
    // Bad input, decided here for every command: common::ConfigError (a config file, --set, a
    // command-line value; file, line, key and value in its message) and any other
    // std::invalid_argument a library throws for arguments it refuses.
    std::cerr << "graspbed: error: " << error.what() << '\n';
    return graspbed::app::kExitBadInput;
  } catch (const std::exception& error) {
    std::cerr << "graspbed: error: " << error.what() << '\n';
    return graspbed::app::kExitFailed;
  }
  return graspbed::app::kExitOk;
}

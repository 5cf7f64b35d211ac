#pragma once
/// Subcommands register themselves here, so each cmd_*.cc stays self-contained.

#include <CLI/CLI.hpp>

namespace graspbed::app {

/// Adds one or more subcommands (with their options and callbacks) to the root command.
using CommandInstaller = void (*)(CLI::App& root);

/// Registers `installer` to run when the CLI is built; returns true so a file can write
/// `const bool kRegistered = RegisterCommands(&AddMyCommands);`.
bool RegisterCommands(CommandInstaller installer);

/// Runs every registered installer on `root`.
void InstallCommands(CLI::App& root);

/// Exit codes shared by every subcommand.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailed = 1;    ///< ran, but an expectation or check failed
inline constexpr int kExitBadInput = 2;  ///< refused before running: bad arguments or files

}  // namespace graspbed::app

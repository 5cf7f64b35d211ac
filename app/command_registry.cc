#include "app/command_registry.h"

#include <vector>

namespace graspbed::app {
namespace {

std::vector<CommandInstaller>& Installers() {
  static std::vector<CommandInstaller> installers;
  return installers;
}

}  // namespace

bool RegisterCommands(CommandInstaller installer) {
  Installers().push_back(installer);
  return true;
}

void InstallCommands(CLI::App& root) {
  for (CommandInstaller installer : Installers()) installer(root);
}

}  // namespace graspbed::app

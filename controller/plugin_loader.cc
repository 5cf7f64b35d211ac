#include "controller/plugin_loader.h"

#include <dlfcn.h>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "common/config_error.h"
#include "common/data_dir.h"

namespace graspbed::controller {
namespace {

namespace fs = std::filesystem;

std::string LibraryOf(const std::string& plugin_name) { return plugin_name.substr(kPluginPrefix.size()); }

/// The library file for `library` (a path, or a bare name on the search path).
fs::path FindLibrary(const std::string& plugin_name) {
  const std::string library = LibraryOf(plugin_name);
  if (library.empty()) throw std::invalid_argument("controller '" + plugin_name + "': no library named");
  if (library.find('/') != std::string::npos) {
    if (!fs::is_regular_file(library)) {
      throw std::invalid_argument("controller plugin " + library + ": no such file");
    }
    return fs::absolute(library).lexically_normal();
  }
  std::vector<std::string> candidates = {library};
  if (library.find(".so") == std::string::npos) candidates.push_back("lib" + library + ".so");
  const std::vector<std::string> search_path = PluginSearchPath();
  for (const std::string& directory : search_path) {
    for (const std::string& candidate : candidates) {
      const fs::path path = fs::path(directory) / candidate;
      if (fs::is_regular_file(path)) return fs::absolute(path).lexically_normal();
    }
  }
  std::string searched;
  for (const std::string& directory : search_path) searched += (searched.empty() ? "" : ", ") + directory;
  throw std::invalid_argument(
      "controller plugin '" + library + "' not found (looked for " + candidates.front() +
      (candidates.size() > 1 ? " and " + candidates.back() : "") + " in " +
      (searched.empty() ? "no directory" : searched) + "; set GRASPBED_PLUGIN_PATH or give a path)");
}

void CheckParameters(const std::string& path, const std::vector<ControllerParameter>& parameters) {
  std::set<std::string> seen;
  for (const ControllerParameter& p : parameters) {
    std::ostringstream problem;
    if (p.name.empty()) {
      problem << "a parameter without a name";
    } else if (!seen.insert(p.name).second) {
      problem << "parameter " << p.name << " declared twice";
    } else if (!std::isfinite(p.default_value) || !(p.min <= p.default_value && p.default_value <= p.max)) {
      problem << "parameter " << p.name << " default " << p.default_value << " outside its range [" << p.min
              << ", " << p.max << "]";
    }
    if (!problem.str().empty()) {
      throw std::invalid_argument("controller plugin " + path + " declares " + problem.str());
    }
  }
}

LoadedPlugin Load(const fs::path& path) {
  const std::string where = "controller plugin " + path.string();
  // RTLD_LOCAL: two plugins may define the same symbols without clashing.
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* reason = dlerror();
    throw std::invalid_argument(where + ": cannot load: " + (reason != nullptr ? reason : "unknown reason"));
  }
  // Never dlclose'd: a controller made from it may outlive the caller, and its vtable lives here.
  void* symbol = dlsym(handle, GRASPBED_CONTROLLER_PLUGIN_SYMBOL);
  if (symbol == nullptr) {
    throw std::invalid_argument(where + ": not a graspbed controller plugin (exports no " +
                                GRASPBED_CONTROLLER_PLUGIN_SYMBOL +
                                "; define it with GRASPBED_CONTROLLER_PLUGIN)");
  }
  const auto entry = reinterpret_cast<GraspbedControllerPluginEntry>(symbol);
  const GraspbedControllerPlugin* descriptor = nullptr;
  try {
    descriptor = entry();
  } catch (...) {
    throw std::invalid_argument(where + ": " + GRASPBED_CONTROLLER_PLUGIN_SYMBOL + "() threw");
  }
  if (descriptor == nullptr) {
    throw std::invalid_argument(where + ": " + GRASPBED_CONTROLLER_PLUGIN_SYMBOL +
                                "() returned no descriptor");
  }
  // The version first: nothing else in the descriptor may be read if it differs.
  if (descriptor->api_version != GRASPBED_CONTROLLER_API_VERSION) {
    throw std::invalid_argument(where + ": built against controller API version " +
                                std::to_string(descriptor->api_version) + ", this graspbed has version " +
                                std::to_string(GRASPBED_CONTROLLER_API_VERSION) +
                                "; rebuild the plugin against this graspbed's headers");
  }
  if (descriptor->name == nullptr || descriptor->name[0] == '\0' || descriptor->parameters == nullptr ||
      descriptor->make == nullptr) {
    throw std::invalid_argument(where + ": incomplete descriptor (name, parameters and make are required)");
  }
  LoadedPlugin plugin;
  plugin.path = path.string();
  plugin.name = descriptor->name;
  plugin.descriptor = descriptor;
  try {
    plugin.parameters = descriptor->parameters();
  } catch (const std::exception& error) {
    throw std::invalid_argument(where + ": parameters() threw: " + error.what());
  } catch (...) {
    throw std::invalid_argument(where + ": parameters() threw");
  }
  CheckParameters(plugin.path, plugin.parameters);
  return plugin;
}

}  // namespace

bool IsPluginName(const std::string& name) { return name.starts_with(kPluginPrefix); }

std::string ResolvePluginName(const std::string& name, const std::string& base_dir) {
  if (!IsPluginName(name)) return name;
  const std::string library = LibraryOf(name);
  if (library.find('/') == std::string::npos || fs::path(library).is_absolute()) return name;
  return std::string(kPluginPrefix) +
         (fs::absolute(base_dir.empty() ? "." : base_dir) / library).lexically_normal().string();
}

std::vector<std::string> PluginSearchPath() {
  std::vector<std::string> directories;
  if (const char* env = std::getenv("GRASPBED_PLUGIN_PATH"); env != nullptr) {
    std::stringstream list(env);
    for (std::string directory; std::getline(list, directory, ':');) {
      if (!directory.empty()) directories.push_back(directory);
    }
  }
  // <prefix>/share/graspbed -> <prefix>/lib/graspbed/plugins (the build tree has no plugins there).
  try {
    directories.push_back(
        (fs::path(common::DataDir()).parent_path().parent_path() / "lib" / "graspbed" / "plugins").string());
  } catch (const std::exception&) {
    // No data directory: only $GRASPBED_PLUGIN_PATH.
  }
  return directories;
}

const LoadedPlugin& LoadPlugin(const std::string& plugin_name) {
  static std::mutex mutex;
  static std::map<std::string, LoadedPlugin> loaded;  // by absolute path; entries never removed
  const fs::path path = FindLibrary(plugin_name);
  std::lock_guard<std::mutex> lock(mutex);
  if (auto found = loaded.find(path.string()); found != loaded.end()) return found->second;
  return loaded.emplace(path.string(), Load(path)).first->second;
}

std::unique_ptr<GraspController> MakePluginController(const LoadedPlugin& plugin,
                                                      const ControllerParams& params) {
  const std::string where = "controller plugin " + plugin.path + " ('" + plugin.name + "')";
  std::unique_ptr<GraspController> controller;
  try {
    controller = plugin.descriptor->make(params);
  } catch (const ParameterError& error) {
    throw common::ConfigError("", 0, error.parameter(), common::ReadableNumber(error.value()), error.reason())
        .WithContext(where);
  } catch (const std::exception& error) {
    throw std::invalid_argument(where + ": " + error.what());
  } catch (...) {
    throw std::invalid_argument(where + ": make() threw a non-standard exception");
  }
  if (controller == nullptr) throw std::invalid_argument(where + ": make() returned no controller");
  return controller;
}

}  // namespace graspbed::controller

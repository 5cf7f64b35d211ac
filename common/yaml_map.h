#pragma once
/// Strict reading of YAML configuration files: typed values with range checks and error messages
/// that name the file, the line, the key and the value ("scenarios/lift.yaml:12: object.mass = -0.1:
/// must be > 0"), and detection of keys nobody read (typos).

#include <yaml-cpp/yaml.h>

#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/config_error.h"

namespace graspbed::common {

/// Inclusive/exclusive bounds for a numeric value; the one rule loading and validating both apply.
struct NumberRule {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;  ///< true: value must be > min, not >= min
  bool max_exclusive = false;  ///< true: value must be < max, not <= max
  static NumberRule Positive() { return {0.0, std::numeric_limits<double>::infinity(), true}; }
  static NumberRule NonNegative() { return {0.0, std::numeric_limits<double>::infinity(), false}; }
  static NumberRule Between(double lo, double hi) { return {lo, hi, false}; }
  /// "" when `value` is finite and within the bounds, else why not ("must be > 0").
  std::string Check(double value) const;
};

/// One YAML mapping read strictly. Every Get/Require marks its key as used; RejectUnknownKeys()
/// then refuses any key that was never asked for, listing the valid ones.
class YamlMap {
 public:
  /// Parses `path`; a missing file or a syntax error throws ConfigError naming the file and line.
  static YamlMap LoadFile(const std::string& path);
  /// Parses YAML text; `source_name` stands for the file name in messages.
  static YamlMap LoadString(const std::string& text, const std::string& source_name);

  /// Wraps `node` (must be a map or null) found in `file` under dotted key path `prefix`.
  YamlMap(YAML::Node node, std::string file, std::string prefix);

  bool Has(std::string_view key) const;
  /// Keys present in this map, in file order.
  std::vector<std::string> Keys() const;

  double GetNumber(std::string_view key, double fallback, NumberRule rule = {}) const;
  double RequireNumber(std::string_view key, NumberRule rule = {}) const;
  int GetInt(std::string_view key, int fallback, int min = std::numeric_limits<int>::min(),
             int max = std::numeric_limits<int>::max()) const;
  int RequireInt(std::string_view key, int min = std::numeric_limits<int>::min(),
                 int max = std::numeric_limits<int>::max()) const;
  bool GetBool(std::string_view key, bool fallback) const;
  /// A string value; when `allowed` is non-empty the value must be one of them (listed on error).
  std::string GetString(std::string_view key, std::string fallback,
                        const std::vector<std::string>& allowed = {}) const;
  std::string RequireString(std::string_view key, const std::vector<std::string>& allowed = {}) const;
  /// A list of numbers, optionally of exactly `expected_size` entries (0 = any size).
  std::vector<double> GetNumberList(std::string_view key, std::vector<double> fallback,
                                    size_t expected_size = 0, NumberRule rule = {}) const;

  /// A nested mapping (required / optional).
  YamlMap RequireMap(std::string_view key) const;
  std::optional<YamlMap> GetMap(std::string_view key) const;
  /// A sequence of mappings (empty when the key is absent).
  std::vector<YamlMap> GetMapList(std::string_view key) const;
  /// The raw node for `key` (marks it used); invalid node when absent.
  YAML::Node Raw(std::string_view key) const;

  /// Throws ConfigError for the first key that no Get/Require asked for, naming the valid keys.
  void RejectUnknownKeys(const std::vector<std::string>& also_valid = {}) const;

  /// Throws ConfigError "file:line: prefix.key = value: message" for `key` of this map.
  [[noreturn]] void Fail(std::string_view key, std::string_view message) const;
  /// Throws ConfigError "file:line: prefix: message" about the map itself.
  [[noreturn]] void FailHere(std::string_view message) const;
  /// Throws `error` (a check's, its key a dotted path relative to this map, e.g. "motor.armature_kg"
  /// or "size_m[2]") located in this file: at the line of that key and with the value as the file
  /// spells it when the file sets it, else at the line of the nearest enclosing map the file has
  /// (none for the document itself) with the error's own value marked "(default)".
  [[noreturn]] void FailAt(const ConfigError& error) const;

  const std::string& file() const { return file_; }
  /// Dotted path of this map from the document root ("" at the root).
  const std::string& prefix() const { return prefix_; }
  /// 1-based line of this map in its file (0 when unknown).
  int line() const;
  const YAML::Node& node() const { return node_; }

 private:
  YAML::Node Lookup(std::string_view key) const;
  std::string FullKey(std::string_view key) const;

  YAML::Node node_;
  std::string file_;
  std::string prefix_;
  mutable std::vector<std::string> used_keys_;
};

/// "file:line: " for a node (line 1-based), or "file: " when the node carries no position.
std::string Where(const std::string& file, const YAML::Node& node);

}  // namespace graspbed::common

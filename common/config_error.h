#pragma once
/// The one error type for bad configuration input (files, --set overrides, command-line values,
/// configs built in code): where it is (file, line), what (key path, value) and why, as data, so a
/// caller can add context or blame another key without parsing text. app/main.cc turns every
/// ConfigError (as every std::invalid_argument) into one line on stderr and exit code 2.

#include <optional>
#include <stdexcept>
#include <string>

namespace graspbed::common {

/// Bad input in a configuration. what() is one line,
/// "[context: ][file[:line]: ][key[ = value]: ]message", e.g.
/// "scenarios/lift.yaml:12: object.mass_kg = -0.1: must be >= 0.001"; the parts that are unknown
/// (empty file, line 0, empty key, no value) are left out.
class ConfigError : public std::invalid_argument {
 public:
  /// Everything known about the error. `line` is 1-based (0 = unknown); `value` is the offending
  /// value as the input spelled it (nullopt: none, e.g. an unknown key; "null" for a missing one).
  ConfigError(std::string file, int line, std::string key, std::optional<std::string> value,
              std::string message);
  /// An error whose only datum is its message (no file, line or key known).
  explicit ConfigError(const std::string& message);

  const std::string& file() const { return file_; }
  int line() const { return line_; }
  /// Dotted key path ("object.mass_kg", "script[2].at_s"); "" when the error is about no key.
  const std::string& key() const { return key_; }
  const std::optional<std::string>& value() const { return value_; }
  /// The reason alone ("must be > 0").
  const std::string& message() const { return message_; }
  /// Text in front of everything else ("--set object.mass_kg=-1"); "" when none.
  const std::string& context() const { return context_; }

  /// The same error with `prefix` + "." in front of its key (a section naming its parent).
  ConfigError WithKeyPrefix(const std::string& prefix) const;
  /// The same error located in `file` at `line` (a config built from a file, validated later).
  ConfigError WithLocation(const std::string& file, int line) const;
  /// The same error with `context` + ": " in front of what().
  ConfigError WithContext(const std::string& context) const;

 private:
  ConfigError(std::string file, int line, std::string key, std::optional<std::string> value,
              std::string message, std::string context);

  std::string file_;
  int line_ = 0;
  std::string key_;
  std::optional<std::string> value_;
  std::string message_;
  std::string context_;
};

/// Throws ConfigError("", 0, key, ReadableNumber(value), message) unless `ok`: the one check helper
/// for values built in code (constructor arguments, configs assembled without a file).
void Require(bool ok, const std::string& key, double value, const std::string& message);

/// Shortest text that reads back to exactly `value`, plain unless an exponent saves more than two
/// characters ("0.0001", "20000", "1e6", "5.5e-4"; "nan", "inf"): values in messages and docs.
std::string ReadableNumber(double value);

/// Shortest text that reads back to exactly `value` (".inf", "-.inf", ".nan" as YAML spells them).
std::string FormatNumber(double value);

}  // namespace graspbed::common

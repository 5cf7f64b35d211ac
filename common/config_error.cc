#include "common/config_error.h"

#include <charconv>
#include <cmath>

namespace graspbed::common {
namespace {

std::string Format(const std::string& context, const std::string& file, int line, const std::string& key,
                   const std::optional<std::string>& value, const std::string& message) {
  std::string text;
  if (!context.empty()) text.append(context).append(": ");
  if (!file.empty()) {
    text.append(file);
    if (line > 0) text.append(":").append(std::to_string(line));
    text.append(": ");
  }
  if (!key.empty()) {
    text.append(key);
    if (value) text.append(" = ").append(*value);
    text.append(": ");
  }
  return text.append(message);
}

}  // namespace

ConfigError::ConfigError(std::string file, int line, std::string key, std::optional<std::string> value,
                         std::string message, std::string context)
    : std::invalid_argument(Format(context, file, line, key, value, message)),
      file_(std::move(file)),
      line_(line),
      key_(std::move(key)),
      value_(std::move(value)),
      message_(std::move(message)),
      context_(std::move(context)) {}

ConfigError::ConfigError(std::string file, int line, std::string key, std::optional<std::string> value,
                         std::string message)
    : ConfigError(std::move(file), line, std::move(key), std::move(value), std::move(message), "") {}

ConfigError::ConfigError(const std::string& message) : ConfigError("", 0, "", std::nullopt, message, "") {}

ConfigError ConfigError::WithKeyPrefix(const std::string& prefix) const {
  const std::string key = prefix.empty() ? key_ : key_.empty() ? prefix : prefix + "." + key_;
  return ConfigError(file_, line_, key, value_, message_, context_);
}

ConfigError ConfigError::WithLocation(const std::string& file, int line) const {
  return ConfigError(file, line, key_, value_, message_, context_);
}

ConfigError ConfigError::WithContext(const std::string& context) const {
  return ConfigError(file_, line_, key_, value_, message_,
                     context_.empty() ? context : context + ": " + context_);
}

void Require(bool ok, const std::string& key, double value, const std::string& message) {
  if (!ok) throw ConfigError("", 0, key, ReadableNumber(value), message);
}

std::string ReadableNumber(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  // The shortest exact text: plain unless an exponent saves more than two characters ("0.0005",
  // "20000", "-0.0999"; "1e6", "1e-10").
  char buffer[64];
  const auto fixed = std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::fixed);
  const std::string plain(buffer, fixed.ptr);
  const auto scientific =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::scientific);
  std::string text(buffer, scientific.ptr);
  const size_t e = text.find('e');
  std::string exponent = text.substr(e + 1);
  const bool negative = exponent[0] == '-';
  exponent = exponent.substr(1);  // to_chars always writes the exponent's sign
  while (exponent.size() > 1 && exponent[0] == '0') exponent = exponent.substr(1);
  text = text.substr(0, e) + "e" + (negative ? "-" : "") + exponent;
  return plain.size() <= text.size() + 2 ? plain : text;
}

std::string FormatNumber(double value) {
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  if (std::isnan(value)) return ".nan";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

}  // namespace graspbed::common

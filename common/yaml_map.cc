#include "common/yaml_map.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

namespace graspbed::common {
namespace {

std::string Scalar(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  if (node.IsScalar()) return node.Scalar();
  if (node.IsSequence()) return "[...]";
  return "{...}";
}

// A bound as messages have always written it (6 significant digits: "1e+06", "0.001").
std::string FormatBound(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

int LineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.IsDefined() ? node.Mark() : YAML::Mark::null_mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

std::string Join(const std::vector<std::string>& items) {
  std::string joined;
  for (const auto& item : items) joined += (joined.empty() ? "" : ", ") + item;
  return joined;
}

}  // namespace

std::string NumberRule::Check(double value) const {
  if (!std::isfinite(value)) return "must be a finite number";
  if (min_exclusive ? !(value > min) : !(value >= min)) {
    return std::string("must be ") + (min_exclusive ? "> " : ">= ") + FormatBound(min);
  }
  if (max_exclusive ? !(value < max) : !(value <= max)) {
    return std::string("must be ") + (max_exclusive ? "< " : "<= ") + FormatBound(max);
  }
  return "";
}

std::string Where(const std::string& file, const YAML::Node& node) {
  const YAML::Mark mark = node.IsDefined() ? node.Mark() : YAML::Mark::null_mark();
  if (mark.is_null()) return file + ": ";
  return file + ":" + std::to_string(mark.line + 1) + ": ";
}

YamlMap YamlMap::LoadFile(const std::string& path) {
  std::ifstream stream(path);
  if (!stream) throw ConfigError(path, 0, "", std::nullopt, "cannot open file");
  std::stringstream text;
  text << stream.rdbuf();
  return LoadString(text.str(), path);
}

YamlMap YamlMap::LoadString(const std::string& text, const std::string& source_name) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& error) {
    throw ConfigError(source_name, error.mark.line + 1, "", std::nullopt, "YAML syntax error: " + error.msg);
  }
  if (!root.IsNull() && !root.IsMap()) {
    throw ConfigError(source_name, LineOf(root), "", std::nullopt,
                      "expected a mapping of keys at the top level");
  }
  return YamlMap(root, source_name, "");
}

YamlMap::YamlMap(YAML::Node node, std::string file, std::string prefix)
    : node_(std::move(node)), file_(std::move(file)), prefix_(std::move(prefix)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    throw ConfigError(file_, LineOf(node_), prefix_, Scalar(node_), "expected a mapping");
  }
}

int YamlMap::line() const {
  const YAML::Mark mark = node_.IsDefined() ? node_.Mark() : YAML::Mark::null_mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

std::string YamlMap::FullKey(std::string_view key) const {
  return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
}

YAML::Node YamlMap::Lookup(std::string_view key) const {
  used_keys_.emplace_back(key);
  if (!node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  for (const auto& entry : node_) {
    if (entry.first.Scalar() == key) return entry.second;
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

bool YamlMap::Has(std::string_view key) const {
  if (!node_.IsMap()) return false;
  for (const auto& entry : node_) {
    if (entry.first.Scalar() == key) return true;
  }
  return false;
}

std::vector<std::string> YamlMap::Keys() const {
  std::vector<std::string> keys;
  if (!node_.IsMap()) return keys;
  for (const auto& entry : node_) keys.push_back(entry.first.Scalar());
  return keys;
}

void YamlMap::Fail(std::string_view key, std::string_view message) const {
  YAML::Node value;
  if (node_.IsMap()) {
    for (const auto& entry : node_) {
      if (entry.first.Scalar() == key) value = entry.second;
    }
  }
  const YAML::Node& position = value.IsDefined() && !value.IsNull() ? value : node_;
  throw ConfigError(file_, LineOf(position), FullKey(key), Scalar(value), std::string(message));
}

void YamlMap::FailHere(std::string_view message) const {
  throw ConfigError(file_, LineOf(node_), prefix_.empty() ? "(top level)" : prefix_, std::nullopt,
                    std::string(message));
}

namespace {

// Parses one scalar number at `node`; errors name `full_key` and the node's own line.
double ParseNumber(const std::string& file, const std::string& full_key, const YAML::Node& node,
                   const NumberRule& rule) {
  const auto fail = [&](const std::string& reason) {
    throw ConfigError(file, LineOf(node), full_key, Scalar(node), reason);
  };
  if (!node.IsScalar()) fail("expected a number");
  double number = 0.0;
  size_t consumed = 0;
  try {
    number = std::stod(node.Scalar(), &consumed);
  } catch (const std::logic_error&) {
    fail("expected a number");
  }
  if (consumed != node.Scalar().size()) fail("expected a number");
  const std::string failure = rule.Check(number);
  if (!failure.empty()) fail(failure);
  return number;
}

}  // namespace

double YamlMap::GetNumber(std::string_view key, double fallback, NumberRule rule) const {
  const YAML::Node value = Lookup(key);
  if (!value.IsDefined() || value.IsNull()) return fallback;
  return ParseNumber(file_, FullKey(key), value, rule);
}

double YamlMap::RequireNumber(std::string_view key, NumberRule rule) const {
  const YAML::Node value = Lookup(key);
  if (!value.IsDefined() || value.IsNull()) Fail(key, "missing required key");
  return ParseNumber(file_, FullKey(key), value, rule);
}

int YamlMap::GetInt(std::string_view key, int fallback, int min, int max) const {
  if (!Has(key)) {
    used_keys_.emplace_back(key);
    return fallback;
  }
  return RequireInt(key, min, max);
}

int YamlMap::RequireInt(std::string_view key, int min, int max) const {
  const double number = RequireNumber(key, NumberRule::Between(min, max));
  if (number != std::floor(number)) Fail(key, "expected a whole number");
  return static_cast<int>(number);
}

bool YamlMap::GetBool(std::string_view key, bool fallback) const {
  const YAML::Node value = Lookup(key);
  if (!value.IsDefined() || value.IsNull()) return fallback;
  if (!value.IsScalar()) Fail(key, "expected true or false");
  const std::string& text = value.Scalar();
  if (text == "true" || text == "yes" || text == "on") return true;
  if (text == "false" || text == "no" || text == "off") return false;
  Fail(key, "expected true or false");
}

std::string YamlMap::GetString(std::string_view key, std::string fallback,
                               const std::vector<std::string>& allowed) const {
  if (!Has(key)) {
    used_keys_.emplace_back(key);
    return fallback;
  }
  return RequireString(key, allowed);
}

std::string YamlMap::RequireString(std::string_view key, const std::vector<std::string>& allowed) const {
  const YAML::Node value = Lookup(key);
  if (!value.IsDefined() || value.IsNull()) Fail(key, "missing required key");
  if (!value.IsScalar()) Fail(key, "expected a string");
  if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), value.Scalar()) == allowed.end()) {
    Fail(key, "unknown name; valid names: " + Join(allowed));
  }
  return value.Scalar();
}

std::vector<double> YamlMap::GetNumberList(std::string_view key, std::vector<double> fallback,
                                           size_t expected_size, NumberRule rule) const {
  const YAML::Node value = Lookup(key);
  if (!value.IsDefined() || value.IsNull()) return fallback;
  if (!value.IsSequence()) Fail(key, "expected a list of numbers");
  if (expected_size != 0 && value.size() != expected_size) {
    Fail(key, "expected " + std::to_string(expected_size) + " numbers, got " + std::to_string(value.size()));
  }
  std::vector<double> numbers;
  for (size_t i = 0; i < value.size(); ++i) {
    numbers.push_back(ParseNumber(file_, FullKey(key) + "[" + std::to_string(i) + "]", value[i], rule));
  }
  return numbers;
}

YamlMap YamlMap::RequireMap(std::string_view key) const {
  const YAML::Node value = Lookup(key);
  if (!value.IsDefined() || value.IsNull()) Fail(key, "missing required section");
  if (!value.IsMap()) Fail(key, "expected a mapping of keys");
  return YamlMap(value, file_, FullKey(key));
}

std::optional<YamlMap> YamlMap::GetMap(std::string_view key) const {
  const YAML::Node value = Lookup(key);
  if (!value.IsDefined() || value.IsNull()) return std::nullopt;
  if (!value.IsMap()) Fail(key, "expected a mapping of keys");
  return YamlMap(value, file_, FullKey(key));
}

std::vector<YamlMap> YamlMap::GetMapList(std::string_view key) const {
  const YAML::Node value = Lookup(key);
  std::vector<YamlMap> maps;
  if (!value.IsDefined() || value.IsNull()) return maps;
  if (!value.IsSequence()) Fail(key, "expected a list");
  for (size_t i = 0; i < value.size(); ++i) {
    const std::string element_key = FullKey(key) + "[" + std::to_string(i) + "]";
    if (!value[i].IsMap()) {
      throw ConfigError(file_, LineOf(value[i]), element_key, Scalar(value[i]), "expected a mapping of keys");
    }
    maps.emplace_back(value[i], file_, element_key);
  }
  return maps;
}

YAML::Node YamlMap::Raw(std::string_view key) const { return Lookup(key); }

void YamlMap::FailAt(const ConfigError& error) const {
  // Walk the key path ("motor.armature_kg", "size_m[2]") through the nested maps and lists as far
  // as the file goes. Handles are rebound with reset(): yaml-cpp's operator= would overwrite the
  // node a handle points at.
  YAML::Node node;
  node.reset(node_);
  YAML::Node deepest_map;
  deepest_map.reset(node_);
  bool complete = true;
  std::string path = error.key();
  while (!path.empty() && complete) {
    const size_t end = path.find_first_of(".[");
    const std::string step = path.substr(0, end);
    path = end == std::string::npos ? "" : path.substr(end);
    YAML::Node next;
    bool have_next = false;
    if (step.empty() || !node.IsMap()) {
      complete = false;
      break;
    }
    for (const auto& entry : node) {
      if (entry.first.Scalar() == step) {
        next.reset(entry.second);
        have_next = true;
      }
    }
    while (have_next && !path.empty() && path[0] == '[') {
      const size_t close = path.find(']');
      const std::string digits = close == std::string::npos ? "" : path.substr(1, close - 1);
      if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) {
        have_next = false;  // "units[]": no index to follow
        break;
      }
      const size_t index = std::stoul(digits);
      path = path.substr(close + 1);
      if (!next.IsSequence() || index >= next.size()) {
        have_next = false;
        break;
      }
      const YAML::Node list = next;
      next.reset(list[index]);
    }
    if (!path.empty() && path[0] == '.') path = path.substr(1);
    if (!have_next || !next.IsDefined() || next.IsNull()) {
      complete = false;
      break;
    }
    node.reset(next);
    if (node.IsMap()) deepest_map.reset(node);
  }
  const std::string key = FullKey(error.key());
  if (complete && !error.key().empty())
    throw ConfigError(file_, LineOf(node), key, Scalar(node), error.message());
  // Not in the file: the value in use is a default (the struct's, a profile's). Point at the
  // section that holds the key, or at no line when that is the document itself.
  const bool at_top = deepest_map.is(node_) && prefix_.empty();
  const std::optional<std::string> value =
      error.value() ? std::optional<std::string>(*error.value() + " (default)") : std::nullopt;
  throw ConfigError(file_, at_top ? 0 : LineOf(deepest_map), key, value, error.message());
}

void YamlMap::RejectUnknownKeys(const std::vector<std::string>& also_valid) const {
  if (!node_.IsMap()) return;
  std::vector<std::string> valid = used_keys_;
  valid.insert(valid.end(), also_valid.begin(), also_valid.end());
  std::sort(valid.begin(), valid.end());
  valid.erase(std::unique(valid.begin(), valid.end()), valid.end());
  for (const auto& entry : node_) {
    const std::string& key = entry.first.Scalar();
    if (std::find(valid.begin(), valid.end(), key) == valid.end()) {
      throw ConfigError(file_, LineOf(entry.first), FullKey(key), std::nullopt,
                        "unknown key; valid keys: " + Join(valid));
    }
  }
}

}  // namespace graspbed::common

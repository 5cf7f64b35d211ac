#include "common/field_table.h"

namespace graspbed::common {

std::string DocNumber(double value) { return std::isnan(value) ? "auto" : ReadableNumber(value); }

std::string DescribeRule(const NumberRule& rule) {
  const bool has_min = std::isfinite(rule.min);
  const bool has_max = std::isfinite(rule.max);
  if (has_min && has_max && !rule.min_exclusive && !rule.max_exclusive) {
    return DocNumber(rule.min) + " .. " + DocNumber(rule.max);
  }
  std::string text;
  if (has_min) text = (rule.min_exclusive ? "> " : ">= ") + DocNumber(rule.min);
  if (has_max)
    text += (text.empty() ? "" : ", ") + std::string(rule.max_exclusive ? "< " : "<= ") + DocNumber(rule.max);
  return text.empty() ? "any" : text;
}

std::string ReferenceMarkdown(const std::vector<FieldReference>& rows) {
  std::string text = "| key | unit | default | allowed | meaning |\n|---|---|---|---|---|\n";
  for (const FieldReference& row : rows) {
    text += "| `" + row.key + "` | " + row.unit + " | " + row.default_value + " | " + row.allowed + " | " +
            row.doc + " |\n";
  }
  return text;
}

void FieldError(const std::string& key, double value, const std::string& message) {
  throw ConfigError("", 0, key, ReadableNumber(value), message);
}

}  // namespace graspbed::common

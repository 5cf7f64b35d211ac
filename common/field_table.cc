#include "common/field_table.h"

#include <charconv>

namespace graspbed::common {

std::string DocNumber(double value) {
  if (std::isnan(value)) return "auto";
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
  throw ConfigError("", 0, key, FormatNumber(value), message);
}

}  // namespace graspbed::common

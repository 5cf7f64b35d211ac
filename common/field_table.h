#pragma once
/// One field table per config struct, from which its YAML loader, its Validate(), its YAML emitter
/// (the run's config.yaml) and its reference table in docs/ all derive, so the four cannot drift
/// apart (Drake's Serialize(Archive*) idea). A table lists each field once: its key, the member it
/// binds, its rule (range, names), its unit and a one-line doc. Cross-field rules a table cannot
/// say field by field (open_circuit_ohm > short_circuit_ohm) are one function of the table, run
/// by loading and by validating alike.
///
/// A table is built once (a function-local static beside its struct, e.g.
/// sensor::ReadoutConfigFields()) and only read afterwards; none of its functions is on a
/// per-step path.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/config_error.h"
#include "common/yaml_map.h"

namespace graspbed::common {

/// One row of a config's reference table (docs/, `graspbed config-reference`).
struct FieldReference {
  std::string key;            ///< dotted path below the table's own section ("motor.armature_kg")
  std::string unit;           ///< "" when the value has none
  std::string default_value;  ///< the struct's in-class default, as docs write it
  std::string allowed;        ///< the rule in words ("0 .. 0.3", "> 0, <= 1e7", "`box`, `sphere`")
  std::string doc;            ///< what the field means
};

/// A number as docs write it: ReadableNumber, NaN as "auto".
std::string DocNumber(double value);
/// `rule` in words for a reference table ("0 .. 1", "> 0, <= 1000", ">= 0", "any").
std::string DescribeRule(const NumberRule& rule);
/// Markdown table (key, unit, default, allowed, meaning) of `rows`, one row each.
std::string ReferenceMarkdown(const std::vector<FieldReference>& rows);

/// The fields of `Struct`, their rules and its cross-field checks. See the file comment.
template <typename Struct>
class FieldTable {
 public:
  enum class Type {
    kNumber,
    kInteger,
    kBool,
    kText,
    kNumberArray,
    kSection,
    kCustom,
    kOptionalNumber,
    kOptionalBool
  };

  /// One field. Built by the static functions below (Number, Integer, ...), refined by the
  /// chainable setters.
  struct Field {
    std::string key;
    Type type = Type::kNumber;
    NumberRule rule;  ///< kNumber, kInteger, and each entry of a kNumberArray
    std::string unit;
    std::string doc;
    std::string note;  ///< appended to the reference's "allowed" (cross-field rules); all of it for "any"
    bool nan_is_auto = false;        ///< NaN (an entry of) means "derived at run time"
    std::vector<std::string> names;  ///< kText: the allowed names (empty: any text)
    std::string custom_default;      ///< kCustom: the default as docs write it
    std::string custom_allowed;      ///< kCustom: what is allowed, in words
    std::function<double*(Struct*)> number;
    std::function<int*(Struct*)> integer;
    std::function<bool*(Struct*)> boolean;
    std::function<std::string(const Struct&)> get_text;
    std::function<void(Struct*, const std::string&)> set_text;
    std::function<std::span<double>(Struct*)> array;
    std::function<std::optional<double>*(Struct*)> optional_number;
    std::function<std::optional<bool>*(Struct*)> optional_bool;
    std::function<void(const YamlMap&, Struct*)> load_section;
    std::function<void(const Struct&)> validate_section;  ///< throws ConfigError, keys relative
    std::function<void(const Struct&, YAML::Emitter&)> emit_section;
    /// The section's rows, its defaults those of the parent's member in `parent` (a parent may
    /// default its sections apart from their own defaults: FeaConfig's gauge.r1 is 0 .. 0.75 mm).
    std::function<std::vector<FieldReference>(const Struct&)> reference_section;

    /// NaN (in any entry) stands for "derived at run time": not checked, not written out, and
    /// documented as "auto" (the field's doc says from what).
    Field&& NanIsAuto() && {
      nan_is_auto = true;
      return std::move(*this);
    }
    /// Adds a cross-field rule to the reference's "allowed" text (the check itself is the table's).
    Field&& Note(std::string text) && {
      note = std::move(text);
      return std::move(*this);
    }
  };

  /// A number under `rule`; `unit` as docs write it ("N", "m/s", "-" for a ratio, "" for none).
  static Field Number(std::string key, double Struct::*member, NumberRule rule, std::string unit,
                      std::string doc) {
    Field field = Base(std::move(key), Type::kNumber, rule, std::move(unit), std::move(doc));
    field.number = [member](Struct* s) { return &(s->*member); };
    return field;
  }
  /// A number kept in a nested struct but read at this level (StrainModelConfig::nominal.r0_ohm).
  template <typename Sub>
  static Field Number(std::string key, Sub Struct::*outer, double Sub::*inner, NumberRule rule,
                      std::string unit, std::string doc) {
    Field field = Base(std::move(key), Type::kNumber, rule, std::move(unit), std::move(doc));
    field.number = [outer, inner](Struct* s) { return &((s->*outer).*inner); };
    return field;
  }
  /// A whole number in [min, max].
  static Field Integer(std::string key, int Struct::*member, int min, int max, std::string unit,
                       std::string doc) {
    Field field =
        Base(std::move(key), Type::kInteger, NumberRule::Between(min, max), std::move(unit), std::move(doc));
    field.integer = [member](Struct* s) { return &(s->*member); };
    return field;
  }
  /// true / false (also yes / no, on / off in files).
  static Field Bool(std::string key, bool Struct::*member, std::string doc) {
    Field field = Base(std::move(key), Type::kBool, {}, "", std::move(doc));
    field.boolean = [member](Struct* s) { return &(s->*member); };
    return field;
  }
  /// Free text, or one of `names` when that is not empty.
  static Field Text(std::string key, std::string Struct::*member, std::vector<std::string> names,
                    std::string doc) {
    Field field = Base(std::move(key), Type::kText, {}, "", std::move(doc));
    field.names = std::move(names);
    field.get_text = [member](const Struct& s) { return s.*member; };
    field.set_text = [member](Struct* s, const std::string& text) { s->*member = text; };
    return field;
  }
  /// A number that may be absent (nullopt: not set, e.g. a check that is not made).
  static Field OptionalNumber(std::string key, std::optional<double> Struct::*member, NumberRule rule,
                              std::string unit, std::string doc) {
    Field field = Base(std::move(key), Type::kOptionalNumber, rule, std::move(unit), std::move(doc));
    field.optional_number = [member](Struct* s) { return &(s->*member); };
    return field;
  }
  /// A flag that may be absent.
  static Field OptionalBool(std::string key, std::optional<bool> Struct::*member, std::string doc) {
    Field field = Base(std::move(key), Type::kOptionalBool, {}, "", std::move(doc));
    field.optional_bool = [member](Struct* s) { return &(s->*member); };
    return field;
  }
  /// An enum written by name: `names` pairs every value with its name in files.
  template <typename Enum>
  static Field Choice(std::string key, Enum Struct::*member, std::vector<std::pair<Enum, std::string>> names,
                      std::string doc) {
    Field field = Base(std::move(key), Type::kText, {}, "", std::move(doc));
    for (const auto& entry : names) field.names.push_back(entry.second);
    field.get_text = [member, names](const Struct& s) {
      for (const auto& [value, name] : names) {
        if (value == s.*member) return name;
      }
      return std::string("?");
    };
    field.set_text = [member, names](Struct* s, const std::string& text) {
      for (const auto& [value, name] : names) {
        if (name == text) s->*member = value;
      }
    };
    return field;
  }
  /// Exactly N numbers, each under `rule`.
  template <size_t N>
  static Field Numbers(std::string key, std::array<double, N> Struct::*member, NumberRule rule,
                       std::string unit, std::string doc) {
    Field field = Base(std::move(key), Type::kNumberArray, rule, std::move(unit), std::move(doc));
    field.array = [member](Struct* s) { return std::span<double>((s->*member).data(), N); };
    return field;
  }
  /// A nested struct with its own table, read from a nested map under `key`.
  template <typename Sub>
  static Field Section(std::string key, Sub Struct::*member, const FieldTable<Sub>& table) {
    Field field = Base(std::move(key), Type::kSection, {}, "", "");
    const FieldTable<Sub>* sub = &table;
    field.load_section = [member, sub](const YamlMap& map, Struct* s) { sub->Load(map, &(s->*member)); };
    field.validate_section = [member, sub](const Struct& s) { sub->ValidateRelative(s.*member); };
    field.emit_section = [member, sub](const Struct& s, YAML::Emitter& out) { sub->Emit(s.*member, out); };
    field.reference_section = [member, sub](const Struct& parent) { return sub->Reference(parent.*member); };
    return field;
  }
  /// A key the struct's own loader reads (a list whose bounds depend on the layout, a path):
  /// listed in the reference and accepted by Load, but loaded, checked and written by hand.
  static Field Custom(std::string key, std::string unit, std::string default_value, std::string allowed,
                      std::string doc) {
    Field field = Base(std::move(key), Type::kCustom, {}, std::move(unit), std::move(doc));
    field.custom_default = std::move(default_value);
    field.custom_allowed = std::move(allowed);
    return field;
  }

  /// `name` prefixes the keys in Validate()'s errors ("readout" -> "readout.baseline_frames").
  /// `cross_checks` (may be empty) throws ConfigError with the key of the field it blames,
  /// relative to this struct (FieldError below).
  FieldTable(std::string name, std::vector<Field> fields,
             std::function<void(const Struct&)> cross_checks = nullptr)
      : name_(std::move(name)), fields_(std::move(fields)), cross_checks_(std::move(cross_checks)) {}

  const std::string& name() const { return name_; }
  const std::vector<Field>& fields() const { return fields_; }

  /// Sets every field `map` has (absent keys keep their value in `*config`), then refuses keys
  /// that are neither fields nor in `also_valid`, then runs the cross-field checks. Errors name
  /// the file, line, full key path and value.
  /// @throws ConfigError for a wrong type, a value outside its rule, an unknown key or a failed
  ///   cross-field check (at the key it blames, or at the map when the file does not set it).
  void Load(const YamlMap& map, Struct* config, const std::vector<std::string>& also_valid = {}) const {
    std::vector<std::string> valid = also_valid;
    for (const Field& field : fields_) LoadField(field, map, config, &valid);
    map.RejectUnknownKeys(valid);
    if (cross_checks_) {
      try {
        cross_checks_(*config);
      } catch (const ConfigError& error) {
        map.FailAt(error);
      }
    }
  }

  /// Checks every field against its rule and the cross-field rules.
  /// @throws ConfigError with key "name.field" and the value.
  void Validate(const Struct& config) const {
    try {
      ValidateRelative(config);
    } catch (const ConfigError& error) {
      throw error.WithKeyPrefix(name_);
    }
  }
  /// As Validate(), keys relative to this struct (for a parent's table).
  void ValidateRelative(const Struct& config) const {
    Struct& s = const_cast<Struct&>(config);  // the accessors only read here
    for (const Field& field : fields_) {
      switch (field.type) {
        case Type::kNumber: {
          const double value = *field.number(&s);
          if (field.nan_is_auto && std::isnan(value)) break;
          CheckNumber(field.key, value, field.rule);
          break;
        }
        case Type::kInteger:
          CheckNumber(field.key, *field.integer(&s), field.rule);
          break;
        case Type::kNumberArray: {
          const std::span<double> values = field.array(&s);
          for (size_t i = 0; i < values.size(); ++i) {
            if (field.nan_is_auto && std::isnan(values[i])) continue;
            CheckNumber(field.key + "[" + std::to_string(i) + "]", values[i], field.rule);
          }
          break;
        }
        case Type::kText:
          CheckText(field, field.get_text(config));
          break;
        case Type::kSection:
          try {
            field.validate_section(config);
          } catch (const ConfigError& error) {
            throw error.WithKeyPrefix(field.key);
          }
          break;
        case Type::kOptionalNumber: {
          const std::optional<double>& value = *field.optional_number(&s);
          if (value) CheckNumber(field.key, *value, field.rule);
          break;
        }
        case Type::kBool:
        case Type::kOptionalBool:
        case Type::kCustom:
          break;
      }
    }
    if (cross_checks_) cross_checks_(config);
  }

  /// Writes every field as key: value into the map `out` is in (the caller opens and closes it);
  /// auto (NaN) values and the keys in `skip` are left out, custom fields are the caller's.
  void Emit(const Struct& config, YAML::Emitter& out, const std::vector<std::string>& skip = {}) const {
    Struct& s = const_cast<Struct&>(config);  // the accessors only read here
    for (const Field& field : fields_) {
      if (std::find(skip.begin(), skip.end(), field.key) != skip.end()) continue;
      switch (field.type) {
        case Type::kNumber: {
          const double value = *field.number(&s);
          if (field.nan_is_auto && std::isnan(value)) break;
          out << YAML::Key << field.key << YAML::Value << FormatNumber(value);
          break;
        }
        case Type::kInteger:
          out << YAML::Key << field.key << YAML::Value << *field.integer(&s);
          break;
        case Type::kBool:
          out << YAML::Key << field.key << YAML::Value << *field.boolean(&s);
          break;
        case Type::kText:
          out << YAML::Key << field.key << YAML::Value << field.get_text(config);
          break;
        case Type::kNumberArray: {
          const std::span<double> values = field.array(&s);
          if (field.nan_is_auto &&
              std::any_of(values.begin(), values.end(), [](double v) { return std::isnan(v); }))
            break;
          out << YAML::Key << field.key << YAML::Value << YAML::Flow << YAML::BeginSeq;
          for (double value : values) out << FormatNumber(value);
          out << YAML::EndSeq;
          break;
        }
        case Type::kSection:
          out << YAML::Key << field.key << YAML::Value << YAML::BeginMap;
          field.emit_section(config, out);
          out << YAML::EndMap;
          break;
        case Type::kOptionalNumber:
          if (const std::optional<double>& value = *field.optional_number(&s)) {
            out << YAML::Key << field.key << YAML::Value << FormatNumber(*value);
          }
          break;
        case Type::kOptionalBool:
          if (const std::optional<bool>& value = *field.optional_bool(&s)) {
            out << YAML::Key << field.key << YAML::Value << *value;
          }
          break;
        case Type::kCustom:
          break;
      }
    }
  }

  /// `config` as a YAML mapping of its own (tests, tools).
  std::string EmitYaml(const Struct& config) const {
    YAML::Emitter out;
    out << YAML::BeginMap;
    Emit(config, out);
    out << YAML::EndMap;
    return std::string(out.c_str()) + "\n";
  }

  /// The reference rows of every field, sections' rows under "section.key". Defaults are those of
  /// `defaults_of`: a default-constructed Struct at the top, and for a section the member as its
  /// parent's defaults leave it (a parent may default a section apart from the section's own
  /// defaults: FeaConfig's gauge.r1 spans 0 .. 0.75 mm where a ResistorExtent{} spans 0 .. 0).
  std::vector<FieldReference> Reference(const Struct& defaults_of = Struct{}) const {
    Struct defaults = defaults_of;
    std::vector<FieldReference> rows;
    for (const Field& field : fields_) {
      FieldReference row{field.key, field.unit, "", "", field.doc};
      switch (field.type) {
        case Type::kNumber:
          row.default_value = DocNumber(*field.number(&defaults));
          row.allowed = DescribeRule(field.rule);
          break;
        case Type::kInteger:
          row.default_value = std::to_string(*field.integer(&defaults));
          row.allowed = DescribeRule(field.rule) + ", whole";
          break;
        case Type::kBool:
          row.default_value = *field.boolean(&defaults) ? "true" : "false";
          row.allowed = "true, false";
          break;
        case Type::kText: {
          const std::string text = field.get_text(defaults);
          row.default_value = text.empty() ? "\"\"" : "`" + text + "`";
          for (const std::string& name : field.names) {
            row.allowed += (row.allowed.empty() ? "`" : ", `") + name + "`";
          }
          if (row.allowed.empty()) row.allowed = "text";
          break;
        }
        case Type::kNumberArray: {
          const std::span<double> values = field.array(&defaults);
          row.default_value = "[";
          for (size_t i = 0; i < values.size(); ++i) {
            row.default_value += (i == 0 ? "" : ", ") + DocNumber(values[i]);
          }
          row.default_value += "]";
          row.allowed = std::to_string(values.size()) + " numbers, each " + DescribeRule(field.rule);
          break;
        }
        case Type::kSection:
          for (FieldReference sub : field.reference_section(defaults)) {
            sub.key = field.key + "." + sub.key;
            rows.push_back(std::move(sub));
          }
          continue;
        case Type::kCustom:
          row.default_value = field.custom_default;
          row.allowed = field.custom_allowed;
          break;
        case Type::kOptionalNumber: {
          const std::optional<double>& value = *field.optional_number(&defaults);
          row.default_value = value ? DocNumber(*value) : "none";
          row.allowed = DescribeRule(field.rule);
          break;
        }
        case Type::kOptionalBool: {
          const std::optional<bool>& value = *field.optional_bool(&defaults);
          row.default_value = value ? (*value ? "true" : "false") : "none";
          row.allowed = "true, false";
          break;
        }
      }
      // A field whose rule is the table's cross-check alone shows that rule, not "any".
      if (!field.note.empty()) row.allowed = row.allowed == "any" ? field.note : row.allowed + "; " + field.note;
      rows.push_back(std::move(row));
    }
    return rows;
  }

 private:
  static Field Base(std::string key, Type type, NumberRule rule, std::string unit, std::string doc) {
    Field field;
    field.key = std::move(key);
    field.type = type;
    field.rule = rule;
    field.unit = std::move(unit);
    field.doc = std::move(doc);
    return field;
  }

  static void CheckNumber(const std::string& key, double value, const NumberRule& rule) {
    const std::string failure = rule.Check(value);
    if (!failure.empty()) throw ConfigError("", 0, key, ReadableNumber(value), failure);
  }

  static void CheckText(const Field& field, const std::string& text) {
    if (field.names.empty() || std::find(field.names.begin(), field.names.end(), text) != field.names.end())
      return;
    std::string valid;
    for (const std::string& name : field.names) valid += (valid.empty() ? "" : ", ") + name;
    throw ConfigError("", 0, field.key, text, "unknown name; valid names: " + valid);
  }

  static void LoadField(const Field& field, const YamlMap& map, Struct* config,
                        std::vector<std::string>* valid) {
    switch (field.type) {
      case Type::kNumber: {
        double* value = field.number(config);
        *value = map.GetNumber(field.key, *value, field.rule);
        break;
      }
      case Type::kInteger: {
        int* value = field.integer(config);
        *value =
            map.GetInt(field.key, *value, static_cast<int>(field.rule.min), static_cast<int>(field.rule.max));
        break;
      }
      case Type::kBool: {
        bool* value = field.boolean(config);
        *value = map.GetBool(field.key, *value);
        break;
      }
      case Type::kText:
        field.set_text(config, map.GetString(field.key, field.get_text(*config), field.names));
        break;
      case Type::kNumberArray: {
        const std::span<double> values = field.array(config);
        const std::vector<double> loaded = map.GetNumberList(
            field.key, std::vector<double>(values.begin(), values.end()), values.size(), field.rule);
        std::copy(loaded.begin(), loaded.end(), values.begin());
        break;
      }
      case Type::kSection:
        if (auto sub = map.GetMap(field.key)) field.load_section(*sub, config);
        break;
      case Type::kOptionalNumber:
        if (map.Has(field.key)) {
          *field.optional_number(config) = map.GetNumber(field.key, 0.0, field.rule);
        } else {
          valid->push_back(field.key);
        }
        break;
      case Type::kOptionalBool:
        if (map.Has(field.key)) {
          *field.optional_bool(config) = map.GetBool(field.key, false);
        } else {
          valid->push_back(field.key);
        }
        break;
      case Type::kCustom:
        valid->push_back(field.key);
        break;
    }
  }

  std::string name_;
  std::vector<Field> fields_;
  std::function<void(const Struct&)> cross_checks_;
};

/// Throws the ConfigError a cross-field check raises: `key` relative to its struct, its value.
[[noreturn]] void FieldError(const std::string& key, double value, const std::string& message);

}  // namespace graspbed::common

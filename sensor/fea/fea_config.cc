#include "sensor/fea/fea_config.h"

#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>

#include "common/data_dir.h"

namespace graspbed::fea {
namespace {

using common::NumberRule;
using common::YamlMap;

// Refuse meshes whose element count would need gigabytes: the 0.05 mm paper mesh has ~1.6e3.
constexpr double kMaxElements = 2.0e5;

std::string FormatValue(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

ResistorExtent ReadResistor(const YamlMap& gauge, const char* key, ResistorExtent fallback) {
  const std::optional<YamlMap> map = gauge.GetMap(key);
  if (!map) return fallback;
  ResistorExtent extent;
  extent.start_mm = map->GetNumber("start_mm", fallback.start_mm);
  extent.end_mm = map->GetNumber("end_mm", fallback.end_mm);
  map->RejectUnknownKeys();
  return extent;
}

}  // namespace

std::optional<ConfigIssue> FindConfigIssue(const FeaConfig& config) {
  const MaterialConfig& m = config.material;
  const GeometryConfig& g = config.geometry;
  auto positive = [](const char* key, double value) -> std::optional<ConfigIssue> {
    if (!(value > 0.0) || !std::isfinite(value)) return ConfigIssue{key, value, "must be > 0"};
    return std::nullopt;
  };
  for (const auto& [key, value] : std::initializer_list<std::pair<const char*, double>>{
           {"material.youngs_modulus_gpa", m.youngs_modulus_gpa},
           {"geometry.beam_length_mm", g.beam_length_mm},
           {"geometry.beam_thickness_mm", g.beam_thickness_mm},
           {"geometry.width_mm", g.width_mm},
           {"geometry.brace_thickness_mm", g.brace_thickness_mm},
           {"geometry.brace_height_mm", g.brace_height_mm},
           {"geometry.mesa_length_mm", g.mesa_length_mm},
           {"geometry.mesa_height_mm", g.mesa_height_mm},
           {"mesh.element_size_mm", config.mesh.element_size_mm},
           {"load.max_force_n", config.load.max_force_n},
           {"reference.kn_per_n", config.reference.kn_per_n},
           {"reference.kt_per_n", config.reference.kt_per_n}}) {
    if (auto issue = positive(key, value)) return issue;
  }
  if (!(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5)) {
    return ConfigIssue{"material.poisson_ratio", m.poisson_ratio, "must be > -1 and < 0.5"};
  }
  if (!(g.SpanMm() > 0.0)) {
    return ConfigIssue{"geometry.brace_thickness_mm", g.brace_thickness_mm,
                       "two braces of this thickness leave no free span under a beam of length " +
                           FormatValue(g.beam_length_mm) + " mm"};
  }
  if (!(g.mesa_length_mm <= g.SpanMm())) {
    return ConfigIssue{"geometry.mesa_length_mm", g.mesa_length_mm,
                       "longer than the free span between the braces (" + FormatValue(g.SpanMm()) + " mm)"};
  }
  if (config.mesh.element_size_mm > g.beam_thickness_mm) {
    return ConfigIssue{"mesh.element_size_mm", config.mesh.element_size_mm,
                       "too coarse to put one element through the beam thickness (" +
                           FormatValue(g.beam_thickness_mm) + " mm)"};
  }
  const double cells_estimate =
      (g.beam_length_mm / config.mesh.element_size_mm + 4.0) *
      ((g.brace_height_mm + g.beam_thickness_mm + g.mesa_height_mm) / config.mesh.element_size_mm + 4.0);
  if (cells_estimate > kMaxElements * 4.0) {
    return ConfigIssue{"mesh.element_size_mm", config.mesh.element_size_mm,
                       "too fine: about " + FormatValue(cells_estimate) + " grid cells, limit " +
                           FormatValue(kMaxElements * 4.0)};
  }
  const double half_span = 0.5 * g.SpanMm();
  for (const auto& [name, extent] : {std::pair<const char*, ResistorExtent>{"r1", config.gauge.r1},
                                     std::pair<const char*, ResistorExtent>{"r2", config.gauge.r2}}) {
    const std::string key = std::string("gauge.") + name;
    if (!(extent.end_mm > extent.start_mm)) {
      return ConfigIssue{key + ".end_mm", extent.end_mm,
                         "must be > " + key + ".start_mm (" + FormatValue(extent.start_mm) + ")"};
    }
    if (extent.start_mm < -half_span) {
      return ConfigIssue{key + ".start_mm", extent.start_mm,
                         "outside the free span under the beam (-" + FormatValue(half_span) + ".." +
                             FormatValue(half_span) + " mm)"};
    }
    if (extent.end_mm > half_span) {
      return ConfigIssue{key + ".end_mm", extent.end_mm,
                         "outside the free span under the beam (-" + FormatValue(half_span) + ".." +
                             FormatValue(half_span) + " mm)"};
    }
  }
  if (config.load.steps < 1) {
    return ConfigIssue{"load.steps", static_cast<double>(config.load.steps), "must be >= 1"};
  }
  return std::nullopt;
}

void FeaConfig::Validate() const {
  if (const auto issue = FindConfigIssue(*this)) {
    throw std::invalid_argument(issue->key + " = " + FormatValue(issue->value) + ": " + issue->message);
  }
}

FeaConfig FeaConfigFromYaml(const YamlMap& root) {
  FeaConfig config;
  std::map<std::string, YamlMap> sections;
  auto section = [&](const char* name) -> std::optional<YamlMap> {
    std::optional<YamlMap> map = root.GetMap(name);
    if (map) sections.emplace(name, *map);
    return map;
  };
  const NumberRule positive = NumberRule::Positive();
  if (const auto material = section("material")) {
    MaterialConfig& m = config.material;
    m.youngs_modulus_gpa = material->GetNumber("youngs_modulus_gpa", m.youngs_modulus_gpa, positive);
    m.poisson_ratio =
        material->GetNumber("poisson_ratio", m.poisson_ratio, NumberRule::Between(-0.999, 0.499));
    material->RejectUnknownKeys();
  }
  if (const auto geometry = section("geometry")) {
    GeometryConfig& g = config.geometry;
    g.beam_length_mm = geometry->GetNumber("beam_length_mm", g.beam_length_mm, positive);
    g.beam_thickness_mm = geometry->GetNumber("beam_thickness_mm", g.beam_thickness_mm, positive);
    g.width_mm = geometry->GetNumber("width_mm", g.width_mm, positive);
    g.brace_thickness_mm = geometry->GetNumber("brace_thickness_mm", g.brace_thickness_mm, positive);
    g.brace_height_mm = geometry->GetNumber("brace_height_mm", g.brace_height_mm, positive);
    g.mesa_length_mm = geometry->GetNumber("mesa_length_mm", g.mesa_length_mm, positive);
    g.mesa_height_mm = geometry->GetNumber("mesa_height_mm", g.mesa_height_mm, positive);
    geometry->RejectUnknownKeys();
  }
  if (const auto mesh = section("mesh")) {
    config.mesh.element_size_mm = mesh->GetNumber("element_size_mm", config.mesh.element_size_mm, positive);
    mesh->RejectUnknownKeys();
  }
  if (const auto gauge = section("gauge")) {
    config.gauge.r1 = ReadResistor(*gauge, "r1", config.gauge.r1);
    config.gauge.r2 = ReadResistor(*gauge, "r2", config.gauge.r2);
    gauge->RejectUnknownKeys();
  }
  if (const auto load = section("load")) {
    config.load.max_force_n = load->GetNumber("max_force_n", config.load.max_force_n, positive);
    config.load.steps = load->GetInt("steps", config.load.steps, 1, 1000);
    load->RejectUnknownKeys();
  }
  if (const auto reference = section("reference")) {
    config.reference.kn_per_n = reference->GetNumber("kn_per_n", config.reference.kn_per_n, positive);
    config.reference.kt_per_n = reference->GetNumber("kt_per_n", config.reference.kt_per_n, positive);
    reference->RejectUnknownKeys();
  }
  root.RejectUnknownKeys();

  // Cross-checks: report them at the offending key's line ("gauge.r1.end_mm" -> map gauge.r1).
  if (const auto issue = FindConfigIssue(config)) {
    const size_t last_dot = issue->key.rfind('.');
    const std::string parent = issue->key.substr(0, last_dot);
    const std::string leaf = issue->key.substr(last_dot + 1);
    const size_t first_dot = parent.find('.');
    const std::string top = parent.substr(0, first_dot);
    auto found = sections.find(top);
    if (found != sections.end()) {
      if (first_dot == std::string::npos) found->second.Fail(leaf, issue->message);
      if (const auto nested = found->second.GetMap(parent.substr(first_dot + 1)))
        nested->Fail(leaf, issue->message);
    }
    // The key was left at its default: no line to point at.
    throw common::ConfigError(root.file() + ": " + issue->key + " = " + FormatValue(issue->value) +
                              " (default): " + issue->message);
  }
  return config;
}

FeaConfig LoadFeaConfig(const std::string& path) { return FeaConfigFromYaml(YamlMap::LoadFile(path)); }

std::string DefaultFeaConfigPath() { return common::DataPath("sensor/fea/unit_fea.yaml"); }

}  // namespace graspbed::fea

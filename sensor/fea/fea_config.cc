#include "sensor/fea/fea_config.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "common/data_dir.h"

namespace graspbed::fea {
namespace {

using common::FieldError;
using common::NumberRule;
using common::YamlMap;

// Refuse meshes whose element count would need gigabytes: the 0.05 mm paper mesh has ~1.6e3.
constexpr double kMaxElements = 2.0e5;

std::string FormatValue(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// The checks no single field's rule can make: braces, mesa and resistors inside the span, a mesh
// that fits through the beam and into memory. Keys relative to FeaConfig.
void CrossCheck(const FeaConfig& config) {
  const GeometryConfig& g = config.geometry;
  if (!(g.SpanMm() > 0.0)) {
    FieldError("geometry.brace_thickness_mm", g.brace_thickness_mm,
               "two braces of this thickness leave no free span under a beam of length " +
                   FormatValue(g.beam_length_mm) + " mm");
  }
  if (!(g.mesa_length_mm <= g.SpanMm())) {
    FieldError("geometry.mesa_length_mm", g.mesa_length_mm,
               "longer than the free span between the braces (" + FormatValue(g.SpanMm()) + " mm)");
  }
  if (config.mesh.element_size_mm > g.beam_thickness_mm) {
    FieldError("mesh.element_size_mm", config.mesh.element_size_mm,
               "too coarse to put one element through the beam thickness (" +
                   FormatValue(g.beam_thickness_mm) + " mm)");
  }
  const double cells_estimate =
      (g.beam_length_mm / config.mesh.element_size_mm + 4.0) *
      ((g.brace_height_mm + g.beam_thickness_mm + g.mesa_height_mm) / config.mesh.element_size_mm + 4.0);
  if (cells_estimate > kMaxElements * 4.0) {
    FieldError("mesh.element_size_mm", config.mesh.element_size_mm,
               "too fine: about " + FormatValue(cells_estimate) + " grid cells, limit " +
                   FormatValue(kMaxElements * 4.0));
  }
  const double half_span = 0.5 * g.SpanMm();
  for (const auto& [name, extent] : {std::pair<const char*, ResistorExtent>{"r1", config.gauge.r1},
                                     std::pair<const char*, ResistorExtent>{"r2", config.gauge.r2}}) {
    const std::string key = std::string("gauge.") + name;
    if (!(extent.end_mm > extent.start_mm)) {
      FieldError(key + ".end_mm", extent.end_mm,
                 "must be > " + key + ".start_mm (" + FormatValue(extent.start_mm) + ")");
    }
    const std::string outside = "outside the free span under the beam (-" + FormatValue(half_span) + ".." +
                                FormatValue(half_span) + " mm)";
    if (extent.start_mm < -half_span) FieldError(key + ".start_mm", extent.start_mm, outside);
    if (extent.end_mm > half_span) FieldError(key + ".end_mm", extent.end_mm, outside);
  }
}

template <typename Struct>
using Table = common::FieldTable<Struct>;

const Table<MaterialConfig>& MaterialFields() {
  using C = MaterialConfig;
  static const Table<C> table(
      "material",
      {
          Table<C>::Number("youngs_modulus_gpa", &C::youngs_modulus_gpa, NumberRule::Positive(), "GPa",
                           "E of the frame"),
          Table<C>::Number("poisson_ratio", &C::poisson_ratio, NumberRule::Between(-0.999, 0.499), "-", "nu"),
      });
  return table;
}

const Table<GeometryConfig>& GeometryFields() {
  using C = GeometryConfig;
  static const Table<C> table(
      "geometry", {
                      Table<C>::Number("beam_length_mm", &C::beam_length_mm, NumberRule::Positive(), "mm",
                                       "overall length of the beam, outer face to outer face of the braces"),
                      Table<C>::Number("beam_thickness_mm", &C::beam_thickness_mm, NumberRule::Positive(),
                                       "mm", "beam thickness (y)"),
                      Table<C>::Number("width_mm", &C::width_mm, NumberRule::Positive(), "mm",
                                       "out-of-plane width of the frame = plane-stress thickness"),
                      Table<C>::Number("brace_thickness_mm", &C::brace_thickness_mm, NumberRule::Positive(),
                                       "mm", "brace thickness along x; braces sit under the beam's ends"),
                      Table<C>::Number("brace_height_mm", &C::brace_height_mm, NumberRule::Positive(), "mm",
                                       "brace height, foot to beam underside"),
                      Table<C>::Number("mesa_length_mm", &C::mesa_length_mm, NumberRule::Positive(), "mm",
                                       "mesa length along the beam, centred"),
                      Table<C>::Number("mesa_height_mm", &C::mesa_height_mm, NumberRule::Positive(), "mm",
                                       "mesa thickness above the beam"),
                  });
  return table;
}

const Table<MeshConfig>& MeshFields() {
  using C = MeshConfig;
  static const Table<C> table(
      "mesh", {Table<C>::Number("element_size_mm", &C::element_size_mm, NumberRule::Positive(), "mm",
                                "largest element edge")});
  return table;
}

const Table<ResistorExtent>& ResistorFields() {
  using C = ResistorExtent;
  // The span rule is CrossCheck's (it depends on the geometry); the reference states it at the
  // default geometry.
  const double half_span = 0.5 * GeometryConfig{}.SpanMm();
  const std::string span = "within the free span under the beam, " + common::DocNumber(-half_span) +
                           " .. " + common::DocNumber(half_span) + " at the default geometry";
  static const Table<C> table(
      "resistor", {
                      Table<C>::Number("start_mm", &C::start_mm, {}, "mm", "x from the beam centre")
                          .Note(span),
                      Table<C>::Number("end_mm", &C::end_mm, {}, "mm", "x from the beam centre")
                          .Note("> `start_mm`, " + span),
                  });
  return table;
}

const Table<GaugeConfig>& GaugeFields() {
  using C = GaugeConfig;
  static const Table<C> table("gauge", {
                                           Table<C>::Section("r1", &C::r1, ResistorFields()),
                                           Table<C>::Section("r2", &C::r2, ResistorFields()),
                                       });
  return table;
}

const Table<LoadConfig>& LoadFields() {
  using C = LoadConfig;
  static const Table<C> table(
      "load",
      {
          Table<C>::Number("max_force_n", &C::max_force_n, NumberRule::Positive(), "N",
                           "largest normal and shear force, and the Fig. 4 load"),
          Table<C>::Integer("steps", &C::steps, 1, 1000, "", "sweep intervals (steps + 1 load levels)"),
      });
  return table;
}

const Table<ReferenceConfig>& ReferenceFields() {
  using C = ReferenceConfig;
  static const Table<C> table(
      "reference",
      {
          Table<C>::Number("kn_per_n", &C::kn_per_n, NumberRule::Positive(), "1/N", "paper's k_n"),
          Table<C>::Number("kt_per_n", &C::kt_per_n, NumberRule::Positive(), "1/N", "paper's k_t"),
      });
  return table;
}

}  // namespace

const common::FieldTable<FeaConfig>& FeaConfigFields() {
  using C = FeaConfig;
  // No name: a FEA config is a file of its own, its keys are the paths from its top.
  static const Table<C> table("",
                              {
                                  Table<C>::Section("material", &C::material, MaterialFields()),
                                  Table<C>::Section("geometry", &C::geometry, GeometryFields()),
                                  Table<C>::Section("mesh", &C::mesh, MeshFields()),
                                  Table<C>::Section("gauge", &C::gauge, GaugeFields()),
                                  Table<C>::Section("load", &C::load, LoadFields()),
                                  Table<C>::Section("reference", &C::reference, ReferenceFields()),
                              },
                              CrossCheck);
  return table;
}

void FeaConfig::Validate() const { FeaConfigFields().Validate(*this); }

FeaConfig LoadFeaConfig(const YamlMap& root) {
  FeaConfig config;
  FeaConfigFields().Load(root, &config);
  return config;
}

FeaConfig LoadFeaConfigFile(const std::string& path) { return LoadFeaConfig(YamlMap::LoadFile(path)); }

std::string DefaultFeaConfigPath() { return common::DataPath("sensor/fea/unit_fea.yaml"); }

}  // namespace graspbed::fea

// The FEA config: the shipped file, and bad geometry refused with file, line, key and value.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <stdexcept>
#include <string>

#include "common/yaml_map.h"
#include "sensor/fea/fea_config.h"
#include "tests/support/error_of.h"

namespace graspbed::fea {
namespace {

using ::testing::HasSubstr;

// The errors refused here are std::invalid_argument; one of another type fails the test.
std::string ErrorOf(const std::function<void()>& action) {
  return graspbed::test_support::ErrorOf<std::invalid_argument>(action);
}

std::string LoadError(const std::string& yaml) {
  return ErrorOf([&] { LoadFeaConfig(common::YamlMap::LoadString(yaml, "unit.yaml")); });
}

TEST(FeaConfigTest, ShippedFileHoldsThePaperValuesAndTheStatedChoices) {
  const FeaConfig config = LoadFeaConfigFile(DefaultFeaConfigPath());
  const FeaConfig defaults;
  EXPECT_DOUBLE_EQ(config.material.youngs_modulus_gpa, 197.0);
  EXPECT_DOUBLE_EQ(config.material.poisson_ratio, 0.3);
  EXPECT_DOUBLE_EQ(config.geometry.beam_length_mm, 3.0);
  EXPECT_DOUBLE_EQ(config.geometry.beam_thickness_mm, 0.2);
  EXPECT_DOUBLE_EQ(config.geometry.width_mm, 2.0);
  EXPECT_DOUBLE_EQ(config.geometry.brace_thickness_mm, 0.5);
  EXPECT_DOUBLE_EQ(config.geometry.brace_height_mm, 3.0);
  EXPECT_DOUBLE_EQ(config.geometry.mesa_height_mm, 0.5);
  EXPECT_DOUBLE_EQ(config.mesh.element_size_mm, 0.05);
  EXPECT_DOUBLE_EQ(config.load.max_force_n, 10.0);
  // The gauge is 1.5 mm long and centred; R1 and R2 each take one half.
  EXPECT_DOUBLE_EQ(config.gauge.r1.end_mm - config.gauge.r2.start_mm, 1.5);
  EXPECT_DOUBLE_EQ(config.gauge.r1.start_mm, config.gauge.r2.end_mm);
  // File and in-class defaults agree, so code that builds FeaConfig{} analyses the same unit.
  EXPECT_DOUBLE_EQ(config.geometry.mesa_length_mm, defaults.geometry.mesa_length_mm);
  EXPECT_DOUBLE_EQ(config.gauge.r1.start_mm, defaults.gauge.r1.start_mm);
  EXPECT_DOUBLE_EQ(config.gauge.r1.end_mm, defaults.gauge.r1.end_mm);
  EXPECT_DOUBLE_EQ(config.gauge.r2.start_mm, defaults.gauge.r2.start_mm);
  EXPECT_DOUBLE_EQ(config.reference.kn_per_n, defaults.reference.kn_per_n);
  EXPECT_NO_THROW(config.Validate());
}

TEST(FeaConfigTest, NegativeOrZeroSizesAreRefusedWithFileLineKeyAndValue) {
  EXPECT_EQ(LoadError("geometry:\n  beam_length_mm: 3\n  beam_thickness_mm: -0.2\n"),
            "unit.yaml:3: geometry.beam_thickness_mm = -0.2: must be > 0");
  EXPECT_EQ(LoadError("geometry:\n  width_mm: 0\n"), "unit.yaml:2: geometry.width_mm = 0: must be > 0");
  EXPECT_EQ(LoadError("mesh:\n  element_size_mm: 0\n"), "unit.yaml:2: mesh.element_size_mm = 0: must be > 0");
  EXPECT_EQ(LoadError("material:\n  youngs_modulus_gpa: -197\n"),
            "unit.yaml:2: material.youngs_modulus_gpa = -197: must be > 0");
  EXPECT_THAT(LoadError("material:\n  poisson_ratio: 0.5\n"),
              HasSubstr("unit.yaml:2: material.poisson_ratio = 0.5: must be <="));
}

TEST(FeaConfigTest, MeshTooCoarseForTheBeamThicknessIsRefused) {
  EXPECT_EQ(LoadError("geometry:\n  beam_thickness_mm: 0.2\nmesh:\n  element_size_mm: 0.25\n"),
            "unit.yaml:4: mesh.element_size_mm = 0.25: too coarse to put one element through the beam "
            "thickness (0.2 mm)");
  // A thinner beam with the default mesh: the message points at the defaulted key.
  EXPECT_EQ(LoadError("geometry:\n  beam_thickness_mm: 0.04\n"),
            "unit.yaml: mesh.element_size_mm = 0.05 (default): too coarse to put one element through the "
            "beam thickness (0.04 mm)");
}

TEST(FeaConfigTest, InconsistentGeometryIsRefusedAtTheOffendingKey) {
  EXPECT_EQ(LoadError("geometry:\n  beam_length_mm: 3\n  brace_thickness_mm: 1.5\n"),
            "unit.yaml:3: geometry.brace_thickness_mm = 1.5: two braces of this thickness leave no free "
            "span under a beam of length 3 mm");
  EXPECT_EQ(
      LoadError("geometry:\n  mesa_length_mm: 2.5\n"),
      "unit.yaml:2: geometry.mesa_length_mm = 2.5: longer than the free span between the braces (2 mm)");
  EXPECT_EQ(LoadError("gauge:\n  r1: {start_mm: 0.0, end_mm: 1.2}\n"),
            "unit.yaml:2: gauge.r1.end_mm = 1.2: outside the free span under the beam (-1..1 mm)");
  EXPECT_EQ(LoadError("gauge:\n  r2:\n    start_mm: 0.5\n    end_mm: 0.2\n"),
            "unit.yaml:4: gauge.r2.end_mm = 0.2: must be > gauge.r2.start_mm (0.5)");
  EXPECT_EQ(LoadError("load:\n  steps: 0\n"), "unit.yaml:2: load.steps = 0: must be >= 1");
}

TEST(FeaConfigTest, UnknownKeysAreRefused) {
  EXPECT_THAT(LoadError("geometry:\n  beam_lenght_mm: 3\n"),
              HasSubstr("unit.yaml:2: geometry.beam_lenght_mm"));
  EXPECT_THAT(LoadError("solver: ldlt\n"), HasSubstr("unit.yaml:1: solver"));
}

TEST(FeaConfigTest, ValidateNamesKeyAndValueForProgrammaticConfigs) {
  FeaConfig config;
  config.geometry.brace_height_mm = -1.0;
  EXPECT_EQ(ErrorOf([&] { config.Validate(); }), "geometry.brace_height_mm = -1: must be > 0");
  config = FeaConfig{};
  config.mesh.element_size_mm = 0.3;
  EXPECT_THAT(ErrorOf([&] { config.Validate(); }), HasSubstr("mesh.element_size_mm = 0.3: too coarse"));
  config = FeaConfig{};
  config.mesh.element_size_mm = 1e-4;
  EXPECT_THAT(ErrorOf([&] { config.Validate(); }), HasSubstr("mesh.element_size_mm = 0.0001: too fine"));
}

TEST(FeaConfigTest, MissingFileNamesThePath) {
  EXPECT_THAT(ErrorOf([] { LoadFeaConfigFile("/nonexistent/unit.yaml"); }),
              HasSubstr("/nonexistent/unit.yaml"));
}

}  // namespace
}  // namespace graspbed::fea

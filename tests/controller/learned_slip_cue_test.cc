// The learned slip cue: model files are evaluated as written, refused for another layout or feature
// set with a message naming the file and what differs, and the per-tick update allocates nothing.
#include "controller/learned_slip_cue.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "common/data_dir.h"
#include "controller/slip_features.h"
#include "tests/controller/synthetic_tactile.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/error_of.h"
#include "tests/support/temp_dir.h"

namespace graspbed::controller {
namespace {

using nlohmann::json;
namespace support = ::graspbed::test_support;
using support::ErrorOf;
using ::testing::HasSubstr;

constexpr double kScoreTol = 1e-12;
const SlipModelTarget kDefault20{.layout_name = "default_20", .units = 20};

json FeatureNames() {
  json names = json::array();
  for (const auto& feature : kSlipFeatures) names.push_back(feature.name);
  return names;
}

/// One stump on shear_ratio (index 2): <= 0.5 gives -2, above +2; baseline 0.25.
json StumpModel() {
  return {{"format", "graspbed-slip-model"},
          {"version", 1},
          {"layout", {{"name", "default_20"}, {"units", 20}, {"columns", 4}}},
          {"tick_period_s", 0.001},
          {"features", {{"set", kSlipFeatureSet}, {"names", FeatureNames()}}},
          {"label", "gross_within_20ms"},
          {"threshold", 0.5},
          {"model",
           {{"kind", "trees"},
            {"baseline", 0.25},
            {"trees", json::array({{{"feature", {2, -1, -1}},
                                    {"threshold", {0.5, 0.0, 0.0}},
                                    {"left", {1, 0, 0}},
                                    {"right", {2, 0, 0}},
                                    {"missing_left", {1, 0, 0}},
                                    {"value", {0.0, -2.0, 2.0}}}})}}}};
}

double Sigmoid(double raw) { return 1.0 / (1.0 + std::exp(-raw)); }

std::string Write(const support::TempDir& dir, const json& model) {
  return dir.Write("model.json", model.dump());
}

TEST(LearnedSlipCueTest, EvaluatesTheTreesAsWritten) {
  const support::TempDir dir("learned_cue");
  const SlipModel model = LoadSlipModel(Write(dir, StumpModel()), kDefault20);
  std::array<double, kSlipFeatureCount> x{};
  x[2] = 0.3;
  EXPECT_NEAR(EvaluateSlipModel(model, x), Sigmoid(0.25 - 2.0), kScoreTol);
  x[2] = 0.5;  // at the threshold: left, as sklearn sends it
  EXPECT_NEAR(EvaluateSlipModel(model, x), Sigmoid(0.25 - 2.0), kScoreTol);
  x[2] = 0.7;
  EXPECT_NEAR(EvaluateSlipModel(model, x), Sigmoid(0.25 + 2.0), kScoreTol);
  x[2] = std::nan("");
  EXPECT_NEAR(EvaluateSlipModel(model, x), Sigmoid(0.25 - 2.0), kScoreTol);
}

TEST(LearnedSlipCueTest, EvaluatesALogisticModel) {
  const support::TempDir dir("learned_cue");
  json document = StumpModel();
  json weights = json::array(), mean = json::array(), scale = json::array();
  for (size_t i = 0; i < kSlipFeatureCount; ++i) {
    weights.push_back(i == 0 ? 0.5 : 0.0);
    mean.push_back(i == 0 ? 1.0 : 0.0);
    scale.push_back(2.0);
  }
  document["model"] = {{"kind", "logistic"}, {"mean", mean}, {"scale", scale}, {"weights", weights}, {"bias", -1.0}};
  const SlipModel model = LoadSlipModel(Write(dir, document), kDefault20);
  std::array<double, kSlipFeatureCount> x{};
  x[0] = 5.0;
  EXPECT_NEAR(EvaluateSlipModel(model, x), Sigmoid(-1.0 + 0.5 * (5.0 - 1.0) / 2.0), kScoreTol);
}

TEST(LearnedSlipCueTest, RefusesAModelTrainedForAnotherLayout) {
  const support::TempDir dir("learned_cue");
  json document = StumpModel();
  document["layout"] = {{"name", "paper_3x3"}, {"units", 9}, {"columns", 3}};
  const std::string path = Write(dir, document);
  const std::string message = ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, kDefault20); });
  EXPECT_THAT(message, HasSubstr(path + ": layout.units = 9"));
  EXPECT_THAT(message, HasSubstr("trained for 9 units (layout paper_3x3), this sensor has 20 (layout default_20)"));
  // Same unit count, another layout's name.
  document["layout"] = {{"name", "my_20"}, {"units", 20}, {"columns", 4}};
  const std::string renamed = Write(dir, document);
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(renamed, kDefault20); }),
              HasSubstr("layout.name = my_20: the model was trained for layout my_20, this sensor is default_20"));
}

TEST(LearnedSlipCueTest, RefusesAnotherFeatureSetOrFeatureList) {
  const support::TempDir dir("learned_cue");
  json document = StumpModel();
  document["features"]["set"] = "tactile_v0";
  std::string path = Write(dir, document);
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, kDefault20); }),
              HasSubstr(path + ": features.set = tactile_v0: the model was trained on feature set tactile_v0, "
                               "this graspbed computes tactile_v1"));
  document = StumpModel();
  document["features"]["names"][3] = "hand_joint_rad";
  path = Write(dir, document);
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, kDefault20); }),
              HasSubstr("features.names[3] = hand_joint_rad: this graspbed's feature set tactile_v1 has ratio_lp there"));
  document = StumpModel();
  document["features"]["names"].erase(document["features"]["names"].size() - 1);
  path = Write(dir, document);
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, kDefault20); }),
              HasSubstr("(18 features in the file, 19 here)"));
}

TEST(LearnedSlipCueTest, RefusesAFileWhoseCheckRowsDoNotReproduce) {
  const support::TempDir dir("learned_cue");
  json document = StumpModel();
  std::vector<double> row(kSlipFeatureCount, 0.0);
  row[2] = 0.9;
  document["check"] = {{"features", {row}}, {"scores", {Sigmoid(2.25)}}};
  EXPECT_NO_THROW(LoadSlipModel(Write(dir, document), kDefault20));
  document["check"]["scores"][0] = Sigmoid(2.25) + 1e-5;
  const std::string path = Write(dir, document);
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, kDefault20); }),
              HasSubstr(path + ": check.scores[0] = "));
}

TEST(LearnedSlipCueTest, RefusesOtherFormatsAndBrokenTrees) {
  const support::TempDir dir("learned_cue");
  json document = StumpModel();
  document["version"] = 2;
  std::string path = Write(dir, document);
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, kDefault20); }),
              HasSubstr("version = 2: this graspbed reads version 1"));
  document = StumpModel();
  document["model"]["trees"][0]["left"][0] = 7;
  path = Write(dir, document);
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, kDefault20); }),
              HasSubstr("model.trees[0].node 0: a feature or child index out of range"));
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(dir.Path("missing.json"), kDefault20); }),
              HasSubstr("missing.json: cannot read the slip model file"));
}

TEST(LearnedSlipCueTest, ShippedModelLoadsForTheDefaultLayoutOnly) {
  const std::string path = common::DataPath("models/slip/default_20.json");
  const SlipModel model = LoadSlipModel(path, kDefault20);  // its check rows evaluate here as in Python
  EXPECT_EQ(model.kind, SlipModel::Kind::kTrees);
  EXPECT_EQ(model.label, "gross_within_20ms");
  EXPECT_THAT(ErrorOf<std::invalid_argument>([&] { LoadSlipModel(path, {.layout_name = "paper_3x3", .units = 9}); }),
              HasSubstr("this sensor has 9 (layout paper_3x3)"));
}

TEST(LearnedSlipCueTest, UpdateAllocatesNothingAndFollowsTheModel) {
  const support::TempDir dir("learned_cue");
  LearnedSlipCue cue(LoadSlipModel(Write(dir, StumpModel()), kDefault20));
  test_support::SyntheticTactile tactile({});
  test_support::SyntheticContact contact;
  contact.grip_n = 3.0;
  std::vector<sensor::TactileState> states;
  for (int i = 0; i < 400; ++i) {
    contact.load_axial_n = i < 200 ? 0.3 : 6.0;  // shear ratio about 0.1, then 2
    states.push_back(tactile.Frame(contact, i * 1e-3));
  }
  const long before = support::AllocationCount();
  int flags_early = 0, flags_late = 0;
  for (size_t i = 0; i < states.size(); ++i) {
    const LearnedSlipOutput out = cue.Update(states[i], i * 1e-3);
    (i < 200 ? flags_early : flags_late) += out.flag ? 1 : 0;
  }
  EXPECT_EQ(support::AllocationCount() - before, 0);
  EXPECT_EQ(flags_early, 0);
  EXPECT_GT(flags_late, 150);
  // Another unit count than the model's: no score, no flag.
  sensor::TactileState nine = states.back();
  nine.unit_count = 9;
  EXPECT_FALSE(cue.Update(nine, 0.5).flag);
}

TEST(SlipFeaturesTest, RefusesANonsensicalLayoutOrPeriod) {
  EXPECT_THAT(ErrorOf<std::invalid_argument>([] { SlipFeatureExtractor({.units = 0, .columns = 4}, 1e-3); }),
              HasSubstr("0 units in 4 columns"));
  EXPECT_THAT(ErrorOf<std::invalid_argument>([] { SlipFeatureExtractor({.units = 20, .columns = 4}, 0.0); }),
              HasSubstr("tick period 0"));
}

}  // namespace
}  // namespace graspbed::controller

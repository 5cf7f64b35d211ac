#include "controller/learned_slip_cue.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <nlohmann/json.hpp>

namespace graspbed::controller {
namespace {

using nlohmann::json;

constexpr double kCheckTolerance = 1e-6;

[[noreturn]] void Refuse(const std::string& path, const std::string& what) {
  throw std::invalid_argument(path + ": " + what);
}

const json& Require(const std::string& path, const json& parent, const char* key, const std::string& where) {
  if (!parent.is_object() || !parent.contains(key)) Refuse(path, "no `" + where + key + "`: not a slip model file");
  return parent.at(key);
}

template <typename T>
std::vector<T> Array(const std::string& path, const json& parent, const char* key, const std::string& where,
                     size_t expected_size) {
  const json& node = Require(path, parent, key, where);
  std::vector<T> values;
  try {
    values = node.get<std::vector<T>>();
  } catch (const json::exception&) {
    Refuse(path, where + key + ": expected a list of numbers");
  }
  if (expected_size > 0 && values.size() != expected_size) {
    Refuse(path, where + key + ": " + std::to_string(values.size()) + " values, expected " +
                     std::to_string(expected_size));
  }
  return values;
}

void CheckHeader(const std::string& path, const json& root, const SlipModelTarget& target, SlipModel& model) {
  const std::string format = Require(path, root, "format", "").get<std::string>();
  if (format != kSlipModelFormat) Refuse(path, "format = " + format + ": expected " + kSlipModelFormat);
  const int version = Require(path, root, "version", "").get<int>();
  if (version != kSlipModelVersion) {
    Refuse(path, "version = " + std::to_string(version) + ": this graspbed reads version " +
                     std::to_string(kSlipModelVersion));
  }
  const json& layout = Require(path, root, "layout", "");
  model.layout_name = Require(path, layout, "name", "layout.").get<std::string>();
  model.layout.units = Require(path, layout, "units", "layout.").get<int>();
  model.layout.columns = Require(path, layout, "columns", "layout.").get<int>();
  if (target.units > 0 && model.layout.units != target.units) {
    Refuse(path, "layout.units = " + std::to_string(model.layout.units) + ": the model was trained for " +
                     std::to_string(model.layout.units) + " units (layout " + model.layout_name +
                     "), this sensor has " + std::to_string(target.units) +
                     (target.layout_name.empty() ? "" : " (layout " + target.layout_name + ")"));
  }
  if (!target.layout_name.empty() && model.layout_name != target.layout_name) {
    Refuse(path, "layout.name = " + model.layout_name + ": the model was trained for layout " + model.layout_name +
                     ", this sensor is " + target.layout_name);
  }
}

void CheckFeatures(const std::string& path, const json& root, SlipModel& model) {
  const json& features = Require(path, root, "features", "");
  model.feature_set = Require(path, features, "set", "features.").get<std::string>();
  if (model.feature_set != kSlipFeatureSet) {
    Refuse(path, "features.set = " + model.feature_set + ": the model was trained on feature set " +
                     model.feature_set + ", this graspbed computes " + kSlipFeatureSet +
                     "; train it again on a dataset made by this graspbed");
  }
  const std::vector<std::string> names = Require(path, features, "names", "features.").get<std::vector<std::string>>();
  for (size_t i = 0; i < std::max(names.size(), kSlipFeatureCount); ++i) {
    const std::string theirs = i < names.size() ? names[i] : "(none)";
    const std::string ours = i < kSlipFeatureCount ? kSlipFeatures[i].name : "(none)";
    if (theirs != ours) {
      Refuse(path, "features.names[" + std::to_string(i) + "] = " + theirs + ": this graspbed's feature set " +
                       kSlipFeatureSet + " has " + ours + " there (" + std::to_string(names.size()) +
                       " features in the file, " + std::to_string(kSlipFeatureCount) + " here)");
    }
  }
}

void LoadTrees(const std::string& path, const json& body, SlipModel& model) {
  model.kind = SlipModel::Kind::kTrees;
  model.baseline = Require(path, body, "baseline", "model.").get<double>();
  const json& trees = Require(path, body, "trees", "model.");
  if (!trees.is_array() || trees.empty()) Refuse(path, "model.trees: expected a non-empty list of trees");
  for (size_t t = 0; t < trees.size(); ++t) {
    const std::string where = "model.trees[" + std::to_string(t) + "].";
    const auto feature = Array<int32_t>(path, trees[t], "feature", where, 0);
    const size_t n = feature.size();
    const auto threshold = Array<double>(path, trees[t], "threshold", where, n);
    const auto left = Array<int32_t>(path, trees[t], "left", where, n);
    const auto right = Array<int32_t>(path, trees[t], "right", where, n);
    const auto missing_left = Array<int>(path, trees[t], "missing_left", where, n);
    const auto value = Array<double>(path, trees[t], "value", where, n);
    const auto offset = static_cast<int32_t>(model.node_feature.size());
    model.tree_roots.push_back(offset);
    for (size_t i = 0; i < n; ++i) {
      const bool leaf = feature[i] < 0;
      if (!leaf && (feature[i] >= static_cast<int32_t>(kSlipFeatureCount) || left[i] <= static_cast<int32_t>(i) ||
                    right[i] <= static_cast<int32_t>(i) || left[i] >= static_cast<int32_t>(n) ||
                    right[i] >= static_cast<int32_t>(n))) {
        Refuse(path, where + "node " + std::to_string(i) + ": a feature or child index out of range");
      }
      model.node_feature.push_back(leaf ? -1 : feature[i]);
      model.node_threshold.push_back(threshold[i]);
      model.node_left.push_back(leaf ? -1 : left[i] + offset);
      model.node_right.push_back(leaf ? -1 : right[i] + offset);
      model.node_missing_left.push_back(missing_left[i] != 0 ? 1 : 0);
      model.node_value.push_back(value[i]);
    }
  }
}

void LoadLogistic(const std::string& path, const json& body, SlipModel& model) {
  model.kind = SlipModel::Kind::kLogistic;
  model.mean = Array<double>(path, body, "mean", "model.", kSlipFeatureCount);
  model.scale = Array<double>(path, body, "scale", "model.", kSlipFeatureCount);
  model.weights = Array<double>(path, body, "weights", "model.", kSlipFeatureCount);
  model.bias = Require(path, body, "bias", "model.").get<double>();
  for (double scale : model.scale) {
    if (!(scale > 0.0)) Refuse(path, "model.scale: every scale must be > 0");
  }
}

/// The file's check rows (features and the trainer's scores) must evaluate to the same scores here.
void CheckScores(const std::string& path, const json& root, const SlipModel& model) {
  if (!root.contains("check")) return;
  const json& check = root.at("check");
  const auto rows = Require(path, check, "features", "check.").get<std::vector<std::vector<double>>>();
  const auto scores = Array<double>(path, check, "scores", "check.", rows.size());
  for (size_t r = 0; r < rows.size(); ++r) {
    if (rows[r].size() != kSlipFeatureCount) Refuse(path, "check.features[" + std::to_string(r) + "]: wrong length");
    const double here = EvaluateSlipModel(model, rows[r]);
    if (!(std::abs(here - scores[r]) <= kCheckTolerance)) {
      std::ostringstream message;
      message.precision(10);
      message << "check.scores[" << r << "] = " << scores[r] << ": the model evaluates to " << here
              << " here (tolerance 1e-6); the file's parameters do not reproduce the trainer's scores";
      Refuse(path, message.str());
    }
  }
}

}  // namespace

SlipModel LoadSlipModel(const std::string& path, const SlipModelTarget& target) {
  std::ifstream stream(path);
  if (!stream) Refuse(path, "cannot read the slip model file");
  json root;
  try {
    root = json::parse(stream);
  } catch (const json::parse_error& error) {
    Refuse(path, std::string("not JSON: ") + error.what());
  }
  SlipModel model;
  model.source_file = path;
  try {
    CheckHeader(path, root, target, model);
    CheckFeatures(path, root, model);
    model.tick_period_s = Require(path, root, "tick_period_s", "").get<double>();
    if (!(model.tick_period_s > 0.0 && model.tick_period_s <= 1.0)) Refuse(path, "tick_period_s: must be in (0, 1]");
    model.label = root.value("label", std::string());
    model.threshold = Require(path, root, "threshold", "").get<double>();
    const json& body = Require(path, root, "model", "");
    const std::string kind = Require(path, body, "kind", "model.").get<std::string>();
    if (kind == "trees") {
      LoadTrees(path, body, model);
    } else if (kind == "logistic") {
      LoadLogistic(path, body, model);
    } else {
      Refuse(path, "model.kind = " + kind + ": expected trees or logistic");
    }
    CheckScores(path, root, model);
  } catch (const json::exception& error) {
    Refuse(path, std::string("malformed slip model: ") + error.what());
  }
  return model;
}

double EvaluateSlipModel(const SlipModel& model, std::span<const double> x) {
  double raw = 0.0;
  if (model.kind == SlipModel::Kind::kLogistic) {
    raw = model.bias;
    for (size_t i = 0; i < kSlipFeatureCount; ++i) raw += model.weights[i] * (x[i] - model.mean[i]) / model.scale[i];
  } else {
    raw = model.baseline;
    for (const int32_t root : model.tree_roots) {
      int32_t node = root;
      while (model.node_feature[static_cast<size_t>(node)] >= 0) {
        const size_t i = static_cast<size_t>(node);
        const double value = x[static_cast<size_t>(model.node_feature[i])];
        const bool left = std::isnan(value) ? model.node_missing_left[i] != 0 : value <= model.node_threshold[i];
        node = left ? model.node_left[i] : model.node_right[i];
      }
      raw += model.node_value[static_cast<size_t>(node)];
    }
  }
  return 1.0 / (1.0 + std::exp(-raw));
}

LearnedSlipCue::LearnedSlipCue(SlipModel model, double threshold)
    : model_(std::move(model)),
      threshold_(threshold >= 0.0 ? threshold : model_.threshold),
      extractor_(model_.layout, model_.tick_period_s) {}

void LearnedSlipCue::Reset() {
  extractor_.Reset();
  features_.fill(0.0);
  output_ = {};
}

LearnedSlipOutput LearnedSlipCue::Update(const sensor::TactileState& state, double time_s) {
  if (state.unit_count != model_.layout.units) {
    output_ = {};
    return output_;
  }
  extractor_.Update(state, time_s, features_);
  output_.score = EvaluateSlipModel(model_, features_);
  output_.flag = output_.score >= threshold_;
  return output_;
}

}  // namespace graspbed::controller

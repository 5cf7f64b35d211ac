#pragma once
/// LearnedSlipCue: a slip detector trained on the testbed's own ground truth (`graspbed dataset`,
/// python/train_slip_model.py) and run per control tick from the TactileState alone. It computes
/// the features of controller/slip_features.h and evaluates a small model loaded from a versioned
/// JSON file (format "graspbed-slip-model" version 1, docs/training-slip-detector.md, "The model
/// file"): a gradient-boosted tree ensemble (flat arrays) or a logistic regression. Its output is the
/// probability that a gross slip is under way or begins within the model's horizon (20 ms for the
/// shipped model), and a flag at the model's threshold.
///
/// Immutable model (SlipModel) + mutable per-tick state (the feature extractor, the feature
/// buffer), allocated at construction: Update() neither allocates nor does I/O.

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "controller/slip_features.h"
#include "sensor/tactile_state.h"

namespace graspbed::controller {

/// Name and version of the model file format this graspbed reads.
inline constexpr const char* kSlipModelFormat = "graspbed-slip-model";
inline constexpr int kSlipModelVersion = 1;

/// A loaded model: what it was trained for and its parameters as flat arrays.
struct SlipModel {
  std::string source_file;   ///< the file it came from ("" when built in memory)
  std::string layout_name;   ///< the sensor layout it was trained on, e.g. "default_20"
  SlipFeatureLayout layout;  ///< its unit count and grid columns
  std::string feature_set;   ///< kSlipFeatureSet of the dataset it was trained on
  double tick_period_s = 0.001;  ///< control period of that dataset [s]; the cue runs at it
  std::string label;             ///< what the score predicts, e.g. "gross_within_20ms"
  double threshold = 0.5;        ///< flag when the score is at or above this [-]
  enum class Kind { kTrees, kLogistic } kind = Kind::kTrees;
  // kTrees: raw = baseline + sum over trees of the leaf reached; score = 1 / (1 + exp(-raw)). A node
  // sends x to `left` when x[feature] <= threshold (or x is NaN and missing_left), else to `right`.
  double baseline = 0.0;
  std::vector<int32_t> tree_roots;  ///< index of each tree's root node in the node arrays
  std::vector<int32_t> node_feature;  ///< -1 at a leaf
  std::vector<double> node_threshold;
  std::vector<int32_t> node_left, node_right;
  std::vector<uint8_t> node_missing_left;
  std::vector<double> node_value;  ///< a leaf's contribution to raw [-]
  // kLogistic: raw = bias + sum_i weights[i] (x[i] - mean[i]) / scale[i].
  std::vector<double> mean, scale, weights;
  double bias = 0.0;
};

/// What the caller's sensor is, for the loader to check a model against.
struct SlipModelTarget {
  std::string layout_name;  ///< "" = do not check the name (only the unit count)
  int units = 0;            ///< the layout's unit count; 0 = not known yet (the cue then checks each state's)
};

/// Reads and checks a model file. Refuses (std::invalid_argument, the message naming the file and what
/// differs) a file that cannot be read or parsed, another format or version, a model trained for
/// another layout (unit count or name) than `target`, or on another feature set or feature list
/// than this graspbed computes, and a file whose embedded check rows ("check": features and the
/// scores the trainer computed) do not evaluate to those scores within 1e-6 here.
SlipModel LoadSlipModel(const std::string& path, const SlipModelTarget& target);

/// The model's score for one feature vector (kSlipFeatureCount values), in [0, 1]. No allocation.
double EvaluateSlipModel(const SlipModel& model, std::span<const double> features);

/// The cue's output at one tick.
struct LearnedSlipOutput {
  double score = 0.0;  ///< the model's probability [-]
  bool flag = false;   ///< score >= the model's threshold
};

class LearnedSlipCue {
 public:
  /// Takes a checked model (LoadSlipModel). `threshold` < 0 keeps the model's own.
  explicit LearnedSlipCue(SlipModel model, double threshold = -1.0);

  /// Forgets the filters' state (a new grasp, a new run).
  void Reset();
  /// One control tick with the newest state at `time_s` [s]; call once per tick at the model's
  /// tick_period_s. A state with another unit count than the model's gives score 0, no flag. No
  /// allocation, no I/O.
  LearnedSlipOutput Update(const sensor::TactileState& state, double time_s);

  /// The last tick's output and features (kSlipFeatureCount values).
  const LearnedSlipOutput& output() const { return output_; }
  std::span<const double> features() const { return features_; }
  const SlipModel& model() const { return model_; }
  double threshold() const { return threshold_; }

 private:
  SlipModel model_;
  double threshold_;
  SlipFeatureExtractor extractor_;
  std::array<double, kSlipFeatureCount> features_{};
  LearnedSlipOutput output_;
};

}  // namespace graspbed::controller

// The front end's named choices by wicp_rgbd_slam's option names: one table of keys for every caller.
#include "weighted_icp/frontend/slam/frontend_choices.h"

#include <cmath>
#include <exception>
#include <functional>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace weighted_icp::frontend {

namespace {

using Setter = std::function<void(FrontendOptions&, const std::string&)>;
using Getter = std::function<std::string(const FrontendOptions&)>;

/// A choice of two words: true for `second`, false for `first`, anything else refused naming both.
bool secondOfTwo(const std::string& value, const std::string& first, const std::string& second) {
  if (value != first && value != second)
    throw std::invalid_argument("'" + value + "' (expected " + first + " or " + second + ")");
  return value == second;
}

/// "full" (every frame at its own size) or "MIN-MAX", the widths in pixels features are found between: MIN 0 (never
/// doubled) or 16 or more, MAX 0 (never halved) or 64-100000, MIN at most MAX / 2 (FeatureExtractorOptions).
std::pair<int, int> parseFeatureWidths(const std::string& value) {
  if (value == "full") return {0, 0};
  const auto fail = [&] {
    return std::invalid_argument(
        "'" + value +
        "' (expected full or MIN-MAX in pixels: MIN 0 (never doubled) or >= 16, MAX 0 (never halved) or 64-100000, "
        "MIN at most MAX / 2; e.g. 427-960)");
  };
  const std::size_t dash = value.find('-');
  if (dash == std::string::npos) throw fail();
  int widths[2] = {0, 0};
  const std::string parts[2] = {value.substr(0, dash), value.substr(dash + 1)};
  for (int i = 0; i < 2; ++i) {
    std::size_t used = 0;
    try {
      widths[i] = std::stoi(parts[i], &used);
    } catch (const std::exception&) {
      throw fail();
    }
    if (used == 0 || used != parts[i].size() || parts[i][0] == '-' || parts[i][0] == '+') throw fail();
  }
  const int min = widths[0], max = widths[1];
  if ((min != 0 && min < 16) || (max != 0 && (max < 64 || max > 100000)) || (max != 0 && 2 * min > max)) throw fail();
  return {widths[0], widths[1]};
}

/// The words of feature-width's value: "full" or "MIN-MAX".
std::string featureWidthsWord(const FeatureExtractorOptions& features) {
  if (features.min_working_width == 0 && features.max_working_width == 0) return "full";
  return std::to_string(features.min_working_width) + "-" + std::to_string(features.max_working_width);
}

/// The word of feature-smoothing's value: "off" or the sigma as a number, as short as reads back exactly ("1", "0.8").
std::string featureSmoothingWord(double sigma) {
  if (sigma == 0.0) return "off";
  std::string shortest;
  for (const int digits : {6, 17}) {
    std::ostringstream word;
    word << std::setprecision(digits) << sigma;
    shortest = word.str();
    if (std::stod(shortest) == sigma) break;
  }
  return shortest;
}

/// "off" or the feature blur's Gaussian sigma in pixels, 0 (off) to 5 (FeatureExtractorOptions::smoothing_sigma).
double parseFeatureSmoothing(const std::string& value) {
  if (value == "off") return 0.0;
  const auto fail = [&] {
    return std::invalid_argument("'" + value + "' (expected off or a Gaussian sigma in pixels from 0 (off) to " +
                                 featureSmoothingWord(FeatureExtractorOptions::kMaxSmoothingSigma) + ")");
  };
  std::size_t used = 0;
  double sigma = 0.0;
  try {
    sigma = std::stod(value, &used);
  } catch (const std::exception&) {
    throw fail();
  }
  if (used != value.size() || !std::isfinite(sigma) || sigma < 0.0 ||
      sigma > FeatureExtractorOptions::kMaxSmoothingSigma)
    throw fail();
  return sigma;
}

/// One named choice: how its word sets the options and which word the options hold, side by side so that the two
/// directions cannot drift apart.
struct Choice {
  std::string key;
  Setter set;
  Getter get;
};

/// The word of a choice of two: `second` when true, `first` when false.
const char* wordOfTwo(bool value, const char* first, const char* second) { return value ? second : first; }

const std::vector<Choice>& choices() {
  static const std::vector<Choice> table = {
      {"matcher", [](FrontendOptions& o, const std::string& v) { o.matcher.kind = parseMatcherKind(v); },
       [](const FrontendOptions& o) { return matcherKindName(o.matcher.kind); }},
      {"quality-gate", [](FrontendOptions& o, const std::string& v) { o.quality.mode = parseQualityGateMode(v); },
       [](const FrontendOptions& o) { return toString(o.quality.mode); }},
      {"quality-measure", [](FrontendOptions& o, const std::string& v) { o.quality.measure = parseQualityMeasure(v); },
       [](const FrontendOptions& o) { return toString(o.quality.measure); }},
      {"descriptor", [](FrontendOptions& o, const std::string& v) { o.features.descriptor = parseDescriptorKind(v); },
       [](const FrontendOptions& o) { return descriptorKindName(o.features.descriptor); }},
      {"match-region", [](FrontendOptions& o, const std::string& v) { o.match_region = parseMatchRegion(v); },
       [](const FrontendOptions& o) { return matchRegionName(o.match_region); }},
      {"dynamic-distance",
       [](FrontendOptions& o, const std::string& v) { o.dynamic_distance = parseDynamicDistanceKind(v); },
       [](const FrontendOptions& o) { return dynamicDistanceKindName(o.dynamic_distance); }},
      {"equalization",
       [](FrontendOptions& o, const std::string& v) { o.features.equalization = parseEqualizationMethod(v); },
       [](const FrontendOptions& o) { return toString(o.features.equalization); }},
      {"describe",
       [](FrontendOptions& o, const std::string& v) {
         o.features.describe_equalized = secondOfTwo(v, "original", "equalized");
       },
       [](const FrontendOptions& o) -> std::string {
         return wordOfTwo(o.features.describe_equalized, "original", "equalized");
       }},
      {"pnp", [](FrontendOptions& o, const std::string& v) { o.pnp.method = parsePnpMethod(v); },
       [](const FrontendOptions& o) { return toString(o.pnp.method); }},
      {"pnp-thresholds",
       [](FrontendOptions& o, const std::string& v) {
         o.pnp_thresholds_in_working_pixels = secondOfTwo(v, "frame", "working");
       },
       [](const FrontendOptions& o) -> std::string {
         return wordOfTwo(o.pnp_thresholds_in_working_pixels, "frame", "working");
       }},
      {"pnp-prediction",
       [](FrontendOptions& o, const std::string& v) { o.pnp.refine_guess = secondOfTwo(v, "start", "candidate"); },
       [](const FrontendOptions& o) -> std::string { return wordOfTwo(o.pnp.refine_guess, "start", "candidate"); }},
      {"gate-free-retry",
       [](FrontendOptions& o, const std::string& v) { o.gate_free_retry = secondOfTwo(v, "off", "on"); },
       [](const FrontendOptions& o) -> std::string { return wordOfTwo(o.gate_free_retry, "off", "on"); }},
      {"motion-timing",
       [](FrontendOptions& o, const std::string& v) { o.motion_per_period = secondOfTwo(v, "frame", "period"); },
       [](const FrontendOptions& o) -> std::string { return wordOfTwo(o.motion_per_period, "frame", "period"); }},
      {"keyframe-before-loss",
       [](FrontendOptions& o, const std::string& v) { o.keyframe_before_loss = secondOfTwo(v, "off", "on"); },
       [](const FrontendOptions& o) -> std::string { return wordOfTwo(o.keyframe_before_loss, "off", "on"); }},
      {"feature-width",
       [](FrontendOptions& o, const std::string& v) {
         std::tie(o.features.min_working_width, o.features.max_working_width) = parseFeatureWidths(v);
       },
       [](const FrontendOptions& o) { return featureWidthsWord(o.features); }},
      {"feature-smoothing",
       [](FrontendOptions& o, const std::string& v) { o.features.smoothing_sigma = parseFeatureSmoothing(v); },
       [](const FrontendOptions& o) { return featureSmoothingWord(o.features.smoothing_sigma); }},
      {"dense-odometry",
       [](FrontendOptions& o, const std::string& v) { o.dense_odometry.use = parseDenseOdometryUse(v); },
       [](const FrontendOptions& o) { return toString(o.dense_odometry.use); }},
      {"dense-odometry-kind",
       [](FrontendOptions& o, const std::string& v) { o.dense_odometry.kind = parseDenseOdometryKind(v); },
       [](const FrontendOptions& o) { return toString(o.dense_odometry.kind); }},
  };
  return table;
}

/// The choice named `key`, or an error listing every key.
const Choice& choiceNamed(const std::string& key) {
  for (const Choice& choice : choices())
    if (choice.key == key) return choice;
  std::string expected;
  const auto keys = frontendChoiceKeys();
  for (std::size_t i = 0; i < keys.size(); ++i)
    expected += (i == 0 ? "" : i + 1 == keys.size() ? " or " : ", ") + keys[i];
  throw std::invalid_argument("unknown front-end option '" + key + "' (expected " + expected + ")");
}

}  // namespace

void setFrontendChoice(FrontendOptions& options, const std::string& key, const std::string& value) {
  const Choice& choice = choiceNamed(key);
  try {
    choice.set(options, value);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(key + ": " + e.what());
  }
}

std::string frontendChoiceWord(const FrontendOptions& options, const std::string& key) {
  return choiceNamed(key).get(options);
}

std::vector<std::string> frontendChoiceKeys() {
  std::vector<std::string> keys;
  for (const Choice& choice : choices()) keys.push_back(choice.key);
  return keys;
}

}  // namespace weighted_icp::frontend

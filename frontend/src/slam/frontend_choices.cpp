// The front end's named choices by wicp_rgbd_slam's option names: one table of keys for every caller.
#include "weighted_icp/frontend/slam/frontend_choices.h"

#include <exception>
#include <functional>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace weighted_icp::frontend {

namespace {

using Setter = std::function<void(FrontendOptions&, const std::string&)>;

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

const std::vector<std::pair<std::string, Setter>>& setters() {
  static const std::vector<std::pair<std::string, Setter>> table = {
      {"matcher", [](FrontendOptions& o, const std::string& v) { o.matcher.kind = parseMatcherKind(v); }},
      {"quality-gate", [](FrontendOptions& o, const std::string& v) { o.quality.mode = parseQualityGateMode(v); }},
      {"quality-measure", [](FrontendOptions& o, const std::string& v) { o.quality.measure = parseQualityMeasure(v); }},
      {"descriptor", [](FrontendOptions& o, const std::string& v) { o.features.descriptor = parseDescriptorKind(v); }},
      {"match-region", [](FrontendOptions& o, const std::string& v) { o.match_region = parseMatchRegion(v); }},
      {"dynamic-distance",
       [](FrontendOptions& o, const std::string& v) { o.dynamic_distance = parseDynamicDistanceKind(v); }},
      {"equalization",
       [](FrontendOptions& o, const std::string& v) { o.features.equalization = parseEqualizationMethod(v); }},
      {"describe",
       [](FrontendOptions& o, const std::string& v) {
         o.features.describe_equalized = secondOfTwo(v, "original", "equalized");
       }},
      {"pnp", [](FrontendOptions& o, const std::string& v) { o.pnp.method = parsePnpMethod(v); }},
      {"pnp-thresholds",
       [](FrontendOptions& o, const std::string& v) {
         o.pnp_thresholds_in_working_pixels = secondOfTwo(v, "frame", "working");
       }},
      {"gate-free-retry",
       [](FrontendOptions& o, const std::string& v) { o.gate_free_retry = secondOfTwo(v, "off", "on"); }},
      {"motion-timing",
       [](FrontendOptions& o, const std::string& v) { o.motion_per_period = secondOfTwo(v, "frame", "period"); }},
      {"keyframe-before-loss",
       [](FrontendOptions& o, const std::string& v) { o.keyframe_before_loss = secondOfTwo(v, "off", "on"); }},
      {"feature-width",
       [](FrontendOptions& o, const std::string& v) {
         std::tie(o.features.min_working_width, o.features.max_working_width) = parseFeatureWidths(v);
       }},
      {"dense-odometry",
       [](FrontendOptions& o, const std::string& v) { o.dense_odometry.use = parseDenseOdometryUse(v); }},
      {"dense-odometry-kind",
       [](FrontendOptions& o, const std::string& v) { o.dense_odometry.kind = parseDenseOdometryKind(v); }},
  };
  return table;
}

}  // namespace

void setFrontendChoice(FrontendOptions& options, const std::string& key, const std::string& value) {
  for (const auto& [name, set] : setters()) {
    if (name != key) continue;
    try {
      set(options, value);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(key + ": " + e.what());
    }
    return;
  }
  std::string expected;
  const auto keys = frontendChoiceKeys();
  for (std::size_t i = 0; i < keys.size(); ++i)
    expected += (i == 0 ? "" : i + 1 == keys.size() ? " or " : ", ") + keys[i];
  throw std::invalid_argument("unknown front-end option '" + key + "' (expected " + expected + ")");
}

std::vector<std::string> frontendChoiceKeys() {
  std::vector<std::string> keys;
  for (const auto& entry : setters()) keys.push_back(entry.first);
  return keys;
}

}  // namespace weighted_icp::frontend

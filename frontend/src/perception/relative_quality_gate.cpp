// Robust z-score of a quality score against the recent ones (see relative_quality_gate.h).

#include "weighted_icp/frontend/perception/relative_quality_gate.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "weighted_icp/core/statistics.h"

namespace weighted_icp::frontend {

RelativeQualityGate::RelativeQualityGate(RelativeQualityGateOptions options) : options_(options) {
  options_.window = std::max<std::size_t>(options_.window, 1);
  options_.min_history = std::clamp<std::size_t>(options_.min_history, 1, options_.window);
}

QualityJudgement RelativeQualityGate::judge(double score, bool must_keep) {
  QualityJudgement judgement;
  judgement.score = score;
  if (!std::isfinite(score)) {
    judgement.refused = !must_keep;
    judgement.kept_anyway = must_keep;
    return judgement;
  }
  if (recent_.size() >= options_.min_history) {
    const std::vector<double> window(recent_.begin(), recent_.end());
    judgement.median = median(window);
    std::vector<double> deviations;
    deviations.reserve(window.size());
    for (const double s : window) deviations.push_back(std::abs(s - judgement.median));
    // 1.4826 MAD estimates a standard deviation for normally distributed scores.
    judgement.spread = std::max(1.4826 * median(deviations), options_.min_spread);
    judgement.z = (score - judgement.median) / judgement.spread;
    const bool bad = options_.two_sided ? std::abs(judgement.z) > options_.max_z : judgement.z > options_.max_z;
    judgement.refused = bad && !must_keep;
    judgement.kept_anyway = bad && must_keep;
  }
  recent_.push_back(score);
  if (recent_.size() > options_.window) recent_.pop_front();
  return judgement;
}

}  // namespace weighted_icp::frontend

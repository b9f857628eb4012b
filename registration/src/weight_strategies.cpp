// The built-in landmark weights, the strategies naming them, and the weights of a whole map.

#include "weighted_icp/registration/weight_strategies.h"

#include <cmath>
#include <stdexcept>

namespace weighted_icp {

double CovarianceWeight::operator()(const LandmarkMetrics& m) const {
  return 1.0 / (1.0 + m.covariance.norm());  // Eigen's Matrix::norm() is the Frobenius norm
}

double ObservationCountWeight::operator()(const LandmarkMetrics& m) const {
  return static_cast<double>(m.num_observations);
}

double MeanObservationDistanceWeight::operator()(const LandmarkMetrics& m) const {
  return 1.0 / (1.0 + m.mean_observation_distance);
}

double UniformWeight::operator()(const LandmarkMetrics&) const { return 1.0; }

const std::vector<WeightStrategy>& allWeightStrategies() {
  static const std::vector<WeightStrategy> all{WeightStrategy::Base, WeightStrategy::Covariance,
                                               WeightStrategy::Observations, WeightStrategy::MeanDistance};
  return all;
}

std::string toString(WeightStrategy strategy) {
  switch (strategy) {
    case WeightStrategy::Base: return "base";
    case WeightStrategy::Covariance: return "covariance";
    case WeightStrategy::Observations: return "observations";
    case WeightStrategy::MeanDistance: return "mean-distance";
  }
  throw std::invalid_argument("unknown weight strategy");
}

WeightStrategy parseWeightStrategy(const std::string& name) {
  for (const auto strategy : allWeightStrategies())
    if (toString(strategy) == name) return strategy;
  throw std::invalid_argument("unknown strategy '" + name +
                              "' (expected base, covariance, observations or mean-distance)");
}

WeightFunction weightFunction(WeightStrategy strategy) {
  switch (strategy) {
    case WeightStrategy::Base: return UniformWeight{};
    case WeightStrategy::Covariance: return CovarianceWeight{};
    case WeightStrategy::Observations: return ObservationCountWeight{};
    case WeightStrategy::MeanDistance: return MeanObservationDistanceWeight{};
  }
  throw std::invalid_argument("unknown weight strategy");
}

unsigned int neighboursFor(WeightStrategy strategy, unsigned int k) { return strategy == WeightStrategy::Base ? 1 : k; }

std::vector<double> computeWeights(const LandmarkMap& map, const WeightFunction& weight) {
  std::vector<double> weights;
  weights.reserve(map.landmarks.size());
  for (const auto& landmark : map.landmarks) {
    const double w = weight(map.metrics(landmark));
    if (!std::isfinite(w) || w < 0.0)
      throw std::invalid_argument("weight of landmark " + std::to_string(landmark.id) + " is " + std::to_string(w) +
                                  "; weights must be finite and >= 0");
    weights.push_back(w);
  }
  return weights;
}

}  // namespace weighted_icp

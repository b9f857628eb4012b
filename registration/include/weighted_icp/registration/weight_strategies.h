#pragma once
// Confidence of a landmark, from what the SLAM front end knows of it. The
// weighted correspondence rule picks, among the k nearest target landmarks,
// the one with the largest weight, so only the order of weights matters.

#include <functional>
#include <string>
#include <vector>

#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp {

/// Any callable `double(const LandmarkMetrics&)`; must return a finite value >= 0.
using WeightFunction = std::function<double(const LandmarkMetrics&)>;

/// 1 / (1 + ||Cov||_F). The matrix norm is the Frobenius norm (the L2 norm of
/// the nine entries), which is what the paper's code computes with
/// Eigen's Matrix::norm(); the spectral norm would rank anisotropic
/// covariances differently.
struct CovarianceWeight {
  double operator()(const LandmarkMetrics& m) const;
};

/// The number of observations: a landmark seen more often is better known.
struct ObservationCountWeight {
  double operator()(const LandmarkMetrics& m) const;
};

/// 1 / (1 + D), D the mean distance to the observing camera centres: depth
/// error of an RGB-D sensor grows with distance.
struct MeanObservationDistanceWeight {
  double operator()(const LandmarkMetrics& m) const;
};

/// 1 for every landmark: the weighted rule then picks the nearest of the k,
/// i.e. plain nearest-neighbour ICP.
struct UniformWeight {
  double operator()(const LandmarkMetrics& m) const;
};

/// The built-in strategies by name, as the command-line tools spell them:
/// "base" (uniform), "covariance", "observations", "mean-distance".
enum class WeightStrategy { Base, Covariance, Observations, MeanDistance };

const std::vector<WeightStrategy>& allWeightStrategies();
std::string toString(WeightStrategy strategy);
/// Throws std::invalid_argument listing the valid names.
WeightStrategy parseWeightStrategy(const std::string& name);
WeightFunction weightFunction(WeightStrategy strategy);

/// @brief The number of neighbours the weighted rule should consider for `strategy`.
/// Base is plain ICP: one neighbour whatever k is. Its uniform weights would make the pick among
/// k neighbours the nearest one anyway; asking for one keeps the search, and what is reported as k, honest.
/// @param strategy  the weight strategy the alignment uses
/// @param k         the neighbours asked for, used by every other strategy as is
/// @return 1 for WeightStrategy::Base, otherwise k
unsigned int neighboursFor(WeightStrategy strategy, unsigned int k);

/// One weight per landmark of `map`, in order. Throws std::invalid_argument
/// naming the landmark when `weight` returns a negative or non-finite value.
std::vector<double> computeWeights(const LandmarkMap& map, const WeightFunction& weight);

}  // namespace weighted_icp

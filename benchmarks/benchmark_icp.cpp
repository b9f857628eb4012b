// Speed of one ICP iteration on the real landmark map: stock PCL
// (pcl::IterativeClosestPoint with its CorrespondenceEstimation, k = 1)
// against the weighted rule, k = 5, with 1 and 2 search threads, both as a
// drop-in inside pcl::IterativeClosestPoint and through LandmarkAligner.
//
//   wicp_benchmark_icp [--map FILE] [--case full|halves] [--repeat N] [Google Benchmark flags]
//
// "per_icp_iteration" is the figure to compare: alignment time (wall clock)
// divided by the iterations ICP ran (both stop on PCL's default convergence
// criteria). --case halves aligns one half of the map's landmarks onto the
// other (alternate landmarks, 3,040 onto 3,041), as the sweeps do; full (the
// default) aligns the displaced map onto itself. --repeat N runs each
// benchmark exactly N times instead of for a minimum time, so that two
// processes do fixed work and can be timed against each other from outside.
//
// BM_Strategy is the total time of one whole alignment per weight strategy (LandmarkAligner, 1 thread,
// k = 5, base k = 1), with and without refinement and the "correspondences repeat" stop rule, with the
// iterations of both stages and the error against the true displacement as counters.

#include <cstdlib>
#include <functional>
#include <iostream>
#include <stdexcept>
#include <string>
#include <tuple>

#include <benchmark/benchmark.h>
#include <pcl/common/transforms.h>
#include <pcl/point_types.h>
#include <pcl/registration/correspondence_estimation.h>
#include <pcl/registration/icp.h>

#include "benchmark_arguments.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/registration/weight_strategies.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace {

using namespace weighted_icp;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

std::string map_path = std::string(WEIGHTED_ICP_DATA_DIR) + "/map_fr1_desk.txt";
std::string case_name = "full";
const Displacement kDisplacement{0.1, 0.05, 0.02, 2, 1, 10};
constexpr int kMaxIterations = 150;

/// The two maps of the chosen case, the source displaced.
const std::pair<LandmarkMap, LandmarkMap>& maps() {
  static const std::pair<LandmarkMap, LandmarkMap> m = [] {
    const LandmarkMap map = io::readLandmarkMap(map_path).withMinObservations(2);
    LandmarkMap target = map, source = map;
    if (case_name == "halves") std::tie(target, source) = map.alternateHalves();
    source.transform(kDisplacement.toIsometry());
    return std::make_pair(target, source);
  }();
  return m;
}

struct Clouds {
  LandmarkCloud::Ptr target, source;  // weighted with the covariance strategy
  Cloud::Ptr target_xyz, source_xyz;
  std::vector<double> target_weights;
};

const Clouds& clouds() {
  static const Clouds c = [] {
    const auto& [target, source] = maps();
    Clouds out;
    out.target = toLandmarkCloud(target, CovarianceWeight{});
    out.source = toLandmarkCloud(source, CovarianceWeight{});
    out.target_xyz = std::make_shared<Cloud>();
    out.source_xyz = std::make_shared<Cloud>();
    pcl::copyPointCloud(*out.target, *out.target_xyz);
    pcl::copyPointCloud(*out.source, *out.source_xyz);
    for (const auto& p : *out.target) out.target_weights.push_back(p.weight);
    return out;
  }();
  return c;
}

/// Records time per ICP iteration as a rate counter inverted: seconds/iteration.
void reportIterations(benchmark::State& state, double iterations_total, std::size_t points) {
  state.counters["icp_iterations"] = benchmark::Counter(iterations_total, benchmark::Counter::kAvgIterations);
  state.counters["per_icp_iteration"] =
      benchmark::Counter(iterations_total, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["points"] = static_cast<double>(points);
}

/// PCL exposes the iteration count only to subclasses.
template <typename Icp>
struct CountingIcp : Icp {
  int iterations() const { return this->nr_iterations_; }
};

using PclIcp = CountingIcp<pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ, double>>;

/// Aligns the clouds as a user runs PCL's ICP once: a fresh ICP (and a fresh
/// correspondence estimation from `make`, so no index or candidate survives
/// from one run to the next) each time, the kd-trees built inside align();
/// `make` null keeps PCL's own correspondence estimation.
void runPclIcp(benchmark::State& state, const std::function<PclIcp::CorrespondenceEstimationPtr()>& make) {
  const Clouds& c = clouds();
  double iterations = 0;
  for (auto _ : state) {
    PclIcp icp;
    if (make) icp.setCorrespondenceEstimation(make());
    icp.setMaximumIterations(kMaxIterations);
    icp.setInputSource(c.source_xyz);
    icp.setInputTarget(c.target_xyz);
    Cloud aligned;
    icp.align(aligned);
    iterations += icp.iterations();
  }
  reportIterations(state, iterations, c.source_xyz->size());
}

void BM_StockPclIcp(benchmark::State& state) { runPclIcp(state, nullptr); }

void BM_WeightedDropInPclIcp(benchmark::State& state) {
  runPclIcp(state, [&state]() -> PclIcp::CorrespondenceEstimationPtr {
    auto ce = std::make_shared<WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ, double>>(5);
    ce->setNumberOfThreads(static_cast<unsigned>(state.range(0)));
    ce->setCandidateReuse(state.range(1) != 0);
    ce->setTargetWeights(clouds().target_weights);
    return ce;
  });
}

void BM_LandmarkAligner(benchmark::State& state) {
  const Clouds& c = clouds();
  AlignmentSettings settings;
  settings.k = static_cast<unsigned>(state.range(0));
  settings.threads = static_cast<unsigned>(state.range(1));
  settings.max_iterations = kMaxIterations;
  LandmarkAligner aligner(settings);
  aligner.setTarget(c.target);
  double iterations = 0;
  for (auto _ : state) iterations += aligner.align(c.source).iterations;
  reportIterations(state, iterations, c.source->size());
}

/// One whole alignment per strategy: range(0) the strategy (WeightStrategy order), range(1) refinement,
/// range(2) the stop rule.
void BM_Strategy(benchmark::State& state) {
  const auto strategy = allWeightStrategies().at(static_cast<std::size_t>(state.range(0)));
  const auto& [target, source] = maps();
  const WeightFunction weight = weightFunction(strategy);
  const LandmarkCloud::Ptr target_cloud = toLandmarkCloud(target, weight);
  const LandmarkCloud::Ptr source_cloud = toLandmarkCloud(source, weight);
  AlignmentSettings settings;
  settings.k = neighboursFor(strategy, 5);
  settings.threads = 1;
  settings.max_iterations = kMaxIterations;
  settings.refine = state.range(1) != 0;
  settings.stop_on_repeated_correspondences = state.range(2) != 0;
  LandmarkAligner aligner(settings);
  aligner.setTarget(target_cloud);
  AlignmentResult result;
  for (auto _ : state) result = aligner.align(source_cloud);
  const Eigen::Isometry3d estimate(result.transformation), truth = kDisplacement.toIsometry().inverse();
  state.SetLabel(toString(strategy));
  state.counters["icp_iterations"] = result.iterations;
  state.counters["refine_iterations"] = result.refine_iterations;
  state.counters["rotation_error_deg"] = rotationErrorDeg(estimate, truth);
  state.counters["translation_error_cm"] = 100.0 * translationError(estimate, truth);
  state.counters["fitness"] = result.fitness_score;
}

/// The correspondence step alone, on the displaced clouds.
void BM_StockPclCorrespondences(benchmark::State& state) {
  const Clouds& c = clouds();
  pcl::registration::CorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ> ce;
  ce.setInputTarget(c.target_xyz);
  pcl::Correspondences out;
  for (auto _ : state) {
    ce.setInputSource(c.source_xyz);
    ce.determineCorrespondences(out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["points"] = static_cast<double>(c.source_xyz->size());
}

void BM_WeightedCorrespondences(benchmark::State& state) {
  const Clouds& c = clouds();
  WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ> ce(static_cast<unsigned>(state.range(0)));
  ce.setNumberOfThreads(static_cast<unsigned>(state.range(1)));
  ce.setCandidateReuse(state.range(2) != 0);
  ce.setTargetWeights(c.target_weights);
  ce.setInputTarget(c.target_xyz);
  pcl::Correspondences out;
  for (auto _ : state) {
    ce.setInputSource(c.source_xyz);
    ce.determineCorrespondences(out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["points"] = static_cast<double>(c.source_xyz->size());
  state.counters["reused"] = static_cast<double>(ce.getLastReusedCount());
  state.counters["candidates"] = static_cast<double>(ce.getCandidateCount());
}

/// Registers every benchmark; `repeat` > 0 fixes their iteration counts.
void registerAll(int repeat) {
  auto fix = [repeat](benchmark::internal::Benchmark* b) {
    b->UseRealTime();
    if (repeat > 0) b->Iterations(repeat);
  };
  fix(benchmark::RegisterBenchmark("BM_StockPclIcp", BM_StockPclIcp)->Unit(benchmark::kMillisecond));
  fix(benchmark::RegisterBenchmark("BM_WeightedDropInPclIcp", BM_WeightedDropInPclIcp)
          ->ArgNames({"threads", "reuse"})
          ->Args({1, 1})
          ->Args({2, 1})
          ->Args({1, 0})
          ->Args({2, 0})
          ->Unit(benchmark::kMillisecond));
  fix(benchmark::RegisterBenchmark("BM_LandmarkAligner", BM_LandmarkAligner)
          ->ArgNames({"k", "threads"})
          ->Args({5, 1})
          ->Args({5, 2})
          ->Args({1, 1})
          ->Args({1, 2})
          ->Unit(benchmark::kMillisecond));
  auto strategies = benchmark::RegisterBenchmark("BM_Strategy", BM_Strategy);
  strategies->ArgNames({"strategy", "refine", "stop_rule"})->Unit(benchmark::kMillisecond);
  for (int strategy = 0; strategy < 4; ++strategy)
    for (int refine = 0; refine < 2; ++refine)
      for (int stop_rule = 0; stop_rule < 2; ++stop_rule) strategies->Args({strategy, refine, stop_rule});
  fix(strategies);
  fix(benchmark::RegisterBenchmark("BM_StockPclCorrespondences", BM_StockPclCorrespondences)
          ->Unit(benchmark::kMicrosecond));
  fix(benchmark::RegisterBenchmark("BM_WeightedCorrespondences", BM_WeightedCorrespondences)
          ->ArgNames({"k", "threads", "reuse"})
          ->Args({1, 1, 0})
          ->Args({1, 1, 1})
          ->Args({5, 1, 0})
          ->Args({5, 1, 1})
          ->Args({5, 2, 0})
          ->Args({5, 2, 1})
          ->Unit(benchmark::kMicrosecond));
}

}  // namespace

int main(int argc, char** argv) {
  weighted_icp::benchmarks::takeOption(argc, argv, "--map", map_path);
  weighted_icp::benchmarks::takeOption(argc, argv, "--case", case_name);
  std::string repeat = "0";
  weighted_icp::benchmarks::takeOption(argc, argv, "--repeat", repeat);
  if (case_name != "full" && case_name != "halves") {
    std::cerr << "wicp_benchmark_icp: error: --case must be full or halves (got " << case_name << ")\n";
    return 2;
  }
  int repeat_count = 0;
  try {
    repeat_count = std::stoi(repeat);
    if (repeat_count < 0 || repeat_count > 1000000) throw std::out_of_range("repeat");
  } catch (const std::exception&) {
    std::cerr << "wicp_benchmark_icp: error: --repeat must be between 0 and 1000000 (got " << repeat << ")\n";
    return 2;
  }
  registerAll(repeat_count);
  return weighted_icp::benchmarks::runBenchmarks("wicp_benchmark_icp", argc, argv, [&] {
    std::cerr << "map " << map_path << " (" << case_name << "): " << clouds().source->size() << " onto "
              << clouds().target->size() << " landmarks with >= 2 observations\n";
  });
}

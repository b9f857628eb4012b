// Speed of one ICP iteration on the real landmark map: stock PCL
// (pcl::IterativeClosestPoint with its CorrespondenceEstimation, k = 1)
// against the weighted rule, k = 5, with 1 and 2 search threads, both as a
// drop-in inside pcl::IterativeClosestPoint and through LandmarkAligner.
//
//   wicp_benchmark_icp [--map FILE] [Google Benchmark flags]
//
// "per_icp_iteration" is the figure to compare: alignment time divided by the
// iterations ICP ran (both stop on PCL's default convergence criteria).

#include <cstdlib>
#include <iostream>
#include <string>

#include <benchmark/benchmark.h>
#include <pcl/common/transforms.h>
#include <pcl/point_types.h>
#include <pcl/registration/correspondence_estimation.h>
#include <pcl/registration/icp.h>

#include "benchmark_arguments.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace {

using namespace weighted_icp;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

std::string map_path = std::string(WEIGHTED_ICP_DATA_DIR) + "/map_fr1_desk.txt";
const Displacement kDisplacement{0.1, 0.05, 0.02, 2, 1, 10};
constexpr int kMaxIterations = 150;

struct Clouds {
  LandmarkCloud::Ptr target, source;  // weighted with the covariance strategy
  Cloud::Ptr target_xyz, source_xyz;
  std::vector<double> target_weights;
};

const Clouds& clouds() {
  static const Clouds c = [] {
    const LandmarkMap target = io::readLandmarkMap(map_path).withMinObservations(2);
    LandmarkMap source = target;
    source.transform(kDisplacement.toIsometry());
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

/// Aligns the clouds as a user runs PCL's ICP: a fresh ICP each time, its
/// kd-trees built inside align(); `correspondences` null keeps PCL's own.
void runPclIcp(benchmark::State& state, const PclIcp::CorrespondenceEstimationPtr& correspondences) {
  const Clouds& c = clouds();
  double iterations = 0;
  for (auto _ : state) {
    PclIcp icp;
    if (correspondences) icp.setCorrespondenceEstimation(correspondences);
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
  auto ce = std::make_shared<WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ, double>>(5);
  ce->setNumberOfThreads(static_cast<unsigned>(state.range(0)));
  ce->setTargetWeights(clouds().target_weights);
  runPclIcp(state, ce);
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
  ce.setTargetWeights(c.target_weights);
  ce.setInputTarget(c.target_xyz);
  pcl::Correspondences out;
  for (auto _ : state) {
    ce.setInputSource(c.source_xyz);
    ce.determineCorrespondences(out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["points"] = static_cast<double>(c.source_xyz->size());
}

BENCHMARK(BM_StockPclIcp)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_WeightedDropInPclIcp)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LandmarkAligner)
    ->ArgNames({"k", "threads"})
    ->Args({5, 1})
    ->Args({5, 2})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_StockPclCorrespondences)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WeightedCorrespondences)
    ->ArgNames({"k", "threads"})
    ->Args({1, 1})
    ->Args({5, 1})
    ->Args({5, 2})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  weighted_icp::benchmarks::takeOption(argc, argv, "--map", map_path);
  try {
    std::cerr << "map " << map_path << ": " << clouds().source->size() << " landmarks with >= 2 observations\n";
  } catch (const std::exception& e) {
    std::cerr << "wicp_benchmark_icp: error: " << e.what() << '\n';
    return 1;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

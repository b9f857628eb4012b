// Time of one alignment from any start on the real landmark map: the
// alternate-landmark halves (no landmark in both), the source displaced by
// yaw 180° and (1.5, -1) m. "global_search" is GlobalAlignment alone,
// "with_weighted_icp" adds the final weighted ICP with refinement, as
// wicp_align --global runs it (one search thread, so the figure does not
// depend on the machine's core count).
//
//   wicp_benchmark_global_alignment [--map FILE] [Google Benchmark flags]

#include <iostream>
#include <string>

#include <benchmark/benchmark.h>
#include <pcl/common/io.h>

#include "benchmark_arguments.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/registration/global_landmark_alignment.h"
#include "weighted_icp/registration/rigid_motion.h"

namespace {

using namespace weighted_icp;

std::string map_path = std::string(WEIGHTED_ICP_DATA_DIR) + "/map_fr1_desk.txt";

struct Pair {
  LandmarkCloud::Ptr source, target;
};

const Pair& pair() {
  static const Pair p = [] {
    auto [even, odd] = io::readLandmarkMap(map_path).withMinObservations(2).alternateHalves();
    odd.transform(Displacement{1.5, -1.0, 0.0, 0.0, 0.0, 180.0}.toIsometry());
    return Pair{toLandmarkCloud(odd, CovarianceWeight{}), toLandmarkCloud(even, CovarianceWeight{})};
  }();
  return p;
}

void BM_GlobalSearch(benchmark::State& state) {
  GlobalAlignment::Cloud source, target;
  pcl::copyPointCloud(*pair().source, source);
  pcl::copyPointCloud(*pair().target, target);
  GlobalAlignment global;
  global.setTarget(target);
  for (auto _ : state) benchmark::DoNotOptimize(global.align(source).inliers);
  state.counters["points"] = static_cast<double>(source.size());
}

void BM_GlobalWithWeightedIcp(benchmark::State& state) {
  AlignmentSettings icp;
  icp.threads = 1;
  GlobalLandmarkAligner aligner({}, icp);
  aligner.setTarget(pair().target);
  for (auto _ : state) benchmark::DoNotOptimize(aligner.align(pair().source).alignment.iterations);
}

BENCHMARK(BM_GlobalSearch)->Name("global_search")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlobalWithWeightedIcp)->Name("with_weighted_icp")->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  weighted_icp::benchmarks::takeOption(argc, argv, "--map", map_path);
  return weighted_icp::benchmarks::runBenchmarks("wicp_benchmark_global_alignment", argc, argv, [] {
    std::cerr << "map " << map_path << ": " << pair().source->size() << " + " << pair().target->size()
              << " landmarks with >= 2 observations\n";
  });
}

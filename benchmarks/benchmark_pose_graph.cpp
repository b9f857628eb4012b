// Time of one pose-graph optimisation per loop, as the loop closer runs it: a drifted circle of N keyframes with
// odometry edges and the loop edge that closes it (odometry solve + one gated loop solve), N = 100 and 1000.
// Also the graph built from scratch each time, as LoopCloser does.
//
//   wicp_benchmark_pose_graph [Google Benchmark flags]

#include <benchmark/benchmark.h>

#include "pose_graph_fixtures.h"
#include "weighted_icp/mapping/pose_graph.h"

namespace {

using namespace weighted_icp;

void BM_PoseGraphPerLoop(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  // The same drift per metre whatever N: the circle grows with N.
  const testing::DriftedLoop loop = testing::makeDriftedLoop(n, 0.05 * static_cast<double>(n), 6.0 / n, 0.005);
  std::size_t used = 0;
  for (auto _ : state) {
    mapping::PoseGraph graph = testing::makeOdometryGraph(loop);
    graph.addEdge(testing::trueLoopEdge(loop, 0, n - 1));
    const auto summary = graph.optimize();
    used += summary.loops_used;
    benchmark::DoNotOptimize(graph.poses());
  }
  if (used != static_cast<std::size_t>(state.iterations())) state.SkipWithError("the loop was not admitted");
  state.counters["keyframes"] = static_cast<double>(n);
}
BENCHMARK(BM_PoseGraphPerLoop)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

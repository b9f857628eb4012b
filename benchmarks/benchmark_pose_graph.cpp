// Time of one pose-graph optimisation per loop, as the loop closer runs it: a drifted circle of N keyframes with
// odometry edges and the loop edge that closes it (odometry solve + one gated loop solve), N = 100 and 1000.
// Also the graph built from scratch each time, as LoopCloser does. And a closure late in a run: 200 keyframes, 40
// loops accepted earlier and one new, the earlier ones tested together (admitted_before, as LoopCloser marks them)
// or, as before 2026-11-26, each alone.
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

/// range(0): 1 = the earlier loops marked admitted_before (tested together), 0 = not (each tested alone).
void BM_PoseGraphClosureWithEarlierLoops(benchmark::State& state) {
  const bool together = state.range(0) != 0;
  constexpr std::size_t kKeyframes = 200, kEarlier = 40;
  const testing::DriftedLoop loop = testing::makeDriftedLoop(kKeyframes, 10.0, 0.03, 0.005);
  std::size_t used = 0, solves = 0;
  for (auto _ : state) {
    mapping::PoseGraph graph = testing::makeOdometryGraph(loop);
    // The camera came back over its start: keyframes 160-199 revisit 0-39.
    for (std::size_t i = 0; i <= kEarlier; ++i) {
      mapping::PoseGraphEdge edge = testing::trueLoopEdge(loop, i, kKeyframes - 1 - kEarlier + i);
      edge.admitted_before = together && i < kEarlier;
      graph.addEdge(edge);
    }
    const auto summary = graph.optimize();
    used += summary.loops_used;
    solves += summary.solves;
    benchmark::DoNotOptimize(graph.poses());
  }
  if (used != (kEarlier + 1) * static_cast<std::size_t>(state.iterations()))
    state.SkipWithError("a true loop was refused");
  state.counters["solves"] = static_cast<double>(solves) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_PoseGraphClosureWithEarlierLoops)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

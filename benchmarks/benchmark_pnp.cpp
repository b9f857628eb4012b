// Time of the front end's RANSAC PnP with Huber refinement (estimatePosePnp) on synthetic matches, by how many of
// them are right and by the most RANSAC draws allowed: OpenCV stops once the best consensus gives 99 %
// confidence, so many draws cost only where few matches are right, and most where none is (the whole budget).
// Each run reports the fraction of calls that found a pose ("found").
//
//   wicp_benchmark_pnp [Google Benchmark flags]

#include <benchmark/benchmark.h>

#include "test_geometry_scene.h"
#include "weighted_icp/frontend/geometry/pose_estimation.h"

namespace {

using namespace weighted_icp;

/// range(0): matches; range(1): percent of them right; range(2): most RANSAC draws. Ten scenes, taken in turn.
void BM_PnpRansac(benchmark::State& state) {
  const int matches = static_cast<int>(state.range(0));
  const double outliers = 1.0 - static_cast<double>(state.range(1)) / 100.0;
  frontend::PnpOptions options;
  options.ransac_iterations = static_cast<int>(state.range(2));
  const PinholeCamera camera = testing::syntheticCamera();
  const Eigen::Isometry3d truth_wc = testing::makePose({5, -10, 3}, {0.3, -0.2, 0.5});
  std::vector<testing::PnpScene> scenes;
  for (unsigned seed = 0; seed < 10; ++seed)
    scenes.push_back(testing::makePnpScene(camera, truth_wc, matches, 1.0, outliers, 100 + seed));
  std::size_t call = 0, found = 0;
  for (auto _ : state) {
    const testing::PnpScene& scene = scenes[call++ % scenes.size()];
    const frontend::PoseEstimate estimate =
        frontend::estimatePosePnp(scene.points, scene.pixels, camera, std::nullopt, options);
    found += estimate.ok ? 1 : 0;
    benchmark::DoNotOptimize(estimate.pose_wc);
  }
  state.counters["found"] = static_cast<double>(found) / static_cast<double>(call);
}
BENCHMARK(BM_PnpRansac)
    ->ArgNames({"matches", "right%", "draws"})
    ->ArgsProduct({{80, 300}, {100, 50, 25, 0}, {100, 1000}})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

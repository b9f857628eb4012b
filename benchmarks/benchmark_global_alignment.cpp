// Time of one alignment from any start on the real landmark map: the
// alternate-landmark halves (no landmark in both), the source displaced by
// yaw 180° and (1.5, -1) m. "global_search" is GlobalAlignment alone,
// "with_weighted_icp" adds the final weighted ICP with refinement, as
// wicp_align --global runs it; "camera_frame" is the same pair written in the
// map's first camera's frame and turned about the true up by 120°, so that
// each map is levelled by its cameras, tilts are tried and the search about z
// runs as well (GlobalLandmarkAligner::align with chooseUpAxes's axes);
// "z_up_auto" is the first pair with the axes chooseUpAxes gives it, as
// wicp_align --global's default --up-axis auto: z, with tilts; "one_heading"
// is the map in its first camera's frame and its mini-map of frames 150-189
// (their landmarks both hold dealt out by id parity), whose cameras face about
// one way, turned 90° about the true up onto the whole map: its pitched
// levellings are looked at first and the promising ones searched. The
// argument is the number of search threads (1, 2): the same result on each.
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
#include "weighted_icp/registration/up_axis.h"

namespace {

using namespace weighted_icp;

std::string map_path = std::string(WEIGHTED_ICP_DATA_DIR) + "/map_fr1_desk.txt";

struct Pair {
  LandmarkCloud::Ptr source, target;
  SharedUpAxes axes;  // chooseUpAxes's: both z-up, searched with tilts
};

const Pair& pair() {
  static const Pair p = [] {
    auto [even, odd] = io::readLandmarkMap(map_path).withMinObservations(2).alternateHalves();
    odd.transform(Displacement{1.5, -1.0, 0.0, 0.0, 0.0, 180.0}.toIsometry());
    return Pair{toLandmarkCloud(odd, CovarianceWeight{}), toLandmarkCloud(even, CovarianceWeight{}),
                chooseUpAxes(estimateUpAxis(odd.frames), estimateUpAxis(even.frames))};
  }();
  return p;
}

/// The pair in the first camera's frame, the source turned by 120° about the true up (the world's z there), and
/// the axes chooseUpAxes gives it.
struct CameraFramePair {
  LandmarkCloud::Ptr source, target;
  SharedUpAxes axes;
};

const CameraFramePair& cameraFramePair() {
  static const CameraFramePair p = [] {
    LandmarkMap map = io::readLandmarkMap(map_path).withMinObservations(2);
    const Eigen::Isometry3d first = map.toFirstCameraFrame();
    auto [even, odd] = map.alternateHalves();
    Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
    turn.linear() =
        Eigen::AngleAxisd(2.0 * M_PI / 3.0, first.linear().transpose() * Eigen::Vector3d::UnitZ()).toRotationMatrix();
    turn.translation() = Eigen::Vector3d(0.5, -0.3, 0.2);
    odd.transform(turn);
    return CameraFramePair{toLandmarkCloud(odd, CovarianceWeight{}), toLandmarkCloud(even, CovarianceWeight{}),
                           chooseUpAxes(estimateUpAxis(odd.frames), estimateUpAxis(even.frames))};
  }();
  return p;
}

/// The whole map and its mini-map of frames 150-189 in the first camera's frame, the landmarks both hold dealt out
/// by id parity (the mini-map the even ones), the mini-map turned 90° about the true up: {source mini, target whole}.
const CameraFramePair& oneHeadingPair() {
  static const CameraFramePair p = [] {
    LandmarkMap map = io::readLandmarkMap(map_path);
    const Eigen::Isometry3d first = map.toFirstCameraFrame();
    LandmarkMap mini = map.miniMap(150, 189);
    dealOutSharedLandmarks(mini, map);
    map = map.withMinObservations(2), mini = mini.withMinObservations(2);
    Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
    turn.linear() =
        Eigen::AngleAxisd(M_PI / 2.0, first.linear().transpose() * Eigen::Vector3d::UnitZ()).toRotationMatrix();
    mini.transform(turn);
    return CameraFramePair{toLandmarkCloud(mini, CovarianceWeight{}), toLandmarkCloud(map, CovarianceWeight{}),
                           chooseUpAxes(estimateUpAxis(mini.frames), estimateUpAxis(map.frames))};
  }();
  return p;
}

GlobalAlignmentSettings searchThreads(const benchmark::State& state) {
  GlobalAlignmentSettings settings;
  settings.threads = static_cast<unsigned>(state.range(0));
  return settings;
}

void BM_GlobalSearch(benchmark::State& state) {
  GlobalAlignment::Cloud source, target;
  pcl::copyPointCloud(*pair().source, source);
  pcl::copyPointCloud(*pair().target, target);
  GlobalAlignment global(searchThreads(state));
  global.setTarget(target);
  for (auto _ : state) benchmark::DoNotOptimize(global.align(source).inliers);
  state.counters["points"] = static_cast<double>(source.size());
}

void BM_GlobalWithWeightedIcp(benchmark::State& state) {
  AlignmentSettings icp;
  icp.threads = static_cast<unsigned>(state.range(0));
  GlobalLandmarkAligner aligner(searchThreads(state), icp);
  aligner.setTarget(pair().target);
  for (auto _ : state) benchmark::DoNotOptimize(aligner.align(pair().source).alignment.iterations);
}

void BM_CameraFrame(benchmark::State& state) {
  AlignmentSettings icp;
  icp.threads = static_cast<unsigned>(state.range(0));
  GlobalLandmarkAligner aligner(searchThreads(state), icp);
  aligner.setTarget(cameraFramePair().target);
  for (auto _ : state)
    benchmark::DoNotOptimize(aligner.align(cameraFramePair().source, cameraFramePair().axes).alignment.iterations);
}

void BM_ZUpAuto(benchmark::State& state) {
  AlignmentSettings icp;
  icp.threads = static_cast<unsigned>(state.range(0));
  GlobalLandmarkAligner aligner(searchThreads(state), icp);
  aligner.setTarget(pair().target);
  for (auto _ : state) benchmark::DoNotOptimize(aligner.align(pair().source, pair().axes).alignment.iterations);
  state.counters["tilt_range_deg"] = pair().axes.tilt_range_deg;
}

void BM_OneHeading(benchmark::State& state) {
  AlignmentSettings icp;
  icp.threads = static_cast<unsigned>(state.range(0));
  GlobalLandmarkAligner aligner(searchThreads(state), icp);
  aligner.setTarget(oneHeadingPair().target);
  std::size_t searched = 0;
  for (auto _ : state) searched = aligner.align(oneHeadingPair().source, oneHeadingPair().axes).alternatives_searched;
  state.counters["alternatives"] = static_cast<double>(oneHeadingPair().axes.alternatives.size());
  state.counters["searched"] = static_cast<double>(searched);
}

BENCHMARK(BM_GlobalSearch)->Name("global_search")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlobalWithWeightedIcp)->Name("with_weighted_icp")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CameraFrame)->Name("camera_frame")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ZUpAuto)->Name("z_up_auto")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OneHeading)->Name("one_heading")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  weighted_icp::benchmarks::takeOption(argc, argv, "--map", map_path);
  return weighted_icp::benchmarks::runBenchmarks("wicp_benchmark_global_alignment", argc, argv, [] {
    std::cerr << "map " << map_path << ": " << pair().source->size() << " + " << pair().target->size()
              << " landmarks with >= 2 observations\n";
  });
}

// How ICP's time per iteration and its memory grow with the number of points: stock PCL
// (pcl::IterativeClosestPoint with its CorrespondenceEstimation, k = 1) against the weighted rule (k = 5,
// WeightedCorrespondenceEstimation inside the same ICP), on landmark maps of 3k, 30k and 300k points and on
// dense clouds back-projected from TUM RGB-D depth images (300k and ~1M points).
//
//   wicp_benchmark_scale [--map FILE] [--data DIR] [--iterations N] [--all] [Google Benchmark flags]
//
// By default only the 3k and 30k landmark maps run (a few seconds); --all adds the 300k map and the dense
// clouds (about 170 s of CPU with the default 10 iterations; more than that in wall time on a loaded machine).
//
// Every alignment is a fresh ICP, as a user runs it (index build included), with PCL's convergence tests
// disabled so that it runs exactly N iterations (default 10): "per_icp_iteration" is its wall time / N.
// Memory: "peak_extra_MB" is the process's peak resident memory during the alignment (Linux VmHWM, reset
// through /proc/self/clear_refs before it) minus its resident memory before it, so the clouds themselves,
// built beforehand, are not in it (malloc_trim first returns what earlier benchmarks freed); NaN where the
// kernel refuses the reset.
//
// Landmark maps: 3k is the real map's two alternate halves (3,040 onto 3,041 landmarks, covariance weights),
// as wicp_benchmark_icp --case halves. 30k and 300k are a synthetic enlargement of that pair: 10 and 100
// copies of it tiled side by side on a grid in x and y (each copy shifted by the map's extent, so the
// density stays that of the real map, as in a long merged session), every copied point jittered by a
// Gaussian of 5 mm per axis (seeded), weights copied. The source is then displaced as in wicp_benchmark_icp.
// Dense clouds: the first frames of the TUM sequence (freiburg 1 calibration, depth back-projected without
// undistortion, placed in the world frame by the ground truth); target = frames 0 (and 1, 2, 3 for ~1M),
// source = frames 4 (and 5, 6, 7), displaced; the grey value / 255 is the weight.

#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <malloc.h>

#include <benchmark/benchmark.h>
#include <pcl/common/common.h>
#include <pcl/common/transforms.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>

#include "benchmark_arguments.h"
#include "weighted_icp/core/camera.h"
#include "weighted_icp/io/map_format.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/registration/landmark_point.h"
#include "weighted_icp/registration/rigid_motion.h"
#include "weighted_icp/registration/weight_strategies.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace {

using namespace weighted_icp;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

std::string map_path = std::string(WEIGHTED_ICP_DATA_DIR) + "/map_fr1_desk.txt";
std::string tum_path = std::string(WEIGHTED_ICP_DATA_DIR) + "/tum_fr1_xyz_head";
int icp_iterations = 10;
const Displacement kDisplacement{0.1, 0.05, 0.02, 2, 1, 10};

struct WeightedCloud {
  Cloud::Ptr points = std::make_shared<Cloud>();
  std::vector<double> weights;
};

struct Pair {
  WeightedCloud target, source;
};

/// Copies of `in` tiled `copies` times on a square grid in x and y, every point jittered.
WeightedCloud tiled(const WeightedCloud& in, int copies, const Eigen::Vector3f& extent, std::mt19937& random) {
  if (copies == 1) return in;
  std::normal_distribution<float> jitter(0.0f, 0.005f);
  const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(copies))));
  WeightedCloud out;
  out.points->reserve(in.points->size() * static_cast<std::size_t>(copies));
  for (int c = 0; c < copies; ++c) {
    const Eigen::Vector3f shift((c % columns) * extent.x(), (c / columns) * extent.y(), 0.0f);
    for (std::size_t i = 0; i < in.points->size(); ++i) {
      const pcl::PointXYZ& p = (*in.points)[i];
      out.points->push_back(
          pcl::PointXYZ(p.x + shift.x() + jitter(random), p.y + shift.y() + jitter(random), p.z + jitter(random)));
      out.weights.push_back(in.weights[i]);
    }
  }
  return out;
}

WeightedCloud fromLandmarks(const LandmarkMap& map) {
  WeightedCloud out;
  const LandmarkCloud::Ptr cloud = toLandmarkCloud(map, CovarianceWeight{});  // alive through the loop
  for (const auto& p : *cloud) {
    out.points->push_back(pcl::PointXYZ(p.x, p.y, p.z));
    out.weights.push_back(p.weight);
  }
  return out;
}

void displace(WeightedCloud& cloud) {
  const Eigen::Matrix4f motion = kDisplacement.toIsometry().matrix().cast<float>();
  pcl::transformPointCloud(*cloud.points, *cloud.points, motion);
}

Pair landmarkPair(int copies) {
  const LandmarkMap map = io::readLandmarkMap(map_path).withMinObservations(2);
  const auto [target_map, source_map] = map.alternateHalves();
  Pair pair{fromLandmarks(target_map), fromLandmarks(source_map)};
  Eigen::Vector4f low, high;
  pcl::getMinMax3D(*pair.target.points, low, high);
  const Eigen::Vector3f extent = (high - low).head<3>();
  std::mt19937 random(8);
  pair.target = tiled(pair.target, copies, extent, random);
  pair.source = tiled(pair.source, copies, extent, random);
  displace(pair.source);
  return pair;
}

/// Frames [first, first + count) back-projected into the world frame by the ground truth.
WeightedCloud depthFrames(const io::TumSequence& sequence, std::size_t first, std::size_t count) {
  const PinholeCamera camera = tumCamera(1);
  WeightedCloud out;
  for (std::size_t f = first; f < first + count; ++f) {
    const RgbdFrame frame = sequence.loadFrame(f, camera);
    const auto pose = sequence.groundTruthAt(frame.timestamp);
    if (!pose) throw std::runtime_error(tum_path + ": frame " + std::to_string(f) + " has no ground truth");
    const cv::Mat gray = frame.gray();
    for (int v = 0; v < frame.depth.rows; ++v)
      for (int u = 0; u < frame.depth.cols; ++u) {
        const float depth = frame.depth.at<float>(v, u);
        if (!(depth > 0.0f)) continue;
        const Eigen::Vector3f p = (*pose * camera.backProject(u, v, depth)).cast<float>();
        out.points->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
        out.weights.push_back(gray.at<unsigned char>(v, u) / 255.0);
      }
  }
  return out;
}

Pair densePair(std::size_t frames_per_cloud) {
  const io::TumSequence sequence = io::TumSequence::open(tum_path);
  if (sequence.size() < 2 * frames_per_cloud)
    throw std::runtime_error(tum_path + ": needs " + std::to_string(2 * frames_per_cloud) + " frames, has " +
                             std::to_string(sequence.size()));
  Pair pair{depthFrames(sequence, 0, frames_per_cloud), depthFrames(sequence, frames_per_cloud, frames_per_cloud)};
  displace(pair.source);
  return pair;
}

struct Case {
  const char* name;
  std::function<Pair()> make;
  bool quick;  // in the default run
};

const std::vector<Case>& cases() {
  static const std::vector<Case> all = {
      {"landmarks_3k", [] { return landmarkPair(1); }, true},
      {"landmarks_30k", [] { return landmarkPair(10); }, true},
      {"landmarks_300k", [] { return landmarkPair(100); }, false},
      {"dense_300k", [] { return densePair(1); }, false},
      {"dense_1M", [] { return densePair(4); }, false},
  };
  return all;
}

/// The pair of case `index`, built on first use and kept (one at a time: a new case frees the last).
const Pair& pairFor(std::size_t index) {
  static std::size_t held = std::numeric_limits<std::size_t>::max();
  static std::unique_ptr<Pair> pair;
  if (held != index) {
    pair.reset();
    pair = std::make_unique<Pair>(cases()[index].make());
    held = index;
  }
  return *pair;
}

/// Resident memory in kB from /proc/self/status ("VmRSS" or "VmHWM"); -1 when unreadable.
double statusKb(const std::string& field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind(field + ":", 0) == 0) return std::stod(line.substr(field.size() + 1));
  return -1.0;
}

/// Resets the peak resident memory (VmHWM) to the current one; false when the kernel refuses.
bool resetPeakMemory() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return static_cast<bool>(clear);
}

/// PCL exposes the iteration count only to subclasses.
struct CountingIcp : pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ, double> {
  int iterations() const { return nr_iterations_; }
};

/// Runs a fresh ICP of exactly `icp_iterations` iterations per benchmark iteration; `k` 0 is stock PCL.
void BM_Scale(benchmark::State& state, std::size_t case_index, unsigned k, unsigned threads) {
  const Pair& pair = pairFor(case_index);
  malloc_trim(0);  // what earlier benchmarks freed goes back to the system, so it cannot hide our growth
  const double rss_before = statusKb("VmRSS");
  const bool peak_known = resetPeakMemory();
  double iterations = 0;
  for (auto _ : state) {
    CountingIcp icp;
    if (k > 0) {
      auto ce = std::make_shared<WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ, double>>(k);
      ce->setNumberOfThreads(threads);
      ce->setTargetWeights(pair.target.weights);
      icp.setCorrespondenceEstimation(ce);
    }
    icp.setMaximumIterations(icp_iterations);
    // Neither transformation nor MSE tests can stop it: exactly icp_iterations iterations.
    icp.setTransformationEpsilon(-1.0);
    icp.getConvergeCriteria()->setAbsoluteMSE(-1.0);
    icp.setInputSource(pair.source.points);
    icp.setInputTarget(pair.target.points);
    Cloud aligned;
    icp.align(aligned);
    iterations += icp.iterations();
  }
  state.counters["per_icp_iteration"] =
      benchmark::Counter(iterations, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["points"] = static_cast<double>(pair.source.points->size());
  state.counters["target_points"] = static_cast<double>(pair.target.points->size());
  state.counters["peak_extra_MB"] =
      peak_known ? (statusKb("VmHWM") - rss_before) / 1024.0 : std::numeric_limits<double>::quiet_NaN();
}

/// Registers the quick cases, or every case when `all`.
void registerAll(bool all) {
  for (std::size_t c = 0; c < cases().size(); ++c) {
    if (!all && !cases()[c].quick) continue;
    const std::string name = cases()[c].name;
    auto add = [&](const std::string& label, unsigned k, unsigned threads) {
      benchmark::RegisterBenchmark(("BM_Scale/" + name + "/" + label).c_str(),
                                   [c, k, threads](benchmark::State& s) { BM_Scale(s, c, k, threads); })
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
    };
    add("stock_pcl_k1", 0, 1);
    add("weighted_k5_threads1", 5, 1);
    add("weighted_k5_threads2", 5, 2);
  }
}

}  // namespace

int main(int argc, char** argv) {
  weighted_icp::benchmarks::takeOption(argc, argv, "--map", map_path);
  weighted_icp::benchmarks::takeOption(argc, argv, "--data", tum_path);
  std::string iterations = "10";
  weighted_icp::benchmarks::takeOption(argc, argv, "--iterations", iterations);
  try {
    icp_iterations = std::stoi(iterations);
    if (icp_iterations < 1 || icp_iterations > 1000) throw std::out_of_range("iterations");
  } catch (const std::exception&) {
    std::cerr << "wicp_benchmark_scale: error: --iterations must be between 1 and 1000 (got " << iterations << ")\n";
    return 2;
  }
  bool all = false;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--all") {
      all = true;
      for (int j = i; j + 1 <= argc; ++j) argv[j] = argv[j + 1];
      --argc;
      break;
    }
  registerAll(all);
  return weighted_icp::benchmarks::runBenchmarks("wicp_benchmark_scale", argc, argv, [] {
    if (!std::ifstream(map_path)) throw std::runtime_error("cannot read the map " + map_path);
    io::TumSequence::open(tum_path);  // reports a missing or malformed sequence before any benchmark runs
  });
}

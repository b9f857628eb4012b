// Speed of the perception layer on real TUM frames: FeatureExtractor::extract
// on a 640x480 frame, depth registration (ours and OpenCV's), and descriptor matching with FLANN LSH against brute
// force, with the index build inside and outside the timed loop. Each match
// benchmark reports the fraction of its matches (with depth) that the
// ground-truth motion puts within 5 px, as "inlier_fraction".
//
//   wicp_benchmark_matching [--data DIR] [Google Benchmark flags]
//
// DIR holds tum_fr1_xyz_head and tum_fr3_teddy_head (default: the project's
// shared data folder). CPU is process time, all threads (OpenCV may run
// brute-force matching in parallel); on a shared machine it is the fairer
// cost figure than wall time.

#include <cmath>
#include <iostream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/imgproc.hpp>

#include "benchmark_arguments.h"
#include "test_perception_support.h"
#include "weighted_icp/frontend/perception/depth_registration.h"
#include "weighted_icp/frontend/perception/descriptor_matcher.h"
#include "weighted_icp/frontend/perception/feature_extractor.h"

namespace {

using namespace weighted_icp;
using frontend::DescriptorMatcher;
using frontend::DescriptorMatcherOptions;
using frontend::ExtractedFeatures;
using frontend::FeatureExtractor;
using frontend::FeatureExtractorOptions;
using frontend::MatcherKind;
using weighted_icp::testing::RealSequence;

std::string data_dir = WEIGHTED_ICP_DATA_DIR;

struct Sequence {
  const char* name;
  const char* folder;
  int freiburg;
};
const Sequence kSequences[] = {{"fr1_xyz", "tum_fr1_xyz_head", 1}, {"fr3_teddy", "tum_fr3_teddy_head", 3}};

const RealSequence& openSequence(const Sequence& s) {
  static std::map<const Sequence*, RealSequence> opened;
  auto it = opened.find(&s);
  if (it == opened.end()) it = opened.emplace(&s, RealSequence::open(data_dir + "/" + s.folder, s.freiburg)).first;
  return it->second;
}

/// A map-like reference (up to 2000 descriptors) and a frame-like query (up
/// to 1000): min_distance_px 5 rather than 8 so that the frames fill these budgets.
FeatureExtractorOptions denseOptions(int max_features) {
  FeatureExtractorOptions options;
  options.max_features = max_features;
  options.min_distance_px = 5.0;
  return options;
}

struct Pair {
  const Sequence* sequence;
  std::size_t reference_frame, query_frame;
  ExtractedFeatures reference, query;
};

Pair loadPair(const Sequence& s, std::size_t reference_frame, std::size_t query_frame) {
  const RealSequence& data = openSequence(s);
  return {&s, reference_frame, query_frame,
          FeatureExtractor(denseOptions(2000)).extract(data.frame(reference_frame).gray()),
          FeatureExtractor(denseOptions(1000)).extract(data.frame(query_frame).gray())};
}

void reportMatches(benchmark::State& state, const Pair& p, const std::vector<cv::DMatch>& matches) {
  const auto check =
      weighted_icp::testing::checkAgainstGroundTruth(openSequence(*p.sequence), p.reference_frame, p.query_frame,
                                                     p.reference.keypoints, p.query.keypoints, matches, 5.0);
  state.counters["reference"] = p.reference.descriptors.rows;
  state.counters["query"] = p.query.descriptors.rows;
  state.counters["matches"] = static_cast<double>(matches.size());
  state.counters["inlier_fraction"] = check.fraction();
}

void BM_MatchWithIndexBuild(benchmark::State& state, const Pair& p, DescriptorMatcherOptions options) {
  std::vector<cv::DMatch> matches;
  for (auto _ : state) {
    DescriptorMatcher matcher(options);
    matcher.setReference(p.reference.descriptors);
    matches = matcher.match(p.query.descriptors);
    benchmark::DoNotOptimize(matches.data());
  }
  reportMatches(state, p, matches);
}

void BM_MatchWithoutIndexBuild(benchmark::State& state, const Pair& p, DescriptorMatcherOptions options) {
  DescriptorMatcher matcher(options);
  matcher.setReference(p.reference.descriptors);
  std::vector<cv::DMatch> matches;
  for (auto _ : state) {
    matches = matcher.match(p.query.descriptors);
    benchmark::DoNotOptimize(matches.data());
  }
  reportMatches(state, p, matches);
}

void BM_Extract(benchmark::State& state, cv::Mat gray) {
  const FeatureExtractor extractor;
  ExtractedFeatures features;
  for (auto _ : state) {
    features = extractor.extract(gray);
    benchmark::DoNotOptimize(features.descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(features.keypoints.size());
  state.counters["used_clahe"] = features.used_clahe;
}

/// Registering a real depth image as an unregistered sensor's (the variant's depth camera: 2.5 cm aside, 0.5 deg
/// turned) with `registration`: ours or OpenCV's registerDepth.
void BM_RegisterDepth(benchmark::State& state, cv::Mat depth, PinholeCamera camera,
                      cv::Mat (*registration)(const cv::Mat&, const PinholeCamera&)) {
  cv::Mat registered;
  for (auto _ : state) {
    registered = registration(depth, camera);
    benchmark::DoNotOptimize(registered.data);
  }
  state.counters["valid_pixels"] = cv::countNonZero(registered > 0.0f);
}

/// Each matcher on each pair, with and without building its index.
void registerMatching(const std::vector<Pair>& pairs) {
  for (const Pair& p : pairs) {
    const std::string pair_name = std::string(p.sequence->name) + "/" + std::to_string(p.reference_frame) + "_to_" +
                                  std::to_string(p.query_frame);
    for (const MatcherKind kind :
         {MatcherKind::FlannLsh, MatcherKind::Lsh, MatcherKind::BruteForce, MatcherKind::KdTree}) {
      DescriptorMatcherOptions options;
      options.kind = kind;
      const std::string kind_name = frontend::matcherKindName(kind);
      benchmark::RegisterBenchmark(("BM_Match/" + kind_name + "/with_build/" + pair_name).c_str(),
                                   BM_MatchWithIndexBuild, std::cref(p), options)
          ->Unit(benchmark::kMillisecond)
          ->MeasureProcessCPUTime();
      benchmark::RegisterBenchmark(("BM_Match/" + kind_name + "/without_build/" + pair_name).c_str(),
                                   BM_MatchWithoutIndexBuild, std::cref(p), options)
          ->Unit(benchmark::kMillisecond)
          ->MeasureProcessCPUTime();
    }
  }
}

/// Feature extraction on a frame of `s`, and on a dark, low-contrast copy of it.
void registerExtraction(const Sequence& s) {
  const cv::Mat gray = openSequence(s).frame(s.freiburg == 1 ? 0 : 10).gray();
  benchmark::RegisterBenchmark((std::string("BM_Extract/") + s.name).c_str(), BM_Extract, gray)
      ->Unit(benchmark::kMillisecond)
      ->MeasureProcessCPUTime();
  // A dark, low-contrast copy (gray * 0.2 + 20): too few corners, so the
  // extractor equalises (CLAHE) and detects a second time.
  cv::Mat dark;
  gray.convertTo(dark, CV_8U, 0.2, 20.0);
  benchmark::RegisterBenchmark((std::string("BM_Extract/") + s.name + "_dark").c_str(), BM_Extract, dark)
      ->Unit(benchmark::kMillisecond)
      ->MeasureProcessCPUTime();
}

/// Depth registration, ours and OpenCV's, of a frame of `s` from a depth camera 2.5 cm aside and turned 0.5°, at the
/// colour camera's resolution and at half of it.
void registerDepthRegistration(const Sequence& s) {
  PinholeCamera camera = tumCamera(s.freiburg);
  camera.unregistered_depth =
      DepthCamera{camera.fx, camera.fy, camera.cx, camera.cy, {0.025, 0.0, 0.0}, {0.0, 0.5 * M_PI / 180.0, 0.0}};
  const cv::Mat depth = openSequence(s).frame(s.freiburg == 1 ? 0 : 10).depth;
  benchmark::RegisterBenchmark((std::string("BM_RegisterDepth/ours/") + s.name).c_str(), BM_RegisterDepth, depth,
                               camera, &frontend::registerDepthToColor)
      ->Unit(benchmark::kMillisecond)
      ->MeasureProcessCPUTime();
  benchmark::RegisterBenchmark((std::string("BM_RegisterDepth/opencv/") + s.name).c_str(), BM_RegisterDepth, depth,
                               camera, &frontend::registerDepthWithOpenCv)
      ->Unit(benchmark::kMillisecond)
      ->MeasureProcessCPUTime();
  // A depth camera of half the colour camera's resolution (each depth pixel drawn over 3 x 3 colour pixels).
  PinholeCamera half = camera;
  half.unregistered_depth = half.unregistered_depth->resampled(0.5, 0.5);
  half.unregistered_depth->width = camera.width / 2;
  half.unregistered_depth->height = camera.height / 2;
  cv::Mat half_depth;
  cv::resize(depth, half_depth, half.depthImageSize(), 0.0, 0.0, cv::INTER_NEAREST);
  for (const auto& [name, function] :
       {std::pair{"ours", &frontend::registerDepthToColor}, std::pair{"opencv", &frontend::registerDepthWithOpenCv}})
    benchmark::RegisterBenchmark((std::string("BM_RegisterDepth/") + name + "/half_resolution_depth/" + s.name).c_str(),
                                 BM_RegisterDepth, half_depth, half, function)
        ->Unit(benchmark::kMillisecond)
        ->MeasureProcessCPUTime();
}

void registerBenchmarks() {
  static std::vector<Pair> pairs;  // outlive the registered benchmarks
  // fr3's ground truth starts after its first frames.
  pairs.push_back(loadPair(kSequences[0], 0, 5));
  pairs.push_back(loadPair(kSequences[0], 10, 15));
  pairs.push_back(loadPair(kSequences[1], 10, 15));
  pairs.push_back(loadPair(kSequences[1], 20, 25));
  registerMatching(pairs);
  for (const Sequence& s : kSequences) {
    registerExtraction(s);
    registerDepthRegistration(s);
  }
}

}  // namespace

int main(int argc, char** argv) {
  weighted_icp::benchmarks::takeOption(argc, argv, "--data", data_dir);
  return weighted_icp::benchmarks::runBenchmarks("wicp_benchmark_matching", argc, argv, [] { registerBenchmarks(); });
}

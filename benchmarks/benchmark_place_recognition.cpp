// Speed of loop detection per keyframe, on a synthetic loop (keyframes at
// true poses, as the mapping tests build them): the bag-of-words query
// (transform, inverted file, consistency) against databases of growing size,
// and the geometric verification of a true revisit (matching, RANSAC PnP,
// weighted ICP, information matrix), and the odometry edges' information that
// each loop closure computes.
//
//   wicp_benchmark_place_recognition [Google Benchmark flags]
//
// CPU is process time; on a shared machine it is the fairer figure.

#include <benchmark/benchmark.h>

#include "mapping_fixtures.h"
#include "weighted_icp/mapping/loop_verifier.h"
#include "weighted_icp/mapping/place_recognizer.h"
#include "weighted_icp/mapping/tracking_information.h"

namespace {

using namespace weighted_icp;

const testing::SyntheticKeyframes& loopKeyframes() {
  static const testing::SyntheticKeyframes data =
      testing::syntheticKeyframes(7, false, 180.0, testing::everyNth(228, 6));
  return data;
}

/// Transform + detect for the last keyframe, the database holding `range(0)` keyframes (the loop's keyframes
/// repeated under new ids, so that the inverted file lists as many as a long session would).
void BM_PlaceRecognitionQuery(benchmark::State& state) {
  const auto& data = loopKeyframes();
  const auto vocabulary = testing::trainedVocabulary();
  std::vector<mapping::BowVector> bows;
  for (const auto& [id, keyframe] : data.snapshot.keyframes)
    bows.push_back(vocabulary->transform(keyframe.descriptors));
  const auto database_size = static_cast<std::size_t>(state.range(0));
  const frontend::Keyframe& query = data.snapshot.keyframes.rbegin()->second;
  for (auto _ : state) {
    state.PauseTiming();
    mapping::PlaceRecognizer recognizer(vocabulary);
    for (std::size_t i = 0; i < database_size; ++i) recognizer.add(i, bows[i % (bows.size() - 1)]);
    state.ResumeTiming();
    const mapping::BowVector bow = vocabulary->transform(query.descriptors);
    benchmark::DoNotOptimize(recognizer.detect(database_size + 50, bow, {}));
  }
}
BENCHMARK(BM_PlaceRecognitionQuery)->Arg(38)->Arg(500)->Arg(2000)->Unit(benchmark::kMillisecond);

/// Verification of a true revisit (keyframe 32, frame 192, against keyframe 3, frame 18) with the odometry prior.
void BM_LoopVerification(benchmark::State& state) {
  const auto& data = loopKeyframes();
  const mapping::LoopVerifier verifier(data.camera);
  const frontend::KeyframeId query = 32, match = 3;
  const mapping::LoopPrior prior = mapping::odometryPrior(data.snapshot, query, match);
  std::size_t accepted = 0;
  for (auto _ : state) {
    const mapping::LoopVerification result = verifier.verify(data.snapshot, query, data.snapshot, match, prior);
    accepted += result.accepted;
    benchmark::DoNotOptimize(result);
  }
  state.counters["accepted_fraction"] = static_cast<double>(accepted) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_LoopVerification)->Unit(benchmark::kMillisecond);

/// The same where the weighted ICP leaves PnP's pose and plain ICP checks it again: a revisit of a room three times
/// as large (keyframe 8, frame 552, against keyframe 2, frame 12; LoopVerification.AnIcpThatLeavesThePnpPose...).
void BM_LoopVerificationPlainIcpCheck(benchmark::State& state) {
  static const testing::SyntheticKeyframes data = [] {
    std::vector<std::size_t> frames = testing::everyNth(36, 6);
    for (std::size_t f : testing::everyNth(576, 6, 540)) frames.push_back(f);
    return testing::syntheticKeyframes(7, false, 540.0, frames, 3.0);
  }();
  const mapping::LoopVerifier verifier(data.camera);
  const frontend::KeyframeId query = 8, match = 2;
  const mapping::LoopPrior prior = mapping::odometryPrior(data.snapshot, query, match);
  std::size_t accepted = 0, plain = 0;
  for (auto _ : state) {
    const mapping::LoopVerification result = verifier.verify(data.snapshot, query, data.snapshot, match, prior);
    accepted += result.accepted;
    plain += !result.icp_weighted;
    benchmark::DoNotOptimize(result);
  }
  state.counters["accepted_fraction"] = static_cast<double>(accepted) / static_cast<double>(state.iterations());
  state.counters["plain_icp_fraction"] = static_cast<double>(plain) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_LoopVerificationPlainIcpCheck)->Unit(benchmark::kMillisecond);

/// The information of every odometry edge of the loop's keyframes, as each loop closure recomputes it:
/// range(0) = 1 the relative covariance of both keyframes with their landmarks eliminated (the default since
/// 2026-11-25), 0 each keyframe's own covariance, propagated and added (before).
void BM_OdometryInformation(benchmark::State& state) {
  const auto& data = loopKeyframes();
  std::vector<frontend::KeyframeId> ids;
  for (const auto& [id, keyframe] : data.snapshot.keyframes) ids.push_back(id);
  const bool relative = state.range(0) == 1;
  std::size_t edges = 0;
  for (auto _ : state) {
    edges = 0;
    if (relative) {
      for (const auto& c : mapping::odometryEdgeCovariances(data.snapshot, ids, data.camera))
        if (c) {
          benchmark::DoNotOptimize(mapping::relativeOdometryInformation(*c));
          ++edges;
        }
    } else {
      std::vector<std::optional<mapping::Covariance6d>> each;
      for (const frontend::KeyframeId id : ids)
        each.push_back(mapping::keyframePoseCovariance(data.snapshot, id, data.camera));
      for (std::size_t i = 1; i < ids.size(); ++i)
        if (each[i - 1] && each[i]) {
          benchmark::DoNotOptimize(
              mapping::trackedOdometryInformation(data.snapshot.keyframes.at(ids[i - 1]).pose_wc, *each[i - 1],
                                                  data.snapshot.keyframes.at(ids[i]).pose_wc, *each[i]));
          ++edges;
        }
    }
  }
  if (edges + 1 != ids.size()) state.SkipWithError("an edge had no covariance");
  state.counters["edges"] = static_cast<double>(edges);
}
BENCHMARK(BM_OdometryInformation)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

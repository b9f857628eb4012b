// The issue #11 front-end options (KD-tree matcher, regions of interest,
// the keyframe homography, the modified BRIEF, the Eq. 6 distance history):
// each tracks a few synthetic frames and repeats exactly in deterministic mode.

#include <ostream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/frontend/slam/rgbd_slam.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace {

using namespace weighted_icp;

struct Option {
  std::string name;
  void (*apply)(frontend::RgbdSlamOptions&);
};

/// gtest prints the option by its name, not its bytes.
void PrintTo(const Option& option, std::ostream* out) { *out << option.name; }

std::string optionName(const ::testing::TestParamInfo<Option>& info) { return info.param.name; }

class MatchingOption : public ::testing::TestWithParam<Option> {};

Trajectory runFrames(const simulation::SyntheticRgbdSequence& sequence, const Option& option,
                     std::size_t& tracked_relative_or_3d) {
  frontend::RgbdSlamOptions options;
  options.backend.background_thread = false;  // --deterministic
  option.apply(options);
  frontend::RgbdSlam slam(sequence.options().camera, options);
  tracked_relative_or_3d = 0;
  for (std::size_t i = 0; i < sequence.size(); ++i)
    tracked_relative_or_3d += slam.process(sequence.frame(i).rgbd).result.hasPose();
  slam.finish();
  return slam.trajectory();
}

TEST_P(MatchingOption, TracksAndRepeatsExactlyInDeterministicMode) {
  simulation::SyntheticRgbdOptions synthetic;
  synthetic.frames = 8;
  synthetic.moving_object = true;  // gives the dynamic-point options something to flag
  const simulation::SyntheticRgbdSequence sequence(synthetic);
  std::size_t tracked[2] = {0, 0};
  const Trajectory first = runFrames(sequence, GetParam(), tracked[0]);
  const Trajectory second = runFrames(sequence, GetParam(), tracked[1]);
  EXPECT_EQ(tracked[0], sequence.size()) << "every frame has a pose";
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i)
    EXPECT_TRUE(first[i].pose.matrix() == second[i].pose.matrix()) << "frame " << i;
}

INSTANTIATE_TEST_SUITE_P(
    Issue11, MatchingOption,
    ::testing::Values(
        Option{"KdTree", [](frontend::RgbdSlamOptions& o) { o.frontend.matcher.kind = frontend::MatcherKind::KdTree; }},
        Option{"OurLsh", [](frontend::RgbdSlamOptions& o) { o.frontend.matcher.kind = frontend::MatcherKind::Lsh; }},
        Option{"BruteForce",
               [](frontend::RgbdSlamOptions& o) { o.frontend.matcher.kind = frontend::MatcherKind::BruteForce; }},
        Option{"RoiProjection",
               [](frontend::RgbdSlamOptions& o) { o.frontend.match_region = frontend::MatchRegion::Projection; }},
        Option{"RoiHomography",
               [](frontend::RgbdSlamOptions& o) { o.frontend.match_region = frontend::MatchRegion::Homography; }},
        Option{"ModifiedBrief",
               [](frontend::RgbdSlamOptions& o) {
                 o.frontend.features.descriptor = frontend::DescriptorKind::ModifiedBrief;
               }},
        Option{"EpipolarHistory",
               [](frontend::RgbdSlamOptions& o) {
                 o.frontend.dynamic_distance = frontend::DynamicDistanceKind::EpipolarHistory;
               }}),
    optionName);

}  // namespace

// The io headers the simulators used to live under still compile and name the
// same types for one release (they forward to weighted_icp/simulation/).

#include <type_traits>

#include <gtest/gtest.h>

#include "weighted_icp/io/synthetic_rgbd.h"
#include "weighted_icp/io/synthetic_session.h"

namespace weighted_icp {
namespace {

TEST(SyntheticDeprecatedHeaders, OldIoNamesAreTheSimulationOnes) {
  static_assert(std::is_same_v<io::SyntheticRgbdSequence, simulation::SyntheticRgbdSequence>);
  static_assert(std::is_same_v<io::SyntheticRgbdOptions, simulation::SyntheticRgbdOptions>);
  static_assert(std::is_same_v<io::SyntheticRgbdFrame, simulation::SyntheticRgbdFrame>);
  static_assert(std::is_same_v<io::SceneBox, simulation::SceneBox>);
  static_assert(std::is_same_v<io::SyntheticSession, simulation::SyntheticSession>);
  static_assert(std::is_same_v<io::SyntheticSessionOptions, simulation::SyntheticSessionOptions>);
  io::SyntheticSessionOptions options;
  options.num_frames = 3;
  options.num_landmarks = 200;
  EXPECT_FALSE(io::generateSyntheticSession(options).truth.landmarks.empty());
  EXPECT_EQ(io::syntheticRgbdCamera().width, 640);
  EXPECT_NE(&io::writeTumSequence, nullptr);
}

}  // namespace
}  // namespace weighted_icp

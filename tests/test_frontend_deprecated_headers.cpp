// The paths and names that moved in the architecture change still compile for
// one release: the flat frontend headers, io's camera and trajectory types and
// frontend::RgbdImage, each the same entity as its new home.
#include <type_traits>

#include <gtest/gtest.h>

#include "weighted_icp/frontend/backend.h"
#include "weighted_icp/frontend/depth_noise_model.h"
#include "weighted_icp/frontend/descriptor_matcher.h"
#include "weighted_icp/frontend/dynamic_point_filter.h"
#include "weighted_icp/frontend/feature_extractor.h"
#include "weighted_icp/frontend/frame.h"
#include "weighted_icp/frontend/frontend.h"
#include "weighted_icp/frontend/image_preprocessor.h"
#include "weighted_icp/frontend/image_quality_gate.h"
#include "weighted_icp/frontend/keyframe.h"
#include "weighted_icp/frontend/landmark_conversion.h"
#include "weighted_icp/frontend/local_bundle_adjustment.h"
#include "weighted_icp/frontend/map.h"
#include "weighted_icp/frontend/map_point.h"
#include "weighted_icp/frontend/minimap_builder.h"
#include "weighted_icp/frontend/motion_model.h"
#include "weighted_icp/frontend/pose_estimation.h"
#include "weighted_icp/frontend/reprojection_residual.h"
#include "weighted_icp/frontend/rgbd_slam.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/trajectory.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/metrics/trajectory_error.h"

namespace weighted_icp {

static_assert(std::is_same_v<frontend::RgbdImage, RgbdFrame>);
static_assert(std::is_same_v<io::PinholeCamera, PinholeCamera>);
static_assert(std::is_same_v<io::Trajectory, Trajectory>);
static_assert(std::is_same_v<io::StampedPose, StampedPose>);
static_assert(std::is_same_v<io::ErrorStatistics, ErrorStatistics>);
static_assert(std::is_same_v<io::AbsoluteTrajectoryError, metrics::AbsoluteTrajectoryError>);

TEST(DeprecatedNames, OldFunctionNamesAreTheMovedFunctions) {
  EXPECT_EQ(&io::tumCamera, &tumCamera);
  EXPECT_EQ(io::tumCamera(3).fx, tumCamera(3).fx);
  // The old flat frontend paths bring the same classes as the layer folders.
  EXPECT_STREQ(frontend::toString(frontend::FrontendState::Tracking).c_str(), "tracking");
}

}  // namespace weighted_icp

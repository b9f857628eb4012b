#pragma once
// One check shared by the tests that write a landmark map and read it back.

#include <gtest/gtest.h>

#include "weighted_icp/registration/landmark_map.h"

namespace weighted_icp::testing {

/// Every landmark the same to the bit: id, position, covariance, observations.
inline void expectSameLandmarks(const LandmarkMap& expected, const LandmarkMap& actual) {
  ASSERT_EQ(actual.landmarks.size(), expected.landmarks.size());
  for (std::size_t i = 0; i < expected.landmarks.size(); ++i) {
    const Landmark& e = expected.landmarks[i];
    const Landmark& a = actual.landmarks[i];
    EXPECT_EQ(a.id, e.id);
    EXPECT_EQ(a.position, e.position) << "landmark " << e.id;
    EXPECT_EQ(a.covariance, e.covariance) << "landmark " << e.id;
    ASSERT_EQ(a.observations.size(), e.observations.size()) << "landmark " << e.id;
    for (std::size_t k = 0; k < e.observations.size(); ++k) {
      EXPECT_EQ(a.observations[k].frame_id, e.observations[k].frame_id);
      EXPECT_EQ(a.observations[k].u, e.observations[k].u);
      EXPECT_EQ(a.observations[k].v, e.observations[k].v);
    }
  }
}

}  // namespace weighted_icp::testing

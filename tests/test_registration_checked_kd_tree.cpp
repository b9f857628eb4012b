// CheckedKdTree: a user's pcl::IterativeClosestPoint with WeightedCorrespondenceEstimation refuses a target (or
// reciprocal source) it cannot index instead of overflowing the stack in FLANN, and is otherwise PCL's tree.
#include <memory>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>
#include <pcl/point_types.h>
#include <pcl/registration/icp.h>

#include "weighted_icp/registration/checked_kd_tree.h"
#include "weighted_icp/registration/weighted_correspondence_estimation.h"

namespace {

using weighted_icp::CheckedKdTree;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using Icp = pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ, double>;
using Estimation = weighted_icp::WeightedCorrespondenceEstimation<pcl::PointXYZ, pcl::PointXYZ, double>;

/// A small, well-conditioned cloud: three perpendicular rows of points.
Cloud::Ptr gridCloud(float shift) {
  auto cloud = std::make_shared<Cloud>();
  for (int i = 0; i < 10; ++i) {
    cloud->push_back({0.1f * i + shift, 0.0f, 0.0f});
    cloud->push_back({0.0f, 0.13f * i, shift});
    cloud->push_back({shift, 0.0f, 0.17f * i});
  }
  return cloud;
}

/// The case: landmarks at one huge but finite position (fine as float, beyond what FLANN can split).
Cloud::Ptr hugeCloud() {
  auto cloud = gridCloud(0.0f);
  for (int i = 0; i < 20; ++i) cloud->push_back({3e38f, 3e38f, 3e38f});
  return cloud;
}

std::string alignError(Icp& icp) {
  Cloud aligned;
  try {
    icp.align(aligned);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(CheckedKdTree, AUserIcpRefusesAHugeTargetNamingThePoint) {
  Icp icp;
  icp.setCorrespondenceEstimation(std::make_shared<Estimation>(3));
  icp.setSearchMethodTarget(std::make_shared<CheckedKdTree<pcl::PointXYZ>>("target"));
  icp.setInputSource(gridCloud(0.01f));
  icp.setInputTarget(hugeCloud());
  const std::string error = alignError(icp);
  EXPECT_NE(error.find("target point 30 "), std::string::npos) << error;
  EXPECT_NE(error.find("beyond"), std::string::npos) << error;
}

// The reciprocal rule's source index is the estimation's own, checked too: no source tree is needed.
TEST(CheckedKdTree, AReciprocalSourceIsRefusedByTheEstimation) {
  Icp icp;
  icp.setCorrespondenceEstimation(std::make_shared<Estimation>(3));
  icp.setUseReciprocalCorrespondences(true);
  icp.setSearchMethodTarget(std::make_shared<CheckedKdTree<pcl::PointXYZ>>("target"));
  icp.setInputSource(hugeCloud());
  icp.setInputTarget(gridCloud(0.0f));
  const std::string error = alignError(icp);
  EXPECT_NE(error.find("source point 30 "), std::string::npos) << error;
}

TEST(CheckedKdTree, OnlyTheIndexedPointsAreChecked) {
  CheckedKdTree<pcl::PointXYZ> tree;
  const auto cloud = hugeCloud();
  auto first = std::make_shared<pcl::Indices>();
  for (int i = 0; i < 30; ++i) first->push_back(i);
  EXPECT_NO_THROW(tree.setInputCloud(cloud, first));
  EXPECT_THROW(tree.setInputCloud(cloud), std::invalid_argument);
  EXPECT_EQ(tree.getInputCloud(), cloud) << "a refused cloud replaced the tree's";
  EXPECT_EQ(tree.getIndices(), first);
}

// The check changes nothing else: the same alignment as with PCL's default tree, bit for bit.
TEST(CheckedKdTree, GivesPclsResultOnAValidCloud) {
  const auto run = [](bool checked) {
    Icp icp;
    icp.setCorrespondenceEstimation(std::make_shared<Estimation>(3));
    if (checked) icp.setSearchMethodTarget(std::make_shared<CheckedKdTree<pcl::PointXYZ>>());
    icp.setInputSource(gridCloud(0.02f));
    icp.setInputTarget(gridCloud(0.0f));
    Cloud aligned;
    icp.align(aligned);
    EXPECT_TRUE(icp.hasConverged());
    return std::make_pair(icp.getFinalTransformation(), icp.getFitnessScore());
  };
  const auto plain = run(false), checked = run(true);
  EXPECT_EQ(plain.first, checked.first);
  EXPECT_EQ(plain.second, checked.second);
}

}  // namespace

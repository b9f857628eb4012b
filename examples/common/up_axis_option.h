#pragma once
// The tools' --up-axis option (wicp_align --global, wicp_global_sweep): auto
// (each map's cameras say, up_axis.h), z, or an axis given as "X Y Z".

#include <string>

#include <Eigen/Core>

#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/up_axis.h"

namespace weighted_icp::tools {

/// @brief What --up-axis asked for.
struct UpAxisOption {
  /// True for "auto": each map's cameras decide (chooseUpAxes()); false: `axis` for both maps.
  bool automatic = true;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
};

/// @brief Parses "auto", "z" or "X Y Z" (three finite numbers, not all zero).
/// @param text  the option's value; std::invalid_argument says what was expected
UpAxisOption parseUpAxisOption(const std::string& text);

/// @brief "(x y z)" with three decimals, for the tools' messages.
std::string vectorText(const Eigen::Vector3d& v);

/// @brief The up axes the source and the target are levelled by, with one line saying which and why.
struct ResolvedUpAxes {
  SharedUpAxes axes;
  std::string description;
};

/// @brief Resolves --up-axis for one pair of maps (the source as it will be aligned, already displaced).
/// @param option  parseUpAxisOption()'s result
/// @param source  the source map (its camera poses)
/// @param target  the target map (its camera poses)
ResolvedUpAxes resolveUpAxes(const UpAxisOption& option, const LandmarkMap& source, const LandmarkMap& target);

}  // namespace weighted_icp::tools

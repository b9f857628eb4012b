#pragma once
// The tools' pictures: tables of numbers handed to scripts/plot_results.py, run by the project's Python
// (WEIGHTED_ICP_PYTHON) with matplotlib. A picture is a bonus, never the result: when Python, matplotlib or
// the script is missing or fails, the tool prints a warning saying why and carries on. The environment
// variable WEIGHTED_ICP_PLOT_PYTHON, when set, replaces the Python the build chose.

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "weighted_icp/core/trajectory.h"
#include "weighted_icp/registration/landmark_map.h"
#include "weighted_icp/registration/weight_strategies.h"

namespace weighted_icp::tools {

/// @brief Runs a program and waits for it. Its standard error is kept in a temporary file, not shown: a failure's
/// message ends with its last line (a Python traceback's last line says what went wrong).
/// @param argv  the program (an absolute path: no PATH lookup) and its arguments
/// @throws std::runtime_error when it cannot start, is killed or exits non-zero, naming argv[1] (the script) and
///         the last line it wrote to standard error;
///         exit status 3 reads "matplotlib is not installed", scripts/plot_results.py's way of saying so
void runProcess(const std::vector<std::string>& argv);

/// @brief The estimate against the ground truth, as evo and the TUM tools draw them: top view, x / y / z
/// against time, and the position error along the trajectory. Poses are paired as the ATE pairs them.
/// @param tool            the tool's name, for the warning when no picture is drawn
/// @param groundtruth     camera-to-world poses
/// @param estimate        camera-to-world poses, drawn after `alignment`
/// @param alignment       maps the estimate onto the ground truth (the ATE's)
/// @param max_difference  pair poses whose timestamps differ by less than this (seconds)
/// @param png             the picture, written atomically
/// @param title           the figure's title
/// @return true when the picture was written; false after a warning on stderr
bool plotTrajectory(const std::string& tool, const Trajectory& groundtruth, const Trajectory& estimate,
                    const Eigen::Isometry3d& alignment, double max_difference, const std::string& png,
                    const std::string& title);

/// @brief Two landmark clouds before and after alignment, top view, the target coloured by its weights.
/// @param tool            the tool's name, for the warning when no picture is drawn
/// @param source          source positions as given
/// @param target          target positions
/// @param target_weights  one per target position
/// @param transformation  maps the source onto the target
/// @param png             the picture, written atomically
/// @param title           the figure's title
/// @return true when the picture was written; false after a warning on stderr
bool plotAlignment(const std::string& tool, const std::vector<Eigen::Vector3d>& source,
                   const std::vector<Eigen::Vector3d>& target, const std::vector<double>& target_weights,
                   const Eigen::Matrix4d& transformation, const std::string& png, const std::string& title);

/// @brief plotAlignment() of two landmark maps, the target's points weighted with `weight` (as aligned).
/// @param tool            the tool's name, for the warning when no picture is drawn
/// @param source          the source map as given to the aligner
/// @param target          the target map
/// @param weight          the weight strategy's function
/// @param transformation  maps the source onto the target
/// @param png             the picture, written atomically
/// @param title           the figure's title
/// @return true when the picture was written; false after a warning on stderr
bool plotAlignment(const std::string& tool, const LandmarkMap& source, const LandmarkMap& target,
                   const WeightFunction& weight, const Eigen::Matrix4d& transformation, const std::string& png,
                   const std::string& title);

/// @brief One loop as plotPaths() draws it: the positions of its two keyframes' cameras.
struct PlottedLoop {
  /// @brief The query keyframe's camera position.
  Eigen::Vector3d query = Eigen::Vector3d::Zero();
  /// @brief The match keyframe's camera position.
  Eigen::Vector3d match = Eigen::Vector3d::Zero();
  /// @brief Whether the pose graph admitted it.
  bool used = true;
};

/// @brief Camera paths at a glance, where there is no ground truth to compare with: one run's path (wicp_rgbd_slam)
/// or each merged session's in the first session's frame (wicp_merge), seen along the direction the paths vary
/// least ("from above", whatever the frame) and from the side, and the loops as segments joining their keyframes.
/// @param tool      the tool's name, for the warning when no picture is drawn
/// @param paths     the trajectories, in one frame
/// @param names     one legend label per trajectory
/// @param loops     the loops
/// @param png       the picture, written atomically
/// @param title     the figure's title
/// @return true when the picture was written; false after a warning on stderr
bool plotPaths(const std::string& tool, const std::vector<Trajectory>& paths, const std::vector<std::string>& names,
               const std::vector<PlottedLoop>& loops, const std::string& png, const std::string& title);

}  // namespace weighted_icp::tools

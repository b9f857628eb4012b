// --up-axis: parsing, and the axes a pair of maps is levelled by.
#include "up_axis_option.h"

#include <cmath>
#include <iomanip>
#include <iterator>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

namespace weighted_icp::tools {

UpAxisOption parseUpAxisOption(const std::string& text) {
  UpAxisOption option;
  if (text == "auto") return option;
  option.automatic = false;
  if (text == "z") return option;
  std::istringstream in(text);
  Eigen::Vector3d axis;
  std::string rest;
  if (!(in >> axis.x() >> axis.y() >> axis.z()) || (in >> rest) || !axis.allFinite() || !(axis.norm() > 0.0))
    throw std::invalid_argument("expected auto, z or \"X Y Z\" (three finite numbers, not all zero), got '" + text +
                                "'");
  option.axis = axis.normalized();
  return option;
}

std::string vectorText(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << '(' << v.x() << ' ' << v.y() << ' ' << v.z() << ')';
  return out.str();
}

namespace {

std::string estimateText(const char* which, const UpAxisEstimate& e) {
  std::ostringstream out;
  out << which << ' ' << vectorText(e.axis) << " from " << e.cameras << " cameras, rows level within " << std::fixed
      << std::setprecision(1) << e.row_tilt_deg << " deg rms" << (e.from_rows ? "" : " (one heading)");
  return out.str();
}

/// ", the source's estimate also turned about its cameras' rows ..." when chooseUpAxes added such levellings.
std::string pitchedText(const SharedUpAxes& axes) {
  bool source = false, target = false;
  for (const auto& [source_axis, target_axis] : axes.alternatives) {
    source = source || !source_axis.isApprox(axes.source);
    target = target || !target_axis.isApprox(axes.target);
  }
  if (!source && !target) return "";
  std::set<long> turns;  // "15, 30 and 45" from kPitchedLevellingsDeg
  for (const double pitch : kPitchedLevellingsDeg) turns.insert(std::lround(std::abs(pitch)));
  std::string listed;
  for (auto it = turns.begin(); it != turns.end(); ++it)
    listed += (it == turns.begin() ? "" : std::next(it) == turns.end() ? " and " : ", ") + std::to_string(*it);
  return std::string(", ") +
         (source && target ? "each map's estimate"
          : source         ? "the source's"
                           : "the target's") +
         " also turned " + listed + " deg each way about its cameras' rows (they face about one way)";
}

}  // namespace

ResolvedUpAxes resolveUpAxes(const UpAxisOption& option, const LandmarkMap& source, const LandmarkMap& target) {
  ResolvedUpAxes resolved;
  if (!option.automatic) {
    resolved.axes.source = resolved.axes.target = option.axis;
    resolved.description = "up axis " + vectorText(option.axis) + " for both maps (--up-axis)";
    return resolved;
  }
  const UpAxisEstimate s = estimateUpAxis(source.frames), t = estimateUpAxis(target.frames);
  resolved.axes = chooseUpAxes(s, t);
  if (s.cameras == 0 || t.cameras == 0)
    resolved.description = "up axis z for both maps (a map without cameras to estimate it from)";
  else if (resolved.axes.zUpOnly())
    resolved.description =
        "up axis z for both maps, with tilts up to " + std::to_string(std::lround(resolved.axes.tilt_range_deg)) +
        " deg (their cameras are level about z: " + estimateText("source", s) + ", " + estimateText("target", t) + ")";
  else
    resolved.description = "each map levelled by its cameras (" + estimateText("source", s) + ", " +
                           estimateText("target", t) + "), with tilts" + pitchedText(resolved.axes) +
                           ", and the search about z tried as well";
  return resolved;
}

}  // namespace weighted_icp::tools

#pragma once
// The parts of the Python module weighted_icp, one function per area, called in this order by module.cpp
// (maps first: the other parts take and return LandmarkMap).

#include <pybind11/pybind11.h>

namespace weighted_icp::python {

/// @brief LandmarkMap (load, save, arrays, mini-map cuts) and weights(). @param m the module
void bindMaps(pybind11::module_& m);
/// @brief align(), AlignmentResult and weighted_correspondences(). @param m the module
void bindRegistration(pybind11::module_& m);
/// @brief ate(), rpe() and the trajectory files. @param m the module
void bindMetrics(pybind11::module_& m);
/// @brief Loop, merge_sessions() and its results. @param m the module
void bindMapping(pybind11::module_& m);
/// @brief Camera, RgbdSlam (a TUM folder or frame by frame). @param m the module
void bindFrontend(pybind11::module_& m);

}  // namespace weighted_icp::python

#pragma once
// The place-recognition vocabulary of the Python module: the file the caller names, else the default one shipped in
// the package (the tools' default_vocabulary.txt, copied beside the extension).

#include <pybind11/pybind11.h>

#include "weighted_icp/mapping/binary_vocabulary.h"

namespace weighted_icp::python {

/// @brief The vocabulary at `path_like` (a str or an os.PathLike), or the package's default for None.
/// FileNotFoundError naming the path when there is no such file (or the package lacks its default), ValueError
/// naming the file and line for a malformed one.
/// @param path_like  None or a path
mapping::BinaryVocabulary::ConstPtr loadVocabulary(const pybind11::object& path_like);

}  // namespace weighted_icp::python

// The place-recognition vocabulary of the Python module: the caller's file or the package's default.
#include "vocabulary.h"

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "arrays.h"

namespace weighted_icp::python {

namespace {

/// default_vocabulary.txt in the folder the extension was loaded from (the build tree's python/weighted_icp or the
/// installed package), whatever the working directory.
std::string defaultVocabularyPath() {
  const std::string extension = py::str(py::module_::import("weighted_icp._weighted_icp").attr("__file__"));
  return (std::filesystem::path(extension).parent_path() / "default_vocabulary.txt").string();
}

}  // namespace

mapping::BinaryVocabulary::ConstPtr loadVocabulary(const py::object& path_like) {
  const std::string path = existingPath(path_like.is_none() ? py::str(defaultVocabularyPath()) : path_like);
  try {
    py::gil_scoped_release unlocked;  // a trained vocabulary is megabytes of text
    return std::make_shared<const mapping::BinaryVocabulary>(mapping::BinaryVocabulary::load(path));
  } catch (const std::runtime_error& e) {  // malformed: names the file and the line
    throw py::value_error(e.what());
  }
}

}  // namespace weighted_icp::python

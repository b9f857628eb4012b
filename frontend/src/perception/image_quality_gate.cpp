#include "weighted_icp/frontend/perception/image_quality_gate.h"

#include <filesystem>
#include <stdexcept>
#include <utility>

#include <opencv2/quality/qualitybrisque.hpp>

namespace weighted_icp::frontend {
namespace {

std::string requireFile(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error("ImageQualityGate: missing BRISQUE model file " + path.string() +
                             " (Debian package opencv-data; set ImageQualityGateOptions::model_dir)");
  return path.string();
}

}  // namespace

ImageQualityGate::ImageQualityGate(ImageQualityGateOptions options) : options_(std::move(options)) {
  const std::filesystem::path dir(options_.model_dir);
  const std::string model_path = requireFile(dir / "brisque_model_live.yml");
  const std::string range_path = requireFile(dir / "brisque_range_live.yml");
  try {
    model_ = cv::ml::SVM::load(model_path);
    range_ = cv::FileStorage(range_path, cv::FileStorage::READ)["range"].mat();
  } catch (const cv::Exception& e) {
    throw std::runtime_error("ImageQualityGate: cannot read BRISQUE model " + model_path + " / " + range_path + ": " +
                             e.what());
  }
  if (model_.empty() || !model_->isTrained())
    throw std::runtime_error("ImageQualityGate: no trained SVM in " + model_path);
  if (range_.empty()) throw std::runtime_error("ImageQualityGate: no \"range\" matrix in " + range_path);
}

double ImageQualityGate::score(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("ImageQualityGate::score: empty image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3 && image.channels() != 4))
    throw std::invalid_argument("ImageQualityGate::score: needs an 8-bit gray, BGR or BGRA image, got type " +
                                cv::typeToString(image.type()));
  // QualityBRISQUE::compute is not const; a light wrapper per call around the
  // shared, read-only SVM keeps score() const and safe from several threads.
  return cv::quality::QualityBRISQUE::create(model_, range_)->compute(image)[0];
}

bool ImageQualityGate::accept(const cv::Mat& image) const { return score(image) <= options_.max_brisque_score; }

}  // namespace weighted_icp::frontend

// BRISQUE and sharpness scores and the gate modes that judge them (see image_quality_gate.h).

#include "weighted_icp/frontend/perception/image_quality_gate.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <utility>

#include <opencv2/imgproc.hpp>
#include <opencv2/quality/qualitybrisque.hpp>

#include "weighted_icp/core/named_values.h"

namespace weighted_icp::frontend {
namespace {

std::string requireFile(const std::filesystem::path& path) {
  if (!std::filesystem::is_regular_file(path))
    throw std::runtime_error("ImageQualityGate: missing BRISQUE model file " + path.string() +
                             " (Debian package opencv-data; set ImageQualityGateOptions::model_dir)");
  return path.string();
}

void requireScorable(const cv::Mat& image, const std::string& function) {
  if (image.empty()) throw std::invalid_argument(function + ": empty image");
  if (image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3 && image.channels() != 4))
    throw std::invalid_argument(function + ": needs an 8-bit gray, BGR or BGRA image, got type " +
                                cv::typeToString(image.type()));
}

}  // namespace

std::string toString(QualityMeasure measure) { return measure == QualityMeasure::Sharpness ? "sharpness" : "brisque"; }

QualityMeasure parseQualityMeasure(const std::string& name) {
  return parseNamedValue(
      name, {QualityMeasure::Sharpness, QualityMeasure::Brisque}, [](auto value) { return toString(value); },
      "quality measure");
}

std::string toString(QualityGateMode mode) {
  switch (mode) {
    case QualityGateMode::Relative: return "relative";
    case QualityGateMode::Absolute: return "absolute";
    case QualityGateMode::PaperEveryFrame: return "paper";
  }
  return "unknown";
}

QualityGateMode parseQualityGateMode(const std::string& name) {
  return parseNamedValue(
      name, {QualityGateMode::Relative, QualityGateMode::Absolute, QualityGateMode::PaperEveryFrame},
      [](auto value) { return toString(value); }, "quality gate mode");
}

ImageQualityGate::ImageQualityGate(ImageQualityGateOptions options)
    : options_(std::move(options)),
      relative_brisque_(options_.relative_brisque),
      relative_sharpness_(options_.relative_sharpness) {
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
  requireScorable(image, "ImageQualityGate::score");
  // QualityBRISQUE::compute is not const; a light wrapper per call around the
  // shared, read-only SVM keeps score() const and safe from several threads.
  return cv::quality::QualityBRISQUE::create(model_, range_)->compute(image)[0];
}

bool ImageQualityGate::accept(const cv::Mat& image) const { return score(image) <= options_.max_brisque_score; }

double ImageQualityGate::sharpness(const cv::Mat& image) {
  requireScorable(image, "ImageQualityGate::sharpness");
  cv::Mat gray = image, laplacian;
  if (image.channels() == 3) cv::cvtColor(image, gray, cv::COLOR_BGR2GRAY);
  if (image.channels() == 4) cv::cvtColor(image, gray, cv::COLOR_BGRA2GRAY);
  cv::Laplacian(gray, laplacian, CV_32F);
  cv::Scalar mean, deviation;
  cv::meanStdDev(laplacian, mean, deviation);
  // A flat image has no Laplacian energy: floor it so the log stays finite.
  return std::log10(std::max(deviation[0] * deviation[0], 1e-6));
}

QualityJudgement ImageQualityGate::assess(const cv::Mat& image) {
  if (options_.mode != QualityGateMode::Relative) {
    QualityJudgement judgement;
    judgement.score = score(image);
    judgement.refused = !(judgement.score <= options_.max_brisque_score);
    return judgement;
  }
  return options_.measure == QualityMeasure::Sharpness ? relative_sharpness_.judge(sharpness(image))
                                                       : relative_brisque_.judge(score(image));
}

void ImageQualityGate::decide(QualityJudgement& judgement, bool must_keep) {
  if (options_.mode != QualityGateMode::Relative) return;
  const bool bad = judgement.refused || judgement.kept_anyway;
  const bool keep = must_keep || consecutive_refusals_ >= options_.max_consecutive_refusals;
  judgement.refused = bad && !keep;
  judgement.kept_anyway = bad && keep;
  consecutive_refusals_ = judgement.refused ? consecutive_refusals_ + 1 : 0;
}

QualityJudgement ImageQualityGate::judge(const cv::Mat& image, bool must_keep) {
  QualityJudgement judgement = assess(image);
  decide(judgement, must_keep);
  return judgement;
}

}  // namespace weighted_icp::frontend

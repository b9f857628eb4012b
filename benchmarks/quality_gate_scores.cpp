// BRISQUE scores of whole sequences and what the quality gates make of them
// (issue #11): per sequence, the distribution of the clean frames' scores and
// of the frames a burst degraded (a variant's bursts.txt), and how many of each
// the relative gate (every frame scored, in order) and the absolute threshold
// refuse. Prints Markdown tables.
//
//   wicp_benchmark_quality_gate [--measure brisque|sharpness] [--scale S] DIR[=CAMERA] ...
//
// DIR is a TUM folder (with camera.yaml, or named after its sensor, or
// DIR=fr1|fr2|fr3|FILE.yaml); --scale scores images resized by S (0.5 costs
// about a quarter).

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "weighted_icp/core/statistics.h"
#include "weighted_icp/frontend/perception/image_quality_gate.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/simulation/sequence_variants.h"

using namespace weighted_icp;
namespace fs = std::filesystem;

namespace {

struct Counts {
  std::vector<double> scores;
  std::size_t relative_refused = 0, absolute_refused = 0;
};

std::string distribution(const std::vector<double>& scores) {
  if (scores.empty()) return "– | – | –";
  std::ostringstream text;
  text << std::fixed << std::setprecision(2) << quantile(scores, 0.1) << " | " << median(scores) << " | "
       << quantile(scores, 0.9);
  return text.str();
}

std::string cameraSpec(const std::string& dir, const std::string& given) {
  if (!given.empty()) return given;
  if (fs::is_regular_file(fs::path(dir) / "camera.yaml")) return (fs::path(dir) / "camera.yaml").string();
  const std::string name = fs::path(dir).filename().string();
  for (const char* sensor : {"1", "2", "3"})
    if (name.find(std::string("fr") + sensor) != std::string::npos) return std::string("fr") + sensor;
  throw std::runtime_error("no camera for " + dir + ": pass DIR=fr1|fr2|fr3|FILE.yaml");
}

void scoreSequence(const std::string& dir, const std::string& camera_spec, double scale,
                   frontend::QualityMeasure measure) {
  const io::TumSequence sequence = io::TumSequence::open(dir);
  const PinholeCamera camera = io::loadCamera(cameraSpec(dir, camera_spec));
  std::set<std::size_t> degraded;
  const fs::path bursts = fs::path(dir) / "bursts.txt";
  if (fs::exists(bursts))
    for (const auto& frame : simulation::readDegradedFrames(bursts.string())) degraded.insert(frame.index);
  frontend::ImageQualityGateOptions options;  // relative mode, default options but the measure
  options.measure = measure;
  frontend::ImageQualityGate gate(options);
  const bool brisque = measure == frontend::QualityMeasure::Brisque;
  Counts clean, bad;
  double ms = 0.0;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    cv::Mat image = sequence.loadFrame(i, camera).color;
    const auto start = std::chrono::steady_clock::now();
    if (scale != 1.0) cv::resize(image, image, cv::Size(), scale, scale, cv::INTER_AREA);
    const frontend::QualityJudgement judgement = gate.assess(image);  // bad or not, before any must-keep rule
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    Counts& counts = degraded.count(i) ? bad : clean;
    counts.scores.push_back(judgement.score);
    counts.relative_refused += judgement.refused;
    counts.absolute_refused += brisque && judgement.score > gate.options().max_brisque_score;
  }
  std::cout << std::fixed << std::setprecision(2) << "| " << fs::path(dir).filename().string() << " | "
            << clean.scores.size() << " | " << distribution(clean.scores) << " | " << clean.relative_refused << " | "
            << clean.absolute_refused << " | " << bad.scores.size() << " | " << distribution(bad.scores) << " | "
            << bad.relative_refused << " | " << bad.absolute_refused << " | " << std::setprecision(1)
            << ms / sequence.size() << " |" << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    double scale = 1.0;
    frontend::QualityMeasure measure = frontend::QualityMeasure::Brisque;
    std::vector<std::string> dirs;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--scale" && i + 1 < argc)
        scale = std::stod(argv[++i]);
      else if (arg == "--measure" && i + 1 < argc)
        measure = frontend::parseQualityMeasure(argv[++i]);
      else
        dirs.push_back(arg);
    }
    if (dirs.empty() || !(scale > 0.05 && scale <= 1.0)) {
      std::cerr << "usage: wicp_benchmark_quality_gate [--measure brisque|sharpness] [--scale S in (0.05, 1]] "
                   "DIR[=CAMERA] ...\n";
      return 2;
    }
    std::cout
        << frontend::toString(measure) << " at scale " << scale
        << "; relative gate: every frame assessed in order, default options; absolute (BRISQUE only): "
        << "score > 47\n\n"
        << "| sequence | clean frames | p10 | median | p90 | refused, relative | refused, absolute | burst frames | "
           "p10 | median | p90 | refused, relative | refused, absolute | ms/frame |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const std::string& entry : dirs) {
      const auto equals = entry.find('=');
      scoreSequence(entry.substr(0, equals), equals == std::string::npos ? "" : entry.substr(equals + 1), scale,
                    measure);
    }
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "wicp_benchmark_quality_gate: error: " << e.what() << '\n';
    return 1;
  }
}

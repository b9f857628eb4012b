// Fuzz target: the binary vocabulary's text format (mapping/binary_vocabulary.h). A vocabulary that reads must
// write and read back to the same tree, and give every descriptor a word and every image an L1-normalised
// bag-of-words vector.
#include <cmath>
#include <optional>
#include <sstream>
#include <string>

#include <opencv2/core.hpp>

#include "fuzz_support.h"
#include "weighted_icp/mapping/binary_vocabulary.h"

namespace {
std::string written(const weighted_icp::mapping::BinaryVocabulary& vocabulary) {
  std::ostringstream out;
  vocabulary.write(out);
  return out.str();
}

/// A few fixed descriptors: all zeros, all ones, and two patterns, so that the descent visits several branches.
cv::Mat probeDescriptors() {
  cv::Mat descriptors(4, 32, CV_8U);
  for (int c = 0; c < 32; ++c) {
    descriptors.at<unsigned char>(0, c) = 0x00;
    descriptors.at<unsigned char>(1, c) = 0xff;
    descriptors.at<unsigned char>(2, c) = static_cast<unsigned char>(c * 37);
    descriptors.at<unsigned char>(3, c) = static_cast<unsigned char>(0xa5 ^ c);
  }
  return descriptors;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace weighted_icp;
  const std::string source = "fuzz_vocabulary.txt";
  std::optional<mapping::BinaryVocabulary> vocabulary;
  const bool parsed = fuzz::refusedClearlyOrParsed(source, [&] {
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    vocabulary = mapping::BinaryVocabulary::read(in, source);
  });
  if (!parsed) return 0;
  const std::string text = written(*vocabulary);
  std::istringstream again(text);
  const mapping::BinaryVocabulary reread = mapping::BinaryVocabulary::read(again, "written vocabulary");
  fuzz::require(written(reread) == text, "a vocabulary does not write and read back to the same text");
  fuzz::require(reread.wordCount() == vocabulary->wordCount() && reread.branching() == vocabulary->branching() &&
                    reread.depth() == vocabulary->depth(),
                "a vocabulary reads back with another shape");
  const cv::Mat probes = probeDescriptors();
  for (const auto& descriptor : toBinaryDescriptors(probes))
    fuzz::require(vocabulary->wordOf(descriptor) < vocabulary->wordCount(), "a descriptor's word is out of range");
  const mapping::BowVector bow = vocabulary->transform(probes);
  double sum = 0.0;
  for (const auto& [word, value] : bow) {
    fuzz::require(word < vocabulary->wordCount() && std::isfinite(value) && value >= 0.0,
                  "a bag-of-words entry is out of range or not a finite non-negative weight");
    sum += value;
  }
  fuzz::require(bow.empty() || std::abs(sum - 1.0) < 1e-9, "a bag-of-words vector is not L1-normalised");
  const double self = mapping::BinaryVocabulary::score(bow, bow);
  fuzz::require(bow.empty() || std::abs(self - 1.0) < 1e-9, "a vector does not score 1 against itself");
  return 0;
}

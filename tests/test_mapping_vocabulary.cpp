// The vocabulary tree: training, words and scores, the text format's round
// trip, and errors that name the file and line.

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"
#include "weighted_icp/mapping/binary_vocabulary.h"

namespace weighted_icp::mapping {
namespace {

/// Images of descriptors drawn around a few prototypes (flipping some bits), so that words mean something.
std::vector<cv::Mat> clusteredImages(std::size_t images, int per_image, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::vector<cv::Mat> prototypes;
  for (int p = 0; p < 40; ++p) {
    cv::Mat row(1, 32, CV_8U);
    for (int b = 0; b < 32; ++b) row.at<std::uint8_t>(0, b) = static_cast<std::uint8_t>(random());
    prototypes.push_back(row);
  }
  std::vector<cv::Mat> result;
  for (std::size_t i = 0; i < images; ++i) {
    cv::Mat image(per_image, 32, CV_8U);
    for (int r = 0; r < per_image; ++r) {
      prototypes[(i * 7 + random() % 10) % prototypes.size()].copyTo(image.row(r));
      for (int flip = 0; flip < 12; ++flip) image.at<std::uint8_t>(r, random() % 32) ^= 1u << (random() % 8);
    }
    result.push_back(image);
  }
  return result;
}

std::string text(const BinaryVocabulary& vocabulary) {
  std::ostringstream out;
  vocabulary.write(out);
  return out.str();
}

TEST(Vocabulary, TrainsDeterministicallyAndScoresSameImagesHighest) {
  const auto images = clusteredImages(30, 150, 3);
  VocabularyTrainingOptions options;
  options.branching = 6;
  options.depth = 3;
  const BinaryVocabulary a = BinaryVocabulary::train(images, options);
  const BinaryVocabulary b = BinaryVocabulary::train(images, options);
  EXPECT_EQ(text(a), text(b));
  EXPECT_GT(a.wordCount(), 36u);
  EXPECT_LE(a.wordCount(), 216u);
  const BowVector v0 = a.transform(images[0]);
  double sum = 0.0;
  for (const auto& [word, value] : v0) sum += value;
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_NEAR(BinaryVocabulary::score(v0, v0), 1.0, 1e-12);
  // Image i draws on prototypes 7i .. 7i + 9 (mod 40): images 0 and 1 share three, images 0 and 3 none.
  const BowVector v1 = a.transform(images[1]);
  const BowVector v3 = a.transform(images[3]);
  EXPECT_GT(BinaryVocabulary::score(v0, v1), BinaryVocabulary::score(v0, v3));
  EXPECT_LT(BinaryVocabulary::score(v0, v3), 0.2);
  EXPECT_THROW(BinaryVocabulary::train({}, options), std::invalid_argument);
  options.branching = 1;
  EXPECT_THROW(BinaryVocabulary::train(images, options), std::invalid_argument);
  EXPECT_THROW(a.transform(cv::Mat(3, 16, CV_8U, cv::Scalar(0))), std::invalid_argument);
}

TEST(Vocabulary, SaveLoadRoundTripKeepsWordsWeightsAndVectors) {
  const auto images = clusteredImages(25, 120, 5);
  VocabularyTrainingOptions options;
  options.branching = 5;
  options.depth = 3;
  const BinaryVocabulary trained = BinaryVocabulary::train(images, options);
  const auto path = (testing::scratchDir("round_trip") / "vocabulary.txt").string();
  {
    std::ofstream out(path);
    trained.write(out);
  }
  const BinaryVocabulary loaded = BinaryVocabulary::load(path);
  ASSERT_EQ(loaded.wordCount(), trained.wordCount());
  EXPECT_EQ(loaded.branching(), 5u);
  EXPECT_EQ(loaded.depth(), 3u);
  for (WordId w = 0; w < trained.wordCount(); ++w) EXPECT_DOUBLE_EQ(loaded.weight(w), trained.weight(w));
  for (const cv::Mat& image : images) {
    for (const BinaryDescriptor& d : toBinaryDescriptors(image)) ASSERT_EQ(loaded.wordOf(d), trained.wordOf(d));
    const BowVector a = trained.transform(image), b = loaded.transform(image);
    ASSERT_EQ(a.size(), b.size());
    for (auto i = a.begin(), j = b.begin(); i != a.end(); ++i, ++j) {
      EXPECT_EQ(i->first, j->first);
      EXPECT_DOUBLE_EQ(i->second, j->second);
    }
  }
  EXPECT_EQ(text(loaded), text(trained));
}

/// The message of the error loading `content` from a file raises (empty when none).
std::string loadError(const std::string& folder, const std::string& content, std::string& path) {
  path = (testing::scratchDir(folder) / "vocabulary.txt").string();
  testing::writeFile(path, content);
  try {
    BinaryVocabulary::load(path);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "";
}

TEST(Vocabulary, HugeWeightsInAFileStillGiveNormalisedVectors) {
  // Found by fuzz_vocabulary: two descriptors on a word of weight 1e308 summed to infinity, and the vector to NaN.
  std::istringstream in("wicp_vocabulary 1\nbranching 2\ndepth 1\nnodes 2\nnode 0 1 1e308 " + std::string(64, '0') +
                        "\nnode 0 1 1 " + std::string(64, 'f') + "\n");
  const BinaryVocabulary vocabulary = BinaryVocabulary::read(in, "huge.txt");
  cv::Mat descriptors(3, 32, CV_8U, cv::Scalar(0));
  descriptors.row(2).setTo(cv::Scalar(255));
  const BowVector bow = vocabulary.transform(descriptors);
  ASSERT_EQ(bow.size(), 2u);
  double sum = 0.0;
  for (const auto& [word, value] : bow) {
    EXPECT_TRUE(std::isfinite(value)) << "word " << word;
    sum += value;
  }
  EXPECT_NEAR(sum, 1.0, 1e-12);
  EXPECT_NEAR(BinaryVocabulary::score(bow, bow), 1.0, 1e-12);
}

TEST(Vocabulary, CorruptFileErrorsNameFileAndLine) {
  VocabularyTrainingOptions options;
  options.branching = 4;
  options.depth = 2;
  const std::string good = text(BinaryVocabulary::train(clusteredImages(10, 60, 8), options));
  std::vector<std::string> lines;
  std::istringstream in(good);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  const auto join = [](const std::vector<std::string>& parts) {
    std::string all;
    for (const auto& p : parts) all += p + "\n";
    return all;
  };
  std::size_t first_node = 0;
  while (lines[first_node].rfind("node ", 0) != 0) ++first_node;

  std::string path;
  // A descriptor with a character that is not hex, on the third node line.
  auto bad_hex = lines;
  bad_hex[first_node + 2].back() = 'z';
  std::string message = loadError("bad_hex", join(bad_hex), path);
  EXPECT_NE(message.find(path + ":" + std::to_string(first_node + 3) + ":"), std::string::npos) << message;
  EXPECT_NE(message.find("hex"), std::string::npos) << message;

  // A parent that comes later than its child.
  auto bad_parent = lines;
  bad_parent[first_node] = "node 7 0 0 " + std::string(64, '0');
  message = loadError("bad_parent", join(bad_parent), path);
  EXPECT_NE(message.find(path + ":" + std::to_string(first_node + 1) + ":"), std::string::npos) << message;

  // Truncated: fewer nodes than declared; the error names the line after the last.
  auto truncated = lines;
  truncated.resize(truncated.size() - 2);
  message = loadError("truncated", join(truncated), path);
  EXPECT_NE(message.find(path + ":" + std::to_string(truncated.size() + 1) + ":"), std::string::npos) << message;
  EXPECT_NE(message.find("unexpected end of file"), std::string::npos) << message;

  // A negative weight, a wrong header, another file altogether.
  auto negative = lines;
  std::istringstream fields(lines.back());
  std::string node, parent, leaf, weight, descriptor;
  fields >> node >> parent >> leaf >> weight >> descriptor;
  negative.back() = "node " + parent + " " + leaf + " -1 " + descriptor;
  message = loadError("negative", join(negative), path);
  EXPECT_NE(message.find(path + ":" + std::to_string(lines.size()) + ":"), std::string::npos) << message;
  auto header = lines;
  header[first_node - 3] = "branching two";
  message = loadError("header", join(header), path);
  EXPECT_NE(message.find(path + ":" + std::to_string(first_node - 2) + ":"), std::string::npos) << message;
  message = loadError("other", "ply\nformat ascii 1.0\n", path);
  EXPECT_NE(message.find(path + ":1:"), std::string::npos) << message;
  EXPECT_THROW(BinaryVocabulary::load(path + ".missing"), std::runtime_error);
}

}  // namespace
}  // namespace weighted_icp::mapping

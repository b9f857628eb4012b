// wicp_vocabulary: trains the place-recognition vocabulary (a bag of binary
// words) on RGB-D sequences, and measures place recognition's precision and
// recall on a sequence with ground truth (true revisits by viewing overlap).

#include <algorithm>
#include <cstdint>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <boost/program_options.hpp>

#include "tool_support.h"
#include "weighted_icp/io/camera.h"
#include "weighted_icp/io/tum_sequence.h"
#include "weighted_icp/mapping/binary_vocabulary.h"
#include "weighted_icp/mapping/keyframe_snapshot.h"
#include "weighted_icp/mapping/loop_verifier.h"
#include "weighted_icp/mapping/place_recognizer.h"
#include "weighted_icp/mapping/posed_keyframe_builder.h"
#include "weighted_icp/mapping/view_overlap.h"
#include "weighted_icp/simulation/rgbd_sequence.h"

namespace po = boost::program_options;
using namespace weighted_icp;

namespace {

/// Where keyframes come from: TUM folders (at their ground-truth poses) and synthetic sequences.
struct Sources {
  std::vector<std::string> datasets;
  std::vector<std::uint64_t> synthetic_seeds;
  std::size_t every = 10;
  std::size_t synthetic_frames = 228;
  double frames_per_loop = 180.0;
  bool aliased = false;
};

struct Keyframes {
  PinholeCamera camera;
  mapping::KeyframeSnapshot snapshot;
};

/// Every `every`-th frame of a TUM folder that has a ground-truth pose, as a keyframe at that pose.
Keyframes tumKeyframes(const std::string& dir, std::size_t every) {
  const io::TumSequence sequence = io::TumSequence::open(dir);
  if (!sequence.hasGroundTruth()) throw std::runtime_error(dir + ": no groundtruth.txt (needed for the poses)");
  const PinholeCamera camera = io::datasetCamera(dir, "");
  mapping::PosedKeyframeBuilder builder(camera);
  for (std::size_t i = 0; i < sequence.size(); i += every) {
    const auto pose = sequence.groundTruthAt(sequence.frame(i).rgb_timestamp);
    if (pose) builder.add(sequence.loadFrame(i, camera), i, *pose);
  }
  if (builder.map().keyframeCount() == 0) throw std::runtime_error(dir + ": no frame has a ground-truth pose");
  return {camera, mapping::KeyframeSnapshot::of(builder.map())};
}

Keyframes syntheticKeyframes(std::uint64_t seed, const Sources& sources) {
  simulation::SyntheticRgbdOptions options;
  options.seed = seed;
  options.frames = sources.synthetic_frames;
  options.frames_per_loop = sources.frames_per_loop;
  options.repeated_texture = sources.aliased;
  const simulation::SyntheticRgbdSequence sequence(options);
  mapping::PosedKeyframeBuilder builder(options.camera);
  for (std::size_t i = 0; i < sequence.size(); i += sources.every) {
    const simulation::SyntheticRgbdFrame frame = sequence.frame(i);
    builder.add(frame.rgbd, i, frame.camera_to_world);
  }
  return {options.camera, mapping::KeyframeSnapshot::of(builder.map())};
}

std::vector<Keyframes> loadSources(const Sources& sources) {
  std::vector<Keyframes> all;
  for (const std::string& dir : sources.datasets) all.push_back(tumKeyframes(dir, sources.every));
  for (std::uint64_t seed : sources.synthetic_seeds) all.push_back(syntheticKeyframes(seed, sources));
  if (all.empty()) throw po::error("give at least one --dataset or --synthetic");
  return all;
}

std::vector<cv::Mat> descriptorsOf(const std::vector<Keyframes>& all) {
  std::vector<cv::Mat> images;
  for (const Keyframes& k : all)
    for (const auto& [id, keyframe] : k.snapshot.keyframes) images.push_back(keyframe.descriptors);
  return images;
}

void addSourceOptions(po::options_description& description, Sources& sources) {
  // clang-format off
  description.add_options()
      ("dataset", po::value(&sources.datasets), "TUM RGB-D folder with groundtruth.txt (repeatable); camera from its name")
      ("synthetic", po::value(&sources.synthetic_seeds), "a synthetic loop sequence of this seed (repeatable)")
      ("every", tools::rangedValue(&sources.every, std::size_t{1}, std::size_t{10000})->default_value(sources.every),
       "a keyframe every N frames (1-10000)")
      ("synthetic-frames", tools::rangedValue(&sources.synthetic_frames, std::size_t{1}, std::size_t{100000})
                               ->default_value(sources.synthetic_frames), "synthetic: frames (1-100000)")
      ("frames-per-loop", tools::rangedValue(&sources.frames_per_loop, 10.0, 1e6)->default_value(sources.frames_per_loop),
       "synthetic: frames to go once round (10-1e6)")
      ("aliased", po::bool_switch(&sources.aliased), "synthetic: repeated texture (perceptual aliasing)");
  // clang-format on
}

int train(int argc, const char* const argv[]) {
  Sources sources;
  mapping::VocabularyTrainingOptions options;
  std::string out;
  po::options_description description(
      "wicp_vocabulary train (--dataset DIR | --synthetic SEED)... --out FILE [--branching K] [--depth L]\n"
      "Trains the vocabulary tree on the ORB descriptors of keyframes every --every frames and writes it\n"
      "(text, docs/place_recognition.md) atomically. Exit 1 on errors, 2 on a bad command line. Options");
  description.add_options()("help,h", "print this help")("out", po::value(&out)->required(), "vocabulary file")(
      "branching", tools::rangedValue(&options.branching, 2u, 64u)->default_value(options.branching),
      "children per node (2-64)")("depth", tools::rangedValue(&options.depth, 1u, 8u)->default_value(options.depth),
                                  "levels (1-8)")(
      "seed", tools::rangedValue(&options.seed, std::uint64_t{0})->default_value(options.seed), "k-means++ seed");
  addSourceOptions(description, sources);
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, description, vm)) return 0;
  const std::vector<cv::Mat> images = descriptorsOf(loadSources(sources));
  const mapping::BinaryVocabulary vocabulary = mapping::BinaryVocabulary::train(images, options);
  std::ostringstream text;
  vocabulary.write(text);
  tools::writeTextFile(out, text.str());
  std::cout
      << tools::JsonObject().add("images", images.size()).add("words", vocabulary.wordCount()).add("out", out).str()
      << "\n";
  return 0;
}

constexpr double kDegree = 3.14159265358979323846 / 180.0;
/// An accepted loop is true when its relative pose is this close to the truth.
constexpr double kTrueLoopMetres = 0.10, kTrueLoopDegrees = 3.0;

/// One query's best candidate by appearance alone, and the truth about it.
struct Ranked {
  double normalised = 0.0;
  bool correct = false;
};

/// @brief What the evaluation counts over every query keyframe.
struct EvaluationTally {
  std::vector<Ranked> ranked;
  std::size_t queries = 0, revisits = 0, accepted = 0, accepted_true = 0, queries_closed = 0;
};

/// @brief evaluate's command line.
struct EvaluateCommand {
  Sources sources;
  std::string vocabulary_path;
  bool self_trained = false;
  double min_overlap = 0.3;
  mapping::PlaceRecognitionOptions place;
};

/// @brief Parses evaluate's command line; false when only --help was asked for.
bool parseEvaluate(int argc, const char* const argv[], EvaluateCommand& c) {
  po::options_description description(
      "wicp_vocabulary evaluate (--vocabulary FILE | --self-trained) (--dataset DIR | --synthetic SEED)\n"
      "Precision and recall of place recognition on sequences with ground truth: a query's true revisits are\n"
      "the older keyframes (beyond --exclude-recent) seeing at least --min-overlap of its landmarks. Reports\n"
      "the top candidate by appearance over score thresholds, and the whole pipeline (temporal consistency,\n"
      "verification with the odometry prior; a loop is false when its pose is off the truth by more than\n"
      "10 cm or 3 degrees) as JSON. Options");
  // clang-format off
  description.add_options()
      ("help,h", "print this help")
      ("vocabulary", po::value(&c.vocabulary_path), "vocabulary file (trained on other data)")
      ("self-trained", po::bool_switch(&c.self_trained),
       "train the vocabulary on the evaluated keyframes themselves (what an online vocabulary "
       "could at best learn; overfits by construction)")
      ("min-overlap", tools::rangedValue(&c.min_overlap, 0.0, 1.0)->default_value(c.min_overlap),
       "viewing overlap of a true revisit (0-1)")
      ("exclude-recent", tools::rangedValue(&c.place.exclude_recent, std::size_t{0})->default_value(c.place.exclude_recent),
       "keyframes next to the query never proposed");
  // clang-format on
  addSourceOptions(description, c.sources);
  po::variables_map vm;
  if (!tools::parseCommandLine(argc, argv, description, vm)) return false;
  if (c.vocabulary_path.empty() == !c.self_trained)
    throw po::error("give exactly one of --vocabulary and --self-trained");
  return true;
}

/// @brief True when an older keyframe, not covisible and beyond the excluded recent ones, sees enough of the query.
bool hasTrueRevisit(const Keyframes& k, frontend::KeyframeId id, const std::set<frontend::KeyframeId>& covisible,
                    const EvaluateCommand& c) {
  for (const auto& [other, unused] : k.snapshot.keyframes)
    if (other + c.place.exclude_recent < id && !covisible.count(other) &&
        mapping::viewOverlap(k.snapshot, id, other, k.camera) >= c.min_overlap)
      return true;
  return false;
}

/// @brief A loop is true when its relative pose is within kTrueLoopMetres and kTrueLoopDegrees of the truth (the
/// keyframes' poses are the truth here).
bool isTrueLoop(const Keyframes& k, frontend::KeyframeId query, frontend::KeyframeId match,
                const Eigen::Isometry3d& query_in_match) {
  const Eigen::Isometry3d error =
      (k.snapshot.keyframes.at(match).pose_wc.inverse() * k.snapshot.keyframes.at(query).pose_wc).inverse() *
      query_in_match;
  return error.translation().norm() <= kTrueLoopMetres &&
         Eigen::AngleAxisd(error.linear()).angle() <= kTrueLoopDegrees * kDegree;
}

/// @brief Every keyframe of one sequence as a query, in order: appearance ranking and the whole pipeline.
void evaluateSequence(const Keyframes& k, const mapping::BinaryVocabulary::ConstPtr& vocabulary,
                      const EvaluateCommand& c, EvaluationTally& tally) {
  mapping::PlaceRecognizer recognizer(vocabulary, c.place);
  const mapping::LoopVerifier verifier(k.camera);
  for (const auto& [id, keyframe] : k.snapshot.keyframes) {
    const mapping::BowVector bow = vocabulary->transform(keyframe.descriptors);
    const std::set<frontend::KeyframeId> covisible = k.snapshot.covisible(id);
    ++tally.queries;
    tally.revisits += hasTrueRevisit(k, id, covisible, c) ? 1 : 0;
    const auto candidates = recognizer.rank(id, bow, covisible);
    const double reference = recognizer.referenceScore(id, bow);
    if (!candidates.empty() && reference > 0.0)
      tally.ranked.push_back(
          {std::min(1.0, candidates.front().score / reference),
           mapping::viewOverlap(k.snapshot, id, candidates.front().keyframe, k.camera) >= c.min_overlap});
    bool closed = false;
    for (const mapping::PlaceCandidate& candidate : recognizer.detect(id, bow, covisible)) {
      const auto result = verifier.verify(k.snapshot, id, k.snapshot, candidate.keyframe,
                                          mapping::odometryPrior(k.snapshot, id, candidate.keyframe));
      if (!result.accepted) continue;
      ++tally.accepted;
      const bool true_loop = isTrueLoop(k, id, candidate.keyframe, result.constraint.query_in_match);
      tally.accepted_true += true_loop ? 1 : 0;
      closed = closed || true_loop;
    }
    tally.queries_closed += closed ? 1 : 0;
    recognizer.add(id, bow);
  }
}

/// @brief The JSON line: precision and recall of the top candidate over score thresholds, and of the pipeline.
std::string evaluationJson(const EvaluationTally& t, std::size_t words) {
  tools::JsonObject json;
  json.add("keyframes", t.queries).add("queries_with_revisit", t.revisits).add("words", words);
  for (double threshold : {0.0, 0.5, 0.7, 0.8, 0.9, 0.95}) {
    std::size_t proposed = 0, correct = 0;
    for (const Ranked& r : t.ranked)
      if (r.normalised >= threshold) ++proposed, correct += r.correct;
    std::ostringstream key;
    key << "top1_at_" << threshold;
    json.add(key.str() + "_precision", proposed ? static_cast<double>(correct) / proposed : 1.0);
    json.add(key.str() + "_recall", t.revisits ? static_cast<double>(correct) / t.revisits : 0.0);
  }
  json.add("pipeline_loops_accepted", t.accepted)
      .add("pipeline_loops_false", t.accepted - t.accepted_true)
      .add("pipeline_precision", t.accepted ? static_cast<double>(t.accepted_true) / t.accepted : 1.0)
      .add("pipeline_recall", t.revisits ? static_cast<double>(t.queries_closed) / t.revisits : 0.0);
  return json.str();
}

int evaluate(int argc, const char* const argv[]) {
  EvaluateCommand command;
  if (!parseEvaluate(argc, argv, command)) return 0;
  // A bad vocabulary file fails before any frame is read.
  mapping::BinaryVocabulary::ConstPtr vocabulary;
  if (!command.vocabulary_path.empty())
    vocabulary =
        std::make_shared<const mapping::BinaryVocabulary>(mapping::BinaryVocabulary::load(command.vocabulary_path));
  const std::vector<Keyframes> all = loadSources(command.sources);
  if (!vocabulary)
    vocabulary =
        std::make_shared<const mapping::BinaryVocabulary>(mapping::BinaryVocabulary::train(descriptorsOf(all)));
  EvaluationTally tally;
  for (const Keyframes& k : all) evaluateSequence(k, vocabulary, command, tally);
  std::cout << evaluationJson(tally, vocabulary->wordCount()) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return tools::runTool("wicp_vocabulary", [&] {
    const std::string usage =
        "usage: wicp_vocabulary train|evaluate [options]   (wicp_vocabulary COMMAND --help for each)";
    if (argc < 2) throw po::error(usage);
    const std::string command = argv[1];
    if (command == "-h" || command == "--help") {
      std::cout << usage << "\n";
      return 0;
    }
    if (command == "train") return train(argc - 1, argv + 1);
    if (command == "evaluate") return evaluate(argc - 1, argv + 1);
    throw po::error("unknown command '" + command + "'; " + usage);
  });
}

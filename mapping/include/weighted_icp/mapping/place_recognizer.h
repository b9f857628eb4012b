#pragma once
// Place recognition over a bag of binary words: a database of keyframes'
// bag-of-words vectors with an inverted file, scored against each new
// keyframe, grouped into places and kept only when consecutive queries agree
// (DBoW2's temporal consistency).

#include <cstddef>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "weighted_icp/frontend/slam/map_point.h"
#include "weighted_icp/mapping/binary_vocabulary.h"

namespace weighted_icp::mapping {

/// @brief When a database keyframe counts as a loop candidate.
struct PlaceRecognitionOptions {
  /// Keyframes of the query's segment whose ids are within this many of the query's are never proposed: tracking
  /// links them. Across a tracking loss nothing does, and the keyframes just before it are the likeliest link.
  std::size_t exclude_recent = 20;
  /// Smallest normalised score (the score divided by the query's score with the keyframe just before it,
  /// DBoW2's normalisation, which makes scores comparable across scenes of different texture).
  double min_normalised_score = 0.3;
  /// Queries whose score with the keyframe before them is below this are skipped (DBoW2): too few or too
  /// common words to compare anything by.
  double min_reference_score = 0.005;
  /// Keyframes whose ids differ by at most this form one place ("island"); its score is the sum of theirs.
  std::size_t place_radius = 3;
  /// Places scoring below this fraction of the best place are dropped.
  double min_fraction_of_best = 0.75;
  /// At most this many places per query.
  std::size_t max_places = 3;
  /// A place is proposed once this many consecutive queries found it (or a place next to it);
  /// 1 turns temporal consistency off.
  std::size_t consistent_queries = 3;
};

/// @brief A database keyframe proposed for a query.
struct PlaceCandidate {
  /// @brief The best-scoring keyframe of its place.
  frontend::KeyframeId keyframe = 0;
  /// @brief Its L1 score with the query (0..1).
  double score = 0.0;
  /// @brief The score divided by the query's reference score, capped at 1.
  double normalised_score = 0.0;
  /// @brief How many consecutive queries found this place so far (this one included).
  std::size_t consistent_queries = 0;
};

/// @brief The keyframe database with its inverted file, and the temporal-consistency state.
/// Not thread-safe: one thread (the loop closer) owns it; the vocabulary may be shared.
class PlaceRecognizer {
 public:
  /// @brief An empty database over a vocabulary.
  /// @param vocabulary the vocabulary; null throws std::invalid_argument
  /// @param options the thresholds; a fraction out of [0, 1] or consistent_queries 0 throws std::invalid_argument
  explicit PlaceRecognizer(BinaryVocabulary::ConstPtr vocabulary, PlaceRecognitionOptions options = {});

  /// @brief The class name, as PCL classes report it.
  static std::string getClassName() { return "PlaceRecognizer"; }
  /// @brief The options in use.
  const PlaceRecognitionOptions& options() const { return options_; }
  /// @brief The vocabulary in use.
  const BinaryVocabulary& vocabulary() const { return *vocabulary_; }

  /// @brief Describes a keyframe by its words and stores it (replacing a keyframe of the same id).
  /// @param keyframe its id
  /// @param descriptors its ORB descriptors (CV_8U, 32 columns)
  /// @param segment its tracking segment (frontend::Keyframe::segment)
  /// @return its bag-of-words vector
  const BowVector& add(frontend::KeyframeId keyframe, const cv::Mat& descriptors, std::size_t segment = 0);
  /// @brief Stores a keyframe's vector as it is (replacing a keyframe of the same id).
  /// @param keyframe its id
  /// @param bow its bag-of-words vector (from the same vocabulary)
  /// @param segment its tracking segment (frontend::Keyframe::segment)
  const BowVector& add(frontend::KeyframeId keyframe, BowVector bow, std::size_t segment = 0);
  /// @brief A stored keyframe's vector, if it is stored.
  /// @param keyframe its id
  std::optional<BowVector> bow(frontend::KeyframeId keyframe) const;
  /// @brief The number of stored keyframes.
  std::size_t size() const { return database_.size(); }

  /// @brief Scores every stored keyframe sharing a word with `bow` (through the inverted file), leaving out
  /// `excluded` and those of its segment within exclude_recent of `query`; best first (ties: older first).
  /// @param query the query keyframe's id
  /// @param bow its vector
  /// @param excluded keyframes not to propose (those sharing landmarks with the query)
  /// @param segment the query's tracking segment
  std::vector<PlaceCandidate> rank(frontend::KeyframeId query, const BowVector& bow,
                                   const std::set<frontend::KeyframeId>& excluded, std::size_t segment = 0) const;

  /// @brief The query's score with the latest stored keyframe before it (0 when there is none): what scores are
  /// normalised by.
  /// @param query the query keyframe's id
  /// @param bow its vector
  double referenceScore(frontend::KeyframeId query, const BowVector& bow) const;

  /// @brief One loop query: rank, normalise, group into places, and keep the places that consecutive queries
  /// agree on. Call it once per new keyframe, in order (a query without any place breaks every chain).
  /// @param query the query keyframe's id
  /// @param bow its vector (it need not be stored; add it afterwards so that later queries can find it)
  /// @param excluded keyframes not to propose (those sharing landmarks with the query)
  /// @param segment the query's tracking segment
  /// @return the candidates that passed temporal consistency, best first
  std::vector<PlaceCandidate> detect(frontend::KeyframeId query, const BowVector& bow,
                                     const std::set<frontend::KeyframeId>& excluded, std::size_t segment = 0);

  /// @brief Forgets the consistency chains (e.g. after a loop was closed, or tracking was lost).
  void resetConsistency() { groups_.clear(); }

 private:
  struct Place {
    frontend::KeyframeId first = 0, last = 0;  // id range
    PlaceCandidate best;
    double score_sum = 0.0;
  };
  std::vector<Place> places(std::vector<PlaceCandidate> candidates) const;

  BinaryVocabulary::ConstPtr vocabulary_;
  PlaceRecognitionOptions options_;
  std::map<frontend::KeyframeId, BowVector> database_;
  std::map<frontend::KeyframeId, std::size_t> segment_of_;
  /// word -> (keyframe, its weight of the word) for the keyframes containing it: scoring reads weights
  /// from here, never from the database's maps.
  std::vector<std::vector<std::pair<frontend::KeyframeId, double>>> inverted_file_;
  struct Group {
    frontend::KeyframeId first = 0, last = 0;
    std::size_t count = 0;
  };
  std::vector<Group> groups_;  // the previous query's places and how long their chains are
};

}  // namespace weighted_icp::mapping

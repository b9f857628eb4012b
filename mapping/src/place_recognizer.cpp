// Place recognition (see place_recognizer.h): the inverted file, DBoW2's
// normalised score, places ("islands") and temporal consistency.

#include "weighted_icp/mapping/place_recognizer.h"

#include <algorithm>
#include <stdexcept>
#include <unordered_map>

namespace weighted_icp::mapping {

PlaceRecognizer::PlaceRecognizer(BinaryVocabulary::ConstPtr vocabulary, PlaceRecognitionOptions options)
    : vocabulary_(std::move(vocabulary)), options_(options) {
  if (!vocabulary_) throw std::invalid_argument("PlaceRecognizer: the vocabulary is null");
  const auto fraction = [](double x) { return x >= 0.0 && x <= 1.0; };
  if (!fraction(options_.min_normalised_score) || !fraction(options_.min_reference_score) ||
      !fraction(options_.min_fraction_of_best))
    throw std::invalid_argument(
        "PlaceRecognizer: min_normalised_score, min_reference_score and min_fraction_of_best must be in [0, 1]");
  if (options_.consistent_queries < 1 || options_.max_places < 1)
    throw std::invalid_argument("PlaceRecognizer: consistent_queries and max_places must be at least 1");
  inverted_file_.resize(vocabulary_->wordCount());
}

const BowVector& PlaceRecognizer::add(frontend::KeyframeId keyframe, const cv::Mat& descriptors, std::size_t segment) {
  return add(keyframe, vocabulary_->transform(descriptors), segment);
}

const BowVector& PlaceRecognizer::add(frontend::KeyframeId keyframe, BowVector bow, std::size_t segment) {
  for (const auto& [word, value] : bow)
    if (word >= inverted_file_.size())
      throw std::invalid_argument("PlaceRecognizer: word " + std::to_string(word) + " is not in the vocabulary");
  if (const auto old = database_.find(keyframe); old != database_.end())
    for (const auto& [word, value] : old->second) {
      auto& list = inverted_file_[word];
      list.erase(std::remove_if(list.begin(), list.end(), [&](const auto& entry) { return entry.first == keyframe; }),
                 list.end());
    }
  for (const auto& [word, value] : bow) inverted_file_[word].emplace_back(keyframe, value);
  segment_of_[keyframe] = segment;
  return database_[keyframe] = std::move(bow);
}

std::optional<BowVector> PlaceRecognizer::bow(frontend::KeyframeId keyframe) const {
  const auto found = database_.find(keyframe);
  if (found == database_.end()) return std::nullopt;
  return found->second;
}

std::vector<PlaceCandidate> PlaceRecognizer::rank(frontend::KeyframeId query, const BowVector& bow,
                                                  const std::set<frontend::KeyframeId>& excluded,
                                                  std::size_t segment) const {
  // The inverted file names the keyframes sharing a word; the L1 score is then summed over the common words
  // alone (|a|+|b|-|a-b| per word), which is why a database of thousands stays fast.
  std::unordered_map<frontend::KeyframeId, double> common;
  const auto recent = [&](frontend::KeyframeId id) {
    const frontend::KeyframeId gap = id > query ? id - query : query - id;
    return gap <= options_.exclude_recent && segment_of_.at(id) == segment;
  };
  for (const auto& [word, value] : bow) {
    if (word >= inverted_file_.size()) continue;
    for (const auto& [id, other] : inverted_file_[word]) {
      if (recent(id) || excluded.count(id)) continue;
      common[id] += value + other - std::abs(value - other);
    }
  }
  std::vector<PlaceCandidate> ranked;
  ranked.reserve(common.size());
  for (const auto& [id, sum] : common) ranked.push_back({id, std::clamp(0.5 * sum, 0.0, 1.0), 0.0, 0});
  std::sort(ranked.begin(), ranked.end(), [](const PlaceCandidate& a, const PlaceCandidate& b) {
    return a.score != b.score ? a.score > b.score : a.keyframe < b.keyframe;
  });
  return ranked;
}

double PlaceRecognizer::referenceScore(frontend::KeyframeId query, const BowVector& bow) const {
  auto before = database_.lower_bound(query);
  if (before == database_.begin()) return 0.0;
  --before;
  return BinaryVocabulary::score(bow, before->second);
}

std::vector<PlaceRecognizer::Place> PlaceRecognizer::places(std::vector<PlaceCandidate> candidates) const {
  // Islands: candidates sorted by id, split where two ids are more than place_radius apart.
  std::sort(candidates.begin(), candidates.end(),
            [](const PlaceCandidate& a, const PlaceCandidate& b) { return a.keyframe < b.keyframe; });
  std::vector<Place> result;
  for (const PlaceCandidate& c : candidates) {
    if (result.empty() || c.keyframe - result.back().last > options_.place_radius)
      result.push_back({c.keyframe, c.keyframe, c, 0.0});
    Place& place = result.back();
    place.last = c.keyframe;
    place.score_sum += c.score;
    if (c.score > place.best.score) place.best = c;
  }
  std::sort(result.begin(), result.end(), [](const Place& a, const Place& b) {
    return a.score_sum != b.score_sum ? a.score_sum > b.score_sum : a.first < b.first;
  });
  if (!result.empty()) {
    const double floor = options_.min_fraction_of_best * result.front().score_sum;
    result.erase(std::remove_if(result.begin(), result.end(), [&](const Place& p) { return p.score_sum < floor; }),
                 result.end());
  }
  if (result.size() > options_.max_places) result.resize(options_.max_places);
  return result;
}

std::vector<PlaceCandidate> PlaceRecognizer::detect(frontend::KeyframeId query, const BowVector& bow,
                                                    const std::set<frontend::KeyframeId>& excluded,
                                                    std::size_t segment) {
  const double reference = referenceScore(query, bow);
  std::vector<PlaceCandidate> kept;
  if (reference >= options_.min_reference_score && reference > 0.0)
    for (PlaceCandidate c : rank(query, bow, excluded, segment)) {
      c.normalised_score = std::min(1.0, c.score / reference);
      if (c.normalised_score >= options_.min_normalised_score) kept.push_back(c);
    }
  // Temporal consistency: a place continues a chain of the previous query when their id ranges, widened by
  // place_radius, overlap; the chain is then one longer.
  std::vector<Group> groups;
  std::vector<PlaceCandidate> detected;
  for (const Place& place : places(std::move(kept))) {
    std::size_t count = 1;
    for (const Group& previous : groups_)
      if (place.first <= previous.last + options_.place_radius && previous.first <= place.last + options_.place_radius)
        count = std::max(count, previous.count + 1);
    groups.push_back({place.first, place.last, count});
    if (count >= options_.consistent_queries) {
      PlaceCandidate candidate = place.best;
      candidate.consistent_queries = count;
      detected.push_back(candidate);
    }
  }
  groups_ = std::move(groups);
  return detected;
}

}  // namespace weighted_icp::mapping

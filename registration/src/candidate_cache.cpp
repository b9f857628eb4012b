// CandidateCache: gather 4(k + 1) nearest once, rank them (or re-check the remembered k + 1) while provably complete.
#include "weighted_icp/registration/candidate_cache.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace weighted_icp {

namespace {

/// Relative padding of every bound against float rounding (which is about 1e-7 of the values).
constexpr double kPad = 1e-5;

/// |a - b| in double from float coordinates.
double distance(const float* a, const float* b) {
  const double d0 = static_cast<double>(a[0]) - b[0];
  const double d1 = static_cast<double>(a[1]) - b[1];
  const double d2 = static_cast<double>(a[2]) - b[2];
  return std::sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/// An upper bound on the true distance whose float square is `squared`.
double paddedUp(float squared, double magnitude) {
  return std::sqrt(static_cast<double>(squared)) * (1.0 + kPad) + kPad * magnitude;
}

/// A lower bound on the true distance whose float square is `squared`.
double paddedDown(float squared, double magnitude) {
  return std::sqrt(static_cast<double>(squared)) * (1.0 - kPad) - kPad * magnitude;
}

bool strictlyIncreasing(const float* distances, std::size_t count) {
  for (std::size_t i = 1; i < count; ++i)
    if (!(distances[i] > distances[i - 1])) return false;
  return true;
}

}  // namespace

void CandidateCache::reset(std::size_t slots) {
  entries_.clear();
  rows_.clear();
  top_rows_.clear();
  stride_ = top_stride_ = 0;
  entries_.resize(slots);
  actions_.assign(slots, Action::kNone);
}

void CandidateCache::resize(std::size_t slots, std::size_t k) {
  if (k + 1 > top_stride_) {
    // Room for more neighbours than the entries were gathered for: start afresh.
    entries_.clear();
    top_stride_ = k + 1;
    stride_ = kGatherFactor * top_stride_;
  }
  if (slots == entries_.size() && rows_.size() == slots * stride_) return;
  entries_.resize(slots);
  actions_.assign(slots, Action::kNone);
  rows_.resize(slots * stride_);
  top_rows_.resize(slots * top_stride_);
}

std::size_t CandidateCache::count(Action action) const {
  return static_cast<std::size_t>(std::count(actions_.begin(), actions_.end(), action));
}

std::size_t CandidateCache::candidateCount() const {
  std::size_t total = 0;
  for (const auto& entry : entries_)
    if (entry.reach > 0.0f) total += entry.count;
  return total;
}

void CandidateCache::remember(std::size_t slot, const float* xyz, const Work& work, std::size_t wanted, float next_sq,
                              double others, double magnitude) {
  // Every point but the `wanted` ranked ones is at least `bound` from xyz: the next candidate, or a
  // point never gathered (`others`).
  Entry& entry = entries_[slot];
  entry.outside = -1.0f;
  if (!strictlyIncreasing(work.distances_.data(), wanted)) return;  // a tie: FLANN orders it, every time
  const double bound = std::min(others, paddedDown(next_sq, magnitude));
  if (!(bound > 0.0)) return;
  std::copy(xyz, xyz + 3, entry.anchor);
  std::copy(work.rows_.begin(), work.rows_.begin() + wanted, remembered(slot));
  entry.top = static_cast<std::uint32_t>(wanted);
  entry.outside = static_cast<float>(bound);
}

bool CandidateCache::fromAnchor(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                                std::size_t wanted, double magnitude) {
  Entry& entry = entries_[slot];
  if (!(entry.outside > 0.0f) || entry.top != wanted) return false;
  const NearestNeighborIndex::Row* top = remembered(slot);
  NearestNeighborIndex::Row* rows = work.rows_.data();
  float* distances = work.distances_.data();
  for (std::size_t i = 0; i < wanted; ++i) {
    rows[i] = top[i];
    distances[i] = NearestNeighborIndex::squaredDistance(xyz, index.point(top[i]));
  }
  // Still strictly ordered, and the farthest of them nearer than any other point can have come.
  if (strictlyIncreasing(distances, wanted) &&
      paddedUp(distances[wanted - 1], magnitude) + distance(xyz, entry.anchor) < entry.outside)
    return true;
  entry.outside = -1.0f;
  return false;
}

bool CandidateCache::fromCandidates(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                                    std::size_t wanted, double magnitude) {
  Entry& entry = entries_[slot];
  if (!(entry.reach > 0.0f) || entry.count < wanted) return false;
  const double moved = distance(xyz, entry.origin);
  if (!(moved < entry.reach)) return false;
  // Keep the wanted + 1 smallest distances, sorted; an equal one does not displace (as a tree search).
  const std::size_t keep = std::min<std::size_t>(wanted + 1, entry.count);
  const NearestNeighborIndex::Row* candidates_begin = candidates(slot);
  float* all = work.gather_distances_.data();
  for (std::uint32_t j = 0; j < entry.count; ++j)
    all[j] = NearestNeighborIndex::squaredDistance(xyz, index.point(candidates_begin[j]));
  NearestNeighborIndex::Row* best_rows = work.rows_.data();
  float* best = work.distances_.data();
  std::size_t count = 0;
  for (std::uint32_t j = 0; j < entry.count; ++j) {
    const float d = all[j];
    if (count == keep && !(d < best[keep - 1])) continue;
    std::size_t i = count < keep ? count++ : keep - 1;
    for (; i > 0 && best[i - 1] > d; --i) {
      best[i] = best[i - 1];
      best_rows[i] = best_rows[i - 1];
    }
    best[i] = d;
    best_rows[i] = candidates_begin[j];
  }
  // Every point never gathered is at least reach - moved from xyz.
  if (!(paddedUp(best[wanted - 1], magnitude) + moved < entry.reach)) return false;
  const float next_sq = count > wanted ? best[wanted] : std::numeric_limits<float>::max();
  remember(slot, xyz, work, wanted, next_sq, entry.reach - moved, magnitude);
  return true;
}

std::size_t CandidateCache::search(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                                   std::size_t wanted, double magnitude) {
  Entry& entry = entries_[slot];
  entry.outside = -1.0f;
  // A point still moving by more than a margin per query would outrun new candidates at once: search
  // only, and gather when it has slowed down (as ICP's points do after the first iterations).
  const bool moving =
      entry.has_last && !(NearestNeighborIndex::squaredDistance(xyz, entry.last) <= entry.step_limit_sq);
  std::copy(xyz, xyz + 3, entry.last);
  entry.has_last = true;
  if (moving) {
    entry.reach = -1.0f;
    const std::size_t found = index.nearest(xyz, wanted, work.rows_.data(), work.distances_.data());
    entry.step_limit_sq = kMarginFraction * kMarginFraction * (found ? work.distances_[found - 1] : 0.0f);
    return found;
  }
  // One search for kGatherFactor times the neighbours: its first `wanted` are this query's answer, all of
  // them are the candidates.
  const std::size_t gathered = std::min(index.size(), kGatherFactor * wanted);
  const std::size_t found = index.nearest(xyz, gathered, work.gather_rows_.data(), work.gather_distances_.data());
  entry.reach = -1.0f;
  if (found == 0) return 0;
  const std::size_t answer = std::min(found, wanted);
  std::copy(work.gather_rows_.begin(), work.gather_rows_.begin() + answer, work.rows_.begin());
  std::copy(work.gather_distances_.begin(), work.gather_distances_.begin() + answer, work.distances_.begin());
  const double d = std::sqrt(static_cast<double>(work.gather_distances_[answer - 1]));
  entry.step_limit_sq = static_cast<float>(kMarginFraction * kMarginFraction * d * d);
  double reach;
  if (found == index.size()) {
    reach = std::numeric_limits<float>::max() / 4;  // every point is a candidate: complete anywhere
  } else {
    // Every point nearer than the farthest gathered one is gathered.
    reach = paddedDown(work.gather_distances_[found - 1], magnitude);
    if (!(reach > 0.0)) return answer;  // a crowd at one distance: searched every time
  }
  std::copy(xyz, xyz + 3, entry.origin);
  std::copy(work.gather_rows_.begin(), work.gather_rows_.begin() + found, candidates(slot));
  entry.count = static_cast<std::uint32_t>(found);
  entry.reach = static_cast<float>(reach);
  if (answer == wanted) {
    const float next_sq = found > wanted ? work.gather_distances_[wanted] : std::numeric_limits<float>::max();
    remember(slot, xyz, work, wanted, next_sq, reach, magnitude);
  }
  return answer;
}

std::size_t CandidateCache::knn(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                                NearestNeighborIndex::Scratch& scratch) {
  const std::size_t wanted = std::min(scratch.k() + 1, index.size());
  if (wanted == 0) return 0;
  if (wanted > top_stride_) {
    // Not sized for this k (resize() was not called for it): an uncached search.
    actions_[slot] = Action::kSearched;
    return index.knn(xyz, scratch);
  }
  const double magnitude = std::abs(xyz[0]) + std::abs(xyz[1]) + std::abs(xyz[2]);
  if (fromAnchor(slot, xyz, index, work, wanted, magnitude) ||
      fromCandidates(slot, xyz, index, work, wanted, magnitude)) {
    actions_[slot] = Action::kReused;
    return index.resolve(xyz, work.rows_.data(), work.distances_.data(), wanted, scratch);
  }
  actions_[slot] = Action::kSearched;
  const std::size_t found = search(slot, xyz, index, work, wanted, magnitude);
  return index.resolve(xyz, work.rows_.data(), work.distances_.data(), found, scratch);
}

}  // namespace weighted_icp

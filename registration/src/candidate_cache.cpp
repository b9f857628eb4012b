// CandidateCache: gather within d + 2m once, rank the gathered points while the query stays within m.
#include "weighted_icp/registration/candidate_cache.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace weighted_icp {

void CandidateCache::reset(std::size_t slots) {
  entries_.clear();
  resize(slots);
}

void CandidateCache::resize(std::size_t slots) {
  entries_.resize(slots);
  actions_.assign(slots, Action::kNone);
}

std::size_t CandidateCache::count(Action action) const {
  return static_cast<std::size_t>(std::count(actions_.begin(), actions_.end(), action));
}

std::size_t CandidateCache::candidateCount() const {
  std::size_t total = 0;
  for (const auto& entry : entries_) total += entry.rows.size();
  return total;
}

std::size_t CandidateCache::gather(Entry& entry, const float* xyz, const NearestNeighborIndex& index, Work& work,
                                   std::size_t wanted) {
  // One search for kGatherFactor times the neighbours: its first `wanted` are this query's answer, all of
  // them are the candidates, and the margin is what the farthest of them leaves beyond the (k + 1)-th.
  const std::size_t gathered = std::min(index.size(), kGatherFactor * wanted);
  const std::size_t found = index.nearest(xyz, gathered, work.gather_rows_.data(), work.gather_distances_.data());
  entry.rows.clear();
  entry.margin_sq = -1.0f;
  if (found == 0) return 0;
  const std::size_t answer = std::min(found, wanted);
  std::copy(work.gather_rows_.begin(), work.gather_rows_.begin() + answer, work.rows_.begin());
  std::copy(work.gather_distances_.begin(), work.gather_distances_.begin() + answer, work.distances_.begin());
  const double d = std::sqrt(static_cast<double>(work.gather_distances_[answer - 1]));
  entry.step_limit_sq = static_cast<float>(kMarginFraction * kMarginFraction * d * d);
  std::copy(xyz, xyz + 3, entry.origin);
  entry.neighbors = static_cast<std::uint32_t>(wanted);
  double margin;
  if (found == index.size()) {
    margin = std::numeric_limits<float>::max() / 4;  // every point is a candidate: valid anywhere
  } else {
    // Every point nearer than the farthest gathered one is gathered; padded against float rounding.
    const double reach = std::sqrt(static_cast<double>(work.gather_distances_[found - 1]));
    const double magnitude = std::abs(xyz[0]) + std::abs(xyz[1]) + std::abs(xyz[2]);
    margin = 0.5 * (reach * (1.0 - 1e-5) - 1e-5 * magnitude - d);
    if (!(margin > 0.0)) return answer;  // a crowd: no margin left, searched every time
  }
  entry.rows.assign(work.gather_rows_.begin(), work.gather_rows_.begin() + found);
  std::sort(entry.rows.begin(), entry.rows.end());  // row order: the points are read in memory order
  entry.margin_sq = static_cast<float>(margin * margin);
  return answer;
}

std::size_t CandidateCache::knn(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                                NearestNeighborIndex::Scratch& scratch) {
  Entry& entry = entries_[slot];
  const std::size_t wanted = std::min(scratch.k() + 1, index.size());
  if (entry.margin_sq >= 0.0f && wanted <= entry.neighbors &&
      NearestNeighborIndex::squaredDistance(xyz, entry.origin) <= entry.margin_sq) {
    actions_[slot] = Action::kReused;
    // Keep the `wanted` smallest distances, sorted; an equal one does not displace (as a tree search).
    std::size_t count = 0;
    NearestNeighborIndex::Row* best_rows = work.rows_.data();
    float* best = work.distances_.data();
    for (const NearestNeighborIndex::Row row : entry.rows) {
      const float distance = NearestNeighborIndex::squaredDistance(xyz, index.point(row));
      if (count == wanted && !(distance < best[count - 1])) continue;
      std::size_t i = count < wanted ? count++ : count - 1;
      for (; i > 0 && best[i - 1] > distance; --i) {
        best[i] = best[i - 1];
        best_rows[i] = best_rows[i - 1];
      }
      best[i] = distance;
      best_rows[i] = row;
    }
    return index.resolve(xyz, best_rows, best, count, scratch);
  }
  actions_[slot] = Action::kSearched;
  // A point still moving by more than a margin per query would outrun new candidates at once: search
  // only, and gather when it has slowed down (as ICP's points do after the first iterations).
  const bool moving =
      entry.has_last && !(NearestNeighborIndex::squaredDistance(xyz, entry.last) <= entry.step_limit_sq);
  std::copy(xyz, xyz + 3, entry.last);
  entry.has_last = true;
  if (moving) {
    entry.margin_sq = -1.0f;
    entry.rows.clear();
    const std::size_t found = index.nearest(xyz, wanted, work.rows_.data(), work.distances_.data());
    const float d_sq = found ? work.distances_[found - 1] : 0.0f;
    entry.step_limit_sq = kMarginFraction * kMarginFraction * d_sq;
    return index.resolve(xyz, work.rows_.data(), work.distances_.data(), found, scratch);
  }
  const std::size_t found = gather(entry, xyz, index, work, wanted);
  return index.resolve(xyz, work.rows_.data(), work.distances_.data(), found, scratch);
}

}  // namespace weighted_icp

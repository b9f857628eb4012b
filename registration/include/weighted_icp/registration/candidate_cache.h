#pragma once
// Exact reuse of k-nearest candidates across ICP iterations.
//
// When a query point at q0 gathers every target point within
// R = d + 2m, d being the distance to its (k + 1)-th nearest (here: its
// 4(k + 1) nearest, R just below the farthest of them), then at any
// later position q with |q - q0| <= m its k + 1 nearest are among them: the
// (k + 1)-th nearest of q is at most d + |q - q0| from q (the old k + 1 points
// are still there), so each of the new k + 1 nearest is within
// d + 2|q - q0| <= R of q0 (triangle inequality). Ranking the gathered points
// by their float distance to q therefore gives exactly the k + 1 nearest
// distances a tree search would give, and NearestNeighborIndex::resolve()
// turns them into PCL's answer (FLANN's order where two tie). Late in ICP a
// point moves by far less than m per iteration, so most iterations rank a few
// dozen candidates per point instead of searching the tree.
//
// R is kept 1e-5 of the coordinates' magnitude below the farthest gathered
// distance (float rounding of coordinates and distances is 1e-7 of it), so
// rounding cannot leave a point out.
// Entries are per slot (a source point's position in the query order), and
// the cache is keyed by positions only: a slot whose new query lies beyond
// its margin, whatever the reason, is searched again. A slot whose query
// moved more than a margin since its previous query is still moving fast
// (early ICP iterations): it is searched without gathering, which would be
// wasted on the next step.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "weighted_icp/registration/nearest_neighbor_index.h"

namespace weighted_icp {

class CandidateCache {
 public:
  /// Candidates gathered per neighbour asked for (k + 1): the gathering search asks for this many times
  /// k + 1 nearest, and the margin is half the distance from the (k + 1)-th to the farthest of them.
  static constexpr std::size_t kGatherFactor = 4;
  /// A query that moved more than this fraction of d (the distance to its (k + 1)-th nearest) since the
  /// slot's previous query is still moving fast: searched, not gathered.
  static constexpr float kMarginFraction = 0.25f;

  /// Per-thread work space for k-nearest queries with k = `k`.
  class Work {
   public:
    /// @brief Room for the k + 1 best candidates.
    /// @param k  neighbours per query
    explicit Work(std::size_t k)
        : gather_rows_(kGatherFactor * (k + 1)),
          gather_distances_(kGatherFactor * (k + 1)),
          rows_(k + 1),
          distances_(k + 1) {}

   private:
    friend class CandidateCache;
    std::vector<NearestNeighborIndex::Row> gather_rows_;
    std::vector<float> gather_distances_;
    std::vector<NearestNeighborIndex::Row> rows_;
    std::vector<float> distances_;
  };

  /// What the last query of a slot did.
  enum class Action : std::uint8_t { kNone, kReused, kSearched };

  /// @brief Forgets every entry (the target changed) and sizes the cache for `slots` queries.
  /// @param slots  queries per pass
  void reset(std::size_t slots);
  /// @brief Sizes the cache for `slots` queries, keeping the entries of the slots that remain.
  /// @param slots  queries per pass
  void resize(std::size_t slots);
  std::size_t slots() const { return entries_.size(); }

  /// @brief The scratch.k() nearest of `xyz` in `index`, as NearestNeighborIndex::knn() returns them,
  /// from the slot's candidates when `xyz` is within their margin, else from a new search (which gathers
  /// new candidates). Slots are independent: different threads may query different slots at once.
  /// @param slot     the query's slot (< slots())
  /// @param xyz      the query
  /// @param index    the index the cache was filled from (the same since the last reset())
  /// @param work     this thread's work space (for at least scratch.k())
  /// @param scratch  receives the results
  /// @return how many were found
  std::size_t knn(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                  NearestNeighborIndex::Scratch& scratch);

  /// @brief How many slots did `action` in their last query.
  /// @param action  kReused or kSearched
  std::size_t count(Action action) const;
  /// @brief Candidates held in all, for memory figures.
  std::size_t candidateCount() const;

 private:
  struct Entry {
    float origin[3] = {0, 0, 0};
    float margin_sq = -1.0f;      // negative: empty
    std::uint32_t neighbors = 0;  // the k + 1 it was gathered for
    float last[3] = {0, 0, 0};    // the slot's previous query
    bool has_last = false;
    float step_limit_sq = -1.0f;  // a step longer than this since the previous query: still moving
    std::vector<NearestNeighborIndex::Row> rows;
  };
  std::size_t gather(Entry& entry, const float* xyz, const NearestNeighborIndex& index, Work& work, std::size_t wanted);
  std::vector<Entry> entries_;
  std::vector<Action> actions_;
};

}  // namespace weighted_icp

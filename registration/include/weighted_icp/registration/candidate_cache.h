#pragma once
// Exact reuse of k-nearest candidates across ICP iterations.
//
// A query at q0 gathers its 4(k + 1) nearest target points; every other
// target point is at least R from q0, R being the farthest gathered distance.
// At a later position q, |q - q0| = δ, the others are at least R - δ from q
// (triangle inequality). So after ranking the gathered points by their float
// distance to q, if the (k + 1)-th of them, b, satisfies b + δ < R, no other
// point can come before it: the ranking is exactly the k + 1 nearest a tree
// search would give, and NearestNeighborIndex::resolve() turns them into PCL's
// answer (FLANN's order where two tie). The test uses b as found at q, not its
// worst case: a point whose neighbourhood did not thin out may move up to
// R - b, twice the fixed margin (R - d) / 2 the test started from.
//
// Late in ICP points barely move, and ranking all candidates is the cost: a
// slot whose ranked k + 1 were strictly ordered remembers them (the anchor),
// with a bound on every other point's distance from the anchor (the (k + 2)-th
// candidate's, or R - δ); while the query moves ε from the anchor and the k + 1
// recomputed distances stay strictly increasing and below that bound - ε, they
// are still the k + 1 nearest in the same order: k + 1 distances instead of
// 4(k + 1).
//
// Bounds are padded by 1e-5 of the distances and of the coordinates'
// magnitude against float rounding (about 1e-7 of them), so rounding cannot
// let a point in unseen. Entries are per slot (a source point's position in
// the query order) and keyed by positions only: a slot whose query fails the
// test, whatever the reason, is searched again. A slot whose query moved more
// than a quarter of its (k + 1)-th distance since its previous query is still
// moving fast (early ICP iterations): it is searched without gathering, which
// would be wasted on the next step.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "weighted_icp/registration/nearest_neighbor_index.h"

namespace weighted_icp {

class CandidateCache {
 public:
  /// Candidates gathered per neighbour asked for (k + 1): the gathering search asks for this many times
  /// k + 1 nearest (measured on the real map's halves: 3 to 6 cost within 10 % of each other, 4 the least
  /// with the anchors; docs/performance.md).
  static constexpr std::size_t kGatherFactor = 4;
  /// A query that moved more than this fraction of d (the distance to its (k + 1)-th nearest) since the
  /// slot's previous query is still moving fast: searched, not gathered.
  static constexpr float kMarginFraction = 0.25f;

  /// Per-thread work space for k-nearest queries with k = `k`.
  class Work {
   public:
    /// @brief Room for the gathered candidates and the k + 2 best of a ranking.
    /// @param k  neighbours per query
    explicit Work(std::size_t k)
        : gather_rows_(kGatherFactor * (k + 1)),
          gather_distances_(kGatherFactor * (k + 1)),
          rows_(k + 2),
          distances_(k + 2) {}

   private:
    friend class CandidateCache;
    std::vector<NearestNeighborIndex::Row> gather_rows_;
    std::vector<float> gather_distances_;  // also the ranking's distances
    std::vector<NearestNeighborIndex::Row> rows_;
    std::vector<float> distances_;
  };

  /// What the last query of a slot did.
  enum class Action : std::uint8_t { kNone, kReused, kSearched };

  /// @brief Forgets every entry and its storage (the target changed), leaving `slots` empty slots; resize()
  /// sizes it for a k before the next queries (until then queries are answered by uncached searches).
  /// @param slots  queries per pass
  void reset(std::size_t slots);
  /// @brief Sizes the cache for `slots` queries of up to k = `k` neighbours, keeping the entries of the
  /// slots that remain (all are forgotten when k is larger than the cache was sized for). Call before
  /// querying, from one thread.
  /// @param slots  queries per pass
  /// @param k      neighbours per query
  void resize(std::size_t slots, std::size_t k);
  std::size_t slots() const { return entries_.size(); }
  /// @brief Work space for queries on this cache, as sized by the last resize().
  Work makeWork() const { return Work(top_stride_ > 0 ? top_stride_ - 1 : 0); }

  /// @brief The scratch.k() nearest of `xyz` in `index`, as NearestNeighborIndex::knn() returns them,
  /// from the slot's candidates when the test above proves them complete, else from a new search (which
  /// gathers new candidates). Slots are independent: different threads may query different slots at once.
  /// @param slot     the query's slot (< slots())
  /// @param xyz      the query
  /// @param index    the index the cache was filled from (the same since the last reset())
  /// @param work     this thread's work space, from makeWork() after the last resize()
  /// @param scratch  receives the results (k <= the k given to resize())
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
    float origin[3] = {0, 0, 0};  // where the candidates were gathered
    float reach = -1.0f;          // every other point is at least this far from origin; negative: empty
    std::uint32_t count = 0;      // candidates held
    float last[3] = {0, 0, 0};    // the slot's previous query
    bool has_last = false;
    float step_limit_sq = -1.0f;  // a step longer than this since the previous query: still moving
    float anchor[3] = {0, 0, 0};  // where the remembered k + 1 nearest were ranked
    float outside = -1.0f;        // every other point is at least this far from anchor; negative: none
    std::uint32_t top = 0;        // how many nearest are remembered
  };
  /// The slot's candidates and remembered nearest (rows of the index), in the flat arrays.
  NearestNeighborIndex::Row* candidates(std::size_t slot) { return rows_.data() + slot * stride_; }
  NearestNeighborIndex::Row* remembered(std::size_t slot) { return top_rows_.data() + slot * top_stride_; }
  bool fromAnchor(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work, std::size_t wanted,
                  double magnitude);
  bool fromCandidates(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                      std::size_t wanted, double magnitude);
  std::size_t search(std::size_t slot, const float* xyz, const NearestNeighborIndex& index, Work& work,
                     std::size_t wanted, double magnitude);
  void remember(std::size_t slot, const float* xyz, const Work& work, std::size_t wanted, float next_sq, double others,
                double magnitude);

  std::vector<Entry> entries_;
  std::vector<Action> actions_;
  std::size_t stride_ = 0;      // candidates per slot: kGatherFactor (k + 1)
  std::size_t top_stride_ = 0;  // remembered nearest per slot: k + 1
  std::vector<NearestNeighborIndex::Row> rows_;
  std::vector<NearestNeighborIndex::Row> top_rows_;
};

}  // namespace weighted_icp

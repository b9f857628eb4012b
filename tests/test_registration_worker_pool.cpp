// WorkerPool, the search's threading model, on its own: every index is handled exactly once for any loop
// length, chunk and thread count; an exception in any chunk reaches the caller and leaves the pool usable;
// many short runs in a row (where a helper may wake after its run ended) lose and repeat nothing; the
// destructor joins idle workers. Also run under ThreadSanitizer (scripts/run_sanitizers.sh thread registration).

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "weighted_icp/registration/worker_pool.h"

namespace {

using weighted_icp::WorkerPool;

/// Runs one loop and returns how often each index was handled.
std::vector<int> visits(WorkerPool& pool, std::size_t n, std::size_t chunk, unsigned threads) {
  std::vector<std::atomic<int>> counts(n);
  pool.run(n, chunk, threads, [&](std::size_t begin, std::size_t end, unsigned worker) {
    EXPECT_LT(begin, end);
    EXPECT_LE(end, n);
    EXPECT_LT(worker, std::max(threads, 1u));
    for (std::size_t i = begin; i < end; ++i) counts[i].fetch_add(1, std::memory_order_relaxed);
  });
  std::vector<int> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = counts[i].load();
  return out;
}

TEST(WorkerPool, EveryIndexIsHandledExactlyOnce) {
  WorkerPool pool;
  for (const unsigned threads : {0u, 1u, 2u, 3u, 8u})
    for (const std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{63}, std::size_t{64}, std::size_t{1000}})
      for (const std::size_t chunk :
           {std::size_t{0}, std::size_t{1}, std::size_t{7}, std::size_t{64}, std::size_t{5000}}) {
        SCOPED_TRACE("threads " + std::to_string(threads) + ", n " + std::to_string(n) + ", chunk " +
                     std::to_string(chunk));
        const std::vector<int> counts = visits(pool, n, chunk, threads);
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(counts[i], 1) << "index " << i;
      }
}

TEST(WorkerPool, ResultsWrittenPerIndexDoNotDependOnTheThreadCount) {
  const std::size_t n = 10000;
  std::vector<double> reference;
  for (const unsigned threads : {1u, 2u, 4u}) {
    WorkerPool pool;
    std::vector<double> out(n, 0.0);
    pool.run(n, 64, threads, [&](std::size_t begin, std::size_t end, unsigned) {
      for (std::size_t i = begin; i < end; ++i) out[i] = static_cast<double>(i) * 0.5 + 1.0 / (1.0 + i);
    });
    if (reference.empty())
      reference = out;
    else
      EXPECT_EQ(out, reference) << threads << " threads";
  }
}

TEST(WorkerPool, AnExceptionInAnyChunkReachesTheCallerAndThePoolStaysUsable) {
  WorkerPool pool;
  for (const unsigned threads : {1u, 2u, 4u}) {
    for (const std::size_t failing : {std::size_t{0}, std::size_t{500}, std::size_t{999}}) {
      SCOPED_TRACE("threads " + std::to_string(threads) + ", failing index " + std::to_string(failing));
      try {
        pool.run(1000, 16, threads, [&](std::size_t begin, std::size_t end, unsigned) {
          if (begin <= failing && failing < end) throw std::runtime_error("chunk " + std::to_string(begin) + " failed");
        });
        ADD_FAILURE() << "no exception reached the caller";
      } catch (const std::runtime_error& e) {
        EXPECT_EQ(std::string(e.what()), "chunk " + std::to_string(failing / 16 * 16) + " failed");
      }
      // The next run is complete and throws nothing: no error or skipped chunk is left over.
      const std::vector<int> counts = visits(pool, 1000, 16, threads);
      for (std::size_t i = 0; i < counts.size(); ++i) ASSERT_EQ(counts[i], 1) << "index " << i;
    }
  }
}

TEST(WorkerPool, ManyShortRunsInARowLoseNothing) {
  // Runs shorter than a helper's wake-up: helpers often wake after their run ended and must then take nothing
  // from it, and take part in the next one. Also the case ThreadSanitizer watches most closely.
  WorkerPool pool;
  std::atomic<long> total{0};
  const int runs = 2000;
  for (int r = 0; r < runs; ++r)
    pool.run(8, 1, 2, [&](std::size_t begin, std::size_t end, unsigned) {
      total.fetch_add(static_cast<long>(end - begin), std::memory_order_relaxed);
    });
  EXPECT_EQ(total.load(), 8L * runs);
}

TEST(WorkerPool, TheThreadCountMayChangeFromRunToRun) {
  WorkerPool pool;
  for (const unsigned threads : {4u, 1u, 2u, 8u, 2u}) {
    const std::vector<int> counts = visits(pool, 777, 5, threads);
    for (std::size_t i = 0; i < counts.size(); ++i) ASSERT_EQ(counts[i], 1) << threads << " threads, index " << i;
  }
}

TEST(WorkerPool, DestructionJoinsIdleWorkersAndCopiesOwnNoThreads) {
  std::atomic<int> handled{0};
  {
    WorkerPool pool;
    pool.run(100, 1, 4,
             [&](std::size_t begin, std::size_t end, unsigned) { handled.fetch_add(static_cast<int>(end - begin)); });
    WorkerPool copy(pool);  // a copy starts its own threads when it needs them
    copy.run(100, 1, 3,
             [&](std::size_t begin, std::size_t end, unsigned) { handled.fetch_add(static_cast<int>(end - begin)); });
  }  // both destructors join their sleeping workers here; a hang fails the test by ctest's timeout
  EXPECT_EQ(handled.load(), 200);
}

}  // namespace

#pragma once
// Threads that sleep between parallel loops: the search's threading model.
//
// Measured against OpenMP (libgomp spins its idle threads, which on a shared
// 2-core machine steals the core the other thread needs) and against threads
// started per call (docs/performance.md): workers here block on a condition
// variable between loops (a passive wait) and take chunks of the loop from a
// shared counter, so a thread the machine delays leaves its chunks to the
// others. A run ends when its last chunk does: the caller never waits for a
// helper that has not been scheduled yet (on a loaded machine that wait was
// longer than the loop). Which thread runs a chunk never changes a result when each index
// writes only its own output slot, as every caller does.

#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace weighted_icp {

class WorkerPool {
 public:
  /// Loop body: handles indices [begin, end) as worker `worker` (0 is the calling thread).
  using Body = std::function<void(std::size_t begin, std::size_t end, unsigned worker)>;

  WorkerPool() = default;
  /// @brief Stops and joins every worker.
  ~WorkerPool();
  /// @brief A copy has no threads of its own yet (threads are not shared between copies).
  WorkerPool(const WorkerPool&) {}
  /// @brief Keeps this pool's threads: threads are not copied.
  WorkerPool& operator=(const WorkerPool&) { return *this; }

  /// @brief Runs `body` over [0, n) in chunks of `chunk` indices on `threads` threads, the caller being one.
  /// Returns when every chunk is done; the first exception thrown by any chunk is rethrown here (the
  /// remaining chunks are skipped).
  /// @param n        loop length
  /// @param chunk    indices per chunk (>= 1)
  /// @param threads  threads to use (>= 1); workers are started on first need and kept
  /// @param body     the loop body
  void run(std::size_t n, std::size_t chunk, unsigned threads, const Body& body);

 private:
  void workerLoop(unsigned worker);
  /// Claims and runs chunks until none is left or one failed.
  void drain(unsigned worker);

  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  std::vector<std::thread> workers_;
  bool stopping_ = false;
  unsigned long generation_ = 0;  // one per run(); workers wake when it changes
  unsigned active_ = 0;           // helpers that may take part in the current run (ids 1 .. active_)
  std::size_t running_ = 0;       // chunks claimed and not yet finished
  // The current loop, valid while a run() is in progress.
  const Body* body_ = nullptr;
  std::size_t n_ = 0;
  std::size_t chunk_ = 1;
  std::size_t next_ = 0;  // next chunk start, under mutex_
  std::exception_ptr error_;
};

}  // namespace weighted_icp

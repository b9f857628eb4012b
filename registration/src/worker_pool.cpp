// WorkerPool: sleeping workers, chunks claimed from a shared counter.
#include "weighted_icp/registration/worker_pool.h"

#include <algorithm>
#include <utility>

namespace weighted_icp {

WorkerPool::~WorkerPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (auto& worker : workers_) worker.join();
}

void WorkerPool::run(std::size_t n, std::size_t chunk, unsigned threads, const Body& body) {
  chunk = std::max<std::size_t>(chunk, 1);
  const std::size_t chunks = (n + chunk - 1) / chunk;
  const unsigned helpers = static_cast<unsigned>(
      std::min<std::size_t>(threads > 0 ? threads - 1 : 0, chunks - std::min<std::size_t>(chunks, 1)));
  if (helpers == 0) {
    // One thread: no locking, no hand-over.
    for (std::size_t begin = 0; begin < n; begin += chunk) body(begin, std::min(n, begin + chunk), 0);
    return;
  }
  {
    std::unique_lock<std::mutex> lock(mutex_);
    while (workers_.size() < helpers) {
      const unsigned id = static_cast<unsigned>(workers_.size()) + 1;
      workers_.emplace_back([this, id] { workerLoop(id); });
    }
    body_ = &body;
    n_ = n;
    chunk_ = chunk;
    next_ = 0;
    running_ = 0;
    error_ = nullptr;
    active_ = helpers;
    ++generation_;
  }
  wake_.notify_all();
  drain(0);
  // Done when every chunk is claimed and none is running: a helper the machine has not scheduled yet has
  // nothing to finish, so the caller never waits for it to wake.
  std::unique_lock<std::mutex> lock(mutex_);
  done_.wait(lock, [this] { return next_ >= n_ && running_ == 0; });
  body_ = nullptr;
  active_ = 0;
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
}

void WorkerPool::drain(unsigned worker) {
  for (;;) {
    std::size_t begin, end;
    const Body* body;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      // A helper woken after its run ended, or not among this run's helpers, takes nothing.
      if (next_ >= n_ || (worker != 0 && worker > active_)) return;
      begin = next_;
      end = std::min(n_, begin + chunk_);
      next_ = end;
      ++running_;
      body = body_;
    }
    bool failed = false;
    try {
      (*body)(begin, end, worker);
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!error_) error_ = std::current_exception();
      failed = true;
    }
    bool finished;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (failed) next_ = n_;  // skip the remaining chunks
      --running_;
      finished = next_ >= n_ && running_ == 0;
    }
    if (finished) done_.notify_one();
  }
}

void WorkerPool::workerLoop(unsigned worker) {
  unsigned long seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    drain(worker);
  }
}

}  // namespace weighted_icp

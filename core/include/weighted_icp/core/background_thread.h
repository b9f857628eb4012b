#pragma once
// Names the calling thread, so that top -H, perf and gdb tell the background threads (bundle adjustment, loop
// closing) from the tracking thread and OpenCV's pool.

#include <pthread.h>

#include <string>

namespace weighted_icp {

/// @brief Gives the calling thread a name shown by `top -H`, `perf report --sort comm` and debuggers.
/// @param name at most 15 characters (Linux's limit; longer names are cut)
inline void nameThisThread(const std::string& name) {
  // Failure changes nothing but what tools show, so it is not reported.
  (void)pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
}

}  // namespace weighted_icp

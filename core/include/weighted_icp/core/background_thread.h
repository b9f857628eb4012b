#pragma once
// What a background thread (bundle adjustment, loop closing) says about itself to the system: a name, so that
// top -H, perf and gdb tell it from tracking and OpenCV's pool, and a lower scheduling priority where its work may
// wait for tracking's.

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <string>

namespace weighted_icp {

/// @brief Gives the calling thread a name shown by `top -H`, `perf report --sort comm` and debuggers.
/// @param name at most 15 characters (Linux's limit; longer names are cut)
inline void nameThisThread(const std::string& name) {
  // Failure changes nothing but what tools show, so it is not reported.
  (void)pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
}

/// @brief Lowers the calling thread's scheduling priority (Linux: its nice value; other threads keep theirs), so
/// that when the cores are busy tracking runs first and this thread takes the time left over.
/// @param niceness added to the thread's nice value (0: unchanged; at most 19)
/// @return false where the system refused (the thread then runs at the priority it had)
inline bool lowerThisThreadPriority(int niceness) {
  if (niceness <= 0) return true;
#ifdef SYS_gettid
  const auto thread = static_cast<id_t>(::syscall(SYS_gettid));
  errno = 0;
  const int current = ::getpriority(PRIO_PROCESS, thread);
  if (errno != 0) return false;
  return ::setpriority(PRIO_PROCESS, thread, std::min(current + niceness, 19)) == 0;
#else
  return false;
#endif
}

}  // namespace weighted_icp

#pragma once
// One way to run independent jobs on OpenCV's thread pool, serial under ThreadSanitizer.

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

// ThreadSanitizer: gcc defines __SANITIZE_THREAD__, clang answers __has_feature.
#if defined(__SANITIZE_THREAD__)
#define WEIGHTED_ICP_UNDER_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define WEIGHTED_ICP_UNDER_TSAN 1
#endif
#endif

namespace weighted_icp {

/// @brief cv::parallel_for_, run serially in a ThreadSanitizer build: OpenCV's thread pool (TBB, built without
/// TSan) synchronises in code TSan does not see, so every write of its workers would be reported as a race,
/// hiding ours. Callers give jobs whose results do not depend on how the range is split, so the result is the
/// same with any number of threads.
/// @param range the jobs
/// @param body runs a sub-range of them
template <typename Body>
void parallelFor(const cv::Range& range, const Body& body) {
#ifdef WEIGHTED_ICP_UNDER_TSAN
  body(range);
#else
  cv::parallel_for_(range, body);
#endif
}

}  // namespace weighted_icp

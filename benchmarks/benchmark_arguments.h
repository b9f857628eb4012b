#pragma once
// Google Benchmark owns the command line; a benchmark's own path option
// ("--map FILE", "--data DIR") is taken out of argv before it sees it.

#include <cstring>
#include <string>

namespace weighted_icp::benchmarks {

/// If argv holds `name VALUE`, stores VALUE in `value` and removes both.
inline void takeOption(int& argc, char** argv, const char* name, std::string& value) {
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], name) != 0) continue;
    value = argv[i + 1];
    for (int j = i; j + 2 <= argc; ++j) argv[j] = argv[j + 2];
    argc -= 2;
    return;
  }
}

}  // namespace weighted_icp::benchmarks

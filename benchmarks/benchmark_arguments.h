#pragma once
// Google Benchmark owns the command line; a benchmark's own path option
// ("--map FILE", "--data DIR") is taken out of argv before it sees it, and
// the data is loaded (and its errors reported) before the benchmarks run.

#include <cstring>
#include <exception>
#include <iostream>
#include <string>

#include <benchmark/benchmark.h>

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

/// @brief The main of a benchmark program whose data is loaded before Google Benchmark starts: `prepare`
/// loads and reports it; an error there is one line naming the program (exit 1), an option Google
/// Benchmark does not know exits 2.
/// @param program the program's name, for the error line
/// @param argc,argv the command line, with the program's own options already taken out
/// @param prepare loads the data (and registers benchmarks, if they depend on it)
template <typename Prepare>
int runBenchmarks(const char* program, int argc, char** argv, Prepare&& prepare) {
  try {
    prepare();
  } catch (const std::exception& e) {
    std::cerr << program << ": error: " << e.what() << '\n';
    return 1;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

}  // namespace weighted_icp::benchmarks

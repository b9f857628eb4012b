#!/usr/bin/env bash
# Configures ./build-fuzz once: clang-14 with libFuzzer's coverage instrumentation and ASan+UBSan on
# everything this project compiles (-DWEIGHTED_ICP_FUZZ=ON), tests and tools included. scripts/run_fuzzers.sh
# builds its fuzz_<name> binaries there and scripts/run_sanitizers.sh its ASan+UBSan test programs, so CI
# compiles the libraries once for both. Prints the build folder.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-fuzz"
launcher=()  # ccache when present (CI's clean machine has none)
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
if [ ! -f "$build/build.ninja" ]; then
  CC=clang-14 CXX=clang++-14 cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DWEIGHTED_ICP_FUZZ=ON -DWEIGHTED_ICP_BUILD_BENCHMARKS=OFF -DWEIGHTED_ICP_BUILD_PYTHON=OFF "${launcher[@]}" \
    > "$build.configure.log" 2>&1 || { cat "$build.configure.log" >&2; exit 1; }
fi
echo "$build"

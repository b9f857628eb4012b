#!/usr/bin/env bash
# Builds the libFuzzer targets (fuzz/, clang-14, ASan+UBSan) in ./build-fuzz and runs every one of them for
# SECONDS (default 60), two at a time. Usage: bash scripts/run_fuzzers.sh [SECONDS]
#
# Corpus of each target: its committed seeds (fuzz/seeds/<target>/), seeds cut from ../shared/data now
# (scripts/fuzz_seeds.sh; skipped where the data is absent), and what earlier runs found
# (build-fuzz/fuzz-corpus/<target>/, never committed). An input that crashes, hangs (more than 10 s), leaks,
# trips a sanitizer or breaks a target's rule (fuzz/fuzz_support.h) is saved in
# build-fuzz/fuzz-artifacts/<target>/ and fails the script; once fixed, commit it to
# fuzz/regressions/<target>/ so that ctest replays it in every build (test fuzz.<target>).
# Prints executions per target; exit 1 if any target found something.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
seconds="${1:-60}"
jobs=2

"$root/scripts/install_deps.sh"
build="$(bash "$root/scripts/configure_fuzz_build.sh")"
mapfile -t targets < "$build/fuzz/fuzzers.txt"
cmake --build "$build" -j "$(nproc)" --target "${targets[@]/#/fuzz_}"

# The gcc build's wicp_map converts the map seeds to PCD/PLY (skipped when it is not built).
data="$root/../shared/data"
rm -rf "$build/fuzz-seeds"
if [ -d "$data" ]; then
  bash "$root/scripts/fuzz_seeds.sh" "$data" "$build/fuzz-seeds" "$root/build/examples/wicp_map"
else
  echo "run_fuzzers: $data is absent: committed seeds only"
fi

# One target: its corpus folders, a time limit, its own log and artifact folder.
run_target() {
  local target="$1" corpus="$build/fuzz-corpus/$1" artifacts="$build/fuzz-artifacts/$1/"
  mkdir -p "$corpus" "$artifacts"
  local inputs=("$corpus")
  for dir in "$root/fuzz/seeds/$target" "$root/fuzz/regressions/$target" "$build/fuzz-seeds/$target"; do
    [ -d "$dir" ] && inputs+=("$dir")
  done
  # -timeout: an input taking more than 10 s is a hang; -rss_limit_mb: a parser allocating what a header
  # claims is a finding too. The corpus folder (first) receives the new inputs.
  "$build/fuzz/fuzz_$target" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts" "${inputs[@]}" > "$build/fuzz-$target.log" 2>&1
}
export -f run_target
export build root seconds

rm -rf "$build"/fuzz-artifacts "$build"/fuzz-*.log
status=0
printf '%s\n' "${targets[@]}" | xargs -P "$jobs" -I{} bash -c 'run_target {}' || status=1

printf '\n%-14s %12s %10s %8s %s\n' target executions "exec/s" corpus findings
for target in "${targets[@]}"; do
  log="$build/fuzz-$target.log"
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
  corpus=$(ls "$build/fuzz-corpus/$target" | wc -l)
  findings=$(ls "$build/fuzz-artifacts/$target" 2>/dev/null | wc -l)
  printf '%-14s %12s %10s %8s %s\n' "$target" "${execs:-?}" "${rate:-?}" "$corpus" "$findings"
  if [ "$findings" != 0 ]; then
    status=1
    echo "  found: $(ls "$build/fuzz-artifacts/$target" | tr '\n' ' ')(log: $log)"
  fi
done
exit $status

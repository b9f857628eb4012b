#!/usr/bin/env bash
# Builds and runs the whole test suite. Tests that need ../shared/data skip,
# saying so, only where it is absent. Two tests at a time: each has its own scratch folder.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
ctest --test-dir "$root/build" -j2 --output-on-failure --timeout 600

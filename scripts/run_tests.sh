#!/usr/bin/env bash
# Builds and runs the whole test suite. Tests that need ../shared/data skip,
# saying so, only where it is absent.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
ctest --test-dir "$root/build" --output-on-failure --timeout 600

#!/usr/bin/env bash
# The main job: build, then run the demo on the project's own synthetic session
# (no data needed). Arguments go to wicp_demo (see build/examples/wicp_demo --help).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
cd "$root"
exec "$root/build/examples/wicp_demo" "$@"

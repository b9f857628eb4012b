#!/usr/bin/env bash
# The main job, on data the project generates itself (no arguments needed):
#  1. the RGB-D front end on the synthetic sequence -> out/main/slam
#     (trajectory, mini-maps in the paper's format, map.ply, report.json, ATE)
#  2. weighted-ICP alignment of consecutive mini-maps of a synthetic session,
#     every strategy, with and without refinement -> out/demo
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/build.sh"
cd "$root"
echo
echo "== 1/2  RGB-D front end on the synthetic sequence (build/examples/wicp_rgbd_slam)"
# --overwrite: the main job is re-run into the same folder, replaced whole.
"$root/build/examples/wicp_rgbd_slam" --out out/main/slam --overwrite
echo "report: $(cat out/main/slam/report.json)"
echo
echo "== 2/2  Mini-map alignment with the weighted ICP (build/examples/wicp_demo)"
"$root/build/examples/wicp_demo" --out "$root/out/demo" --overwrite

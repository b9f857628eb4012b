#!/usr/bin/env bash
# Writes seed inputs for the fuzz targets, cut from the shared data set at run time (never copied into the
# repository): small valid maps, trajectories and TUM lists, and clouds converted from those maps.
# Usage: bash scripts/fuzz_seeds.sh DATA_DIR OUT_DIR [WICP_MAP]
#   DATA_DIR  ../shared/data (map_fr1_desk.txt, tum_*/)
#   OUT_DIR   receives OUT_DIR/<target>/ for each target it has seeds for
#   WICP_MAP  a built wicp_map, for the PCD/PLY seeds (skipped without it)
# A target without a case here has only its committed seeds (fuzz/seeds/<target>/).
set -euo pipefail
data="$1" out="$2" wicp_map="${3:-}"
mkdir -p "$out"/{map_format,trajectory,tum_sequence,cloud_pcd,cloud_ply}

# Maps: a few landmarks each, with exactly the frames they are observed from.
map="$data/map_fr1_desk.txt"
if [ -f "$map" ]; then
  awk -v out="$out/map_format" '
    $1 == "FRAME" { frame[$2] = $0; next }
    $1 == "LANDMARK" && n < 4000 { landmark[n++] = $0 }
    END {
      for (s = 0; s < 12; ++s) {
        file = sprintf("%s/fr1_desk_%02d.txt", out, s)
        first = s * 317 % n; count = 2 + s % 5
        delete used
        for (i = first; i < first + count && i < n; ++i) {
          split(landmark[i], f, " ")
          for (k = 16; k <= 15 + 3 * f[15]; k += 3) used[f[k]] = 1
        }
        for (id in used) print frame[id] > file
        for (i = first; i < first + count && i < n; ++i) print landmark[i] > file
        close(file)
      }
    }' "$map"
  if [ -n "$wicp_map" ] && [ -x "$wicp_map" ]; then
    for seed in "$out"/map_format/fr1_desk_0[0-5].txt; do
      name=$(basename "$seed" .txt)
      "$wicp_map" convert "$seed" "$out/cloud_pcd/$name.pcd" --min-observations 0 > /dev/null
      "$wicp_map" convert "$seed" "$out/cloud_ply/$name.ply" --min-observations 0 > /dev/null
    done
  fi
fi

# Trajectories and TUM lists: the head and a middle piece of each sequence's files.
for sequence in "$data"/tum_*/; do
  [ -f "$sequence/rgb.txt" ] || continue
  name=$(basename "$sequence")
  head -n 12 "$sequence/groundtruth.txt" > "$out/trajectory/${name}_head.txt"
  sed -n '200,230p' "$sequence/groundtruth.txt" > "$out/trajectory/${name}_middle.txt"
  { head -n 8 "$sequence/rgb.txt"; echo "@@"; head -n 8 "$sequence/depth.txt"; echo "@@"
    head -n 30 "$sequence/groundtruth.txt"; } > "$out/tum_sequence/${name}.txt"
  { head -n 8 "$sequence/rgb.txt"; echo "@@"; head -n 8 "$sequence/depth.txt"; } > "$out/tum_sequence/${name}_no_gt.txt"
done
for target in "$out"/*/; do echo "$(basename "$target"): $(ls "$target" | wc -l) seed(s) from $data"; done

#!/usr/bin/python3
"""The Python module's overhead over the C++ calls it wraps, measured in one process, interleaved.

    PYTHONPATH=build/python /usr/bin/python3 scripts/measure_binding_overhead.py [--runs 9]

1. align: the real map's alternate halves (min_observations 2, the source displaced 5 cm / 4 deg), strategy
   observations, k 5. For each run: wicp_align --json on the saved halves (its time_ms: the ICP stages
   only) and wi.align() from numpy arrays, timed from the call to its return (conversion, weights, target
   index and ICP). Prints the medians and their ratio.
2. track: a 640x480 frame of the TUM fr1/xyz head sequence through RgbdSlam.track() (RGB uint8 + raw uint16
   depth from numpy), timed from the call to its return, against the tracker's own time for that frame
   (TrackResult.tracking_ms, measured inside RgbdSlam::process around Frontend::track). Prints the median
   difference per frame.
The machine may be loaded by other work: the figures are medians, and the report says so.
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import weighted_icp as wi

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("WEIGHTED_ICP_DATA_DIR", ROOT / ".." / "shared" / "data"))
TOOLS = Path(os.environ.get("WEIGHTED_ICP_TOOLS_DIR", ROOT / "build" / "examples"))


def displacement(x: float, y: float, yaw_deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:2, 3] = [x, y]
    return m


def measure_align(runs: int) -> None:
    whole = wi.LandmarkMap.load(DATA / "map_fr1_desk.txt")
    source, target = whole.alternate_halves()
    source.transform(displacement(0.05, -0.03, 4.0))
    with tempfile.TemporaryDirectory() as folder:
        a, b = Path(folder) / "a.txt", Path(folder) / "b.txt"
        source.save(a)
        target.save(b)
        a_map = wi.LandmarkMap.load(a, min_observations=2)
        b_map = wi.LandmarkMap.load(b, min_observations=2)
        a_xyz, b_xyz = a_map.positions, b_map.positions
        tool_ms, python_ms, inner_ms = [], [], []
        for _ in range(runs):
            done = subprocess.run([str(TOOLS / "wicp_align"), "--source", str(a), "--target", str(b),
                                   "--strategy", "observations", "--k", "5", "--json"],
                                  capture_output=True, text=True, check=True)
            tool = json.loads(done.stdout.strip().splitlines()[-1])
            tool_ms.append(tool["time_ms"])
            start = time.perf_counter()
            r = wi.align(a_xyz, b_xyz, target_weights=wi.weights(b_map, "observations"), k=5)
            python_ms.append((time.perf_counter() - start) * 1000.0)
            inner_ms.append(r.time_ms)
            assert np.array_equal(r.transformation, np.array(tool["transformation"])), "results differ"
    print(f"align, {len(a_xyz)} onto {len(b_xyz)} landmarks, {r.iterations} iterations, {runs} runs (medians):")
    print(f"  wicp_align time_ms           {statistics.median(tool_ms):8.2f} ms")
    print(f"  wi.align() wall, from numpy  {statistics.median(python_ms):8.2f} ms "
          f"(its own time_ms {statistics.median(inner_ms):.2f} ms)")
    print(f"  ratio python / tool          {statistics.median(python_ms) / statistics.median(tool_ms):8.3f}")


def measure_track(frames: int) -> None:
    from PIL import Image

    # Without loop closure: deterministic mode would verify loops inside track(), outside tracking_ms.
    slam = wi.RgbdSlam("fr1", deterministic=True, loop_closure=False)
    overhead = []
    for t, rgb_path, depth_path in wi.tum_frames(str(DATA / "tum_fr1_xyz_head"))[:frames]:
        rgb = np.asarray(Image.open(rgb_path).convert("RGB"))
        depth = np.asarray(Image.open(depth_path)).astype(np.uint16)
        start = time.perf_counter()
        result = slam.track(rgb, depth, t)
        wall = (time.perf_counter() - start) * 1000.0
        overhead.append(wall - result.tracking_ms)
    slam.finish()
    print(f"track, {len(overhead)} frames of 640x480 (medians): wall minus the tracker's own time "
          f"{statistics.median(overhead):.3f} ms per frame (max {max(overhead):.3f} ms)")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=9)
    parser.add_argument("--frames", type=int, default=30)
    args = parser.parse_args()
    if not (DATA / "map_fr1_desk.txt").exists():
        print(f"measure_binding_overhead.py: the data set is absent ({DATA})", file=sys.stderr)
        return 1
    measure_align(args.runs)
    measure_track(args.frames)
    return 0


if __name__ == "__main__":
    sys.exit(main())

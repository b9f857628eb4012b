#!/usr/bin/env python3
"""Checks the loops of a run against ground truth: how far each loop's relative pose is from the true one.

Reads the loops.txt of wicp_rgbd_slam (query_timestamp match_timestamp tx ty tz qx qy qz qw inliers fitness) or of
wicp_merge (query_session query_timestamp match_session match_timestamp tx ... fitness used) and one or more TUM ground
truth files (for a merge, every session's groundtruth.txt: synthetic runs share the sequence's world). A keyframe
is paired with the ground-truth pose nearest in time (within --max-difference seconds). A loop is wrong when it is
more than --max-translation metres or --max-rotation degrees from the truth (5 cm, 2 degrees: the README's figures).

    /usr/bin/python3 scripts/check_loops.py --loops run/loops.txt --groundtruth run/groundtruth.txt [--json]

Exit 0 when every loop could be judged and none is wrong, 1 when a loop is wrong, 2 for bad input.
"""
import argparse
import bisect
import json
import sys

import numpy as np


def fail(message):
    print("check_loops: error: " + message, file=sys.stderr)
    sys.exit(2)


def pose(values):
    """4x4 matrix of tx ty tz qx qy qz qw."""
    t, (x, y, z, w) = values[:3], values[3:7]
    norm = np.sqrt(x * x + y * y + z * z + w * w)
    if not norm > 0:
        raise ValueError("zero quaternion")
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = t
    return m


def rows(path):
    """(line number, floats) of every data line."""
    try:
        with open(path) as f:
            lines = f.readlines()
    except OSError as e:
        fail(f"{path}: {e.strerror}")
    for number, line in enumerate(lines, 1):
        if not line.strip() or line.startswith("#"):
            continue
        try:
            yield number, [float(v) for v in line.split()]
        except ValueError:
            fail(f"{path}:{number}: not a line of numbers")


def load_groundtruth(paths):
    poses = {}
    for path in paths:
        for number, v in rows(path):
            if len(v) != 8:
                fail(f"{path}:{number}: expected 8 values (timestamp tx ty tz qx qy qz qw), found {len(v)}")
            try:
                poses[v[0]] = pose(v[1:8])
            except ValueError as e:
                fail(f"{path}:{number}: {e}")
    if not poses:
        fail("no ground-truth pose in " + ", ".join(paths))
    times = sorted(poses)
    return times, [poses[t] for t in times]


def nearest(times, poses, t, max_difference):
    i = bisect.bisect_left(times, t)
    best = min((j for j in (i - 1, i) if 0 <= j < len(times)), key=lambda j: abs(times[j] - t))
    return poses[best] if abs(times[best] - t) <= max_difference else None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--loops", required=True, help="loops.txt of wicp_rgbd_slam or wicp_merge")
    parser.add_argument("--groundtruth", required=True, action="append", help="TUM ground truth (repeatable)")
    parser.add_argument("--max-difference", type=float, default=0.02, help="seconds (default 0.02)")
    parser.add_argument("--max-translation", type=float, default=0.05, help="metres (default 0.05)")
    parser.add_argument("--max-rotation", type=float, default=2.0, help="degrees (default 2)")
    parser.add_argument("--json", action="store_true", help="one JSON object on the last line")
    args = parser.parse_args()

    times, poses = load_groundtruth(args.groundtruth)
    loops, unmatched = [], 0
    for number, v in rows(args.loops):
        if len(v) == 11:
            query_time, match_time, measured = v[0], v[1], v[2:9]
        elif len(v) == 14:
            query_time, match_time, measured = v[1], v[3], v[4:11]
        else:
            fail(f"{args.loops}:{number}: expected 11 (wicp_rgbd_slam) or 14 (wicp_merge) values, found {len(v)}")
        query, match = (nearest(times, poses, t, args.max_difference) for t in (query_time, match_time))
        if query is None or match is None:
            unmatched += 1
            continue
        try:
            error = np.linalg.inv(np.linalg.inv(match) @ query) @ pose(measured)
        except ValueError as e:
            fail(f"{args.loops}:{number}: {e}")
        metres = float(np.linalg.norm(error[:3, 3]))
        degrees = float(np.degrees(np.arccos(np.clip((np.trace(error[:3, :3]) - 1) / 2, -1.0, 1.0))))
        loops.append((query_time, match_time, metres, degrees))

    wrong = [l for l in loops if l[2] > args.max_translation or l[3] > args.max_rotation]
    for query_time, match_time, metres, degrees in loops:
        flag = "  WRONG" if (query_time, match_time, metres, degrees) in wrong else ""
        print(f"{query_time:.4f} -> {match_time:.4f}: {100 * metres:.2f} cm, {degrees:.2f} deg{flag}")
    summary = {
        "loops": len(loops),
        "wrong": len(wrong),
        "without_ground_truth": unmatched,
        "median_translation_m": float(np.median([l[2] for l in loops])) if loops else None,
        "worst_translation_m": max((l[2] for l in loops), default=None),
        "worst_rotation_deg": max((l[3] for l in loops), default=None),
    }
    print(f"{len(loops)} loop(s) judged, {len(wrong)} wrong (more than {100 * args.max_translation:g} cm or "
          f"{args.max_rotation:g} deg), {unmatched} without ground truth")
    if args.json:
        print(json.dumps(summary))
    return 1 if wrong or unmatched else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Two SLAM sessions of one sequence, merged into one map, and the merge judged against the ground truth.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/merge_sessions.py \\
        [--dataset ../shared/data/tum_fr3_teddy_head] [--first-end 120] [--second-start 80] \\
        [--out merge_sessions.png] [--keep DIR]

Session a runs the RGB-D SLAM over frames 0 to FIRST_END - 1, session b over SECOND_START to the end, each on its
own (its world is its own first camera). Both are saved as session folders (in a temporary folder, or in --keep
DIR), merge_sessions() finds where they overlap (place recognition, verification, the free-space check, one joint
pose graph) and puts b into a's frame. The merged trajectory, every frame once, is then compared with the ground
truth under one rigid alignment: a wrong relative pose between the sessions shows in that error, which each
session aligned on its own would hide.
"""

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
import numpy.typing as npt

import weighted_icp as wi

DEFAULT_DATASET = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "tum_fr3_teddy_head"


def every_frame_once(merge: wi.SessionMerge) -> npt.NDArray[np.float64]:
    """The merged sessions' frames in the first one's frame, a frame two sessions share taken from the earlier."""
    rows: list[npt.NDArray[np.float64]] = []
    seen: set[float] = set()
    for session in merge.sessions:
        if session.trajectory is None:
            continue
        fresh = [row for row in session.trajectory if float(row[0]) not in seen]
        seen.update(float(row[0]) for row in fresh)
        rows.extend(fresh)
    return np.array(sorted(rows, key=lambda row: float(row[0])))


def plot(merge: wi.SessionMerge, truth: npt.NDArray[np.float64], alignment: npt.NDArray[np.float64],
         out: str) -> None:
    """Top view (the ground truth's x and y) of each session's path moved by the ATE alignment, and the truth."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("warning: matplotlib is not installed (Debian: python3-matplotlib); no plot", file=sys.stderr)
        return
    figure, panel = plt.subplots(figsize=(8, 7), constrained_layout=True)
    panel.plot(truth[:, 1], truth[:, 2], color="0.6", linestyle="--", linewidth=1, label="ground truth")
    for index, session in enumerate(merge.sessions):
        if session.trajectory is None:
            continue
        xyz = session.trajectory[:, 1:4] @ alignment[:3, :3].T + alignment[:3, 3]
        panel.plot(xyz[:, 0], xyz[:, 1], linewidth=1.2, label=f"session {index} in session 0's frame")
        panel.scatter(xyz[:1, 0], xyz[:1, 1], s=30)
    panel.set_aspect("equal", adjustable="datalim")
    panel.set(xlabel="x (m)", ylabel="y (m)", title=f"{len(merge.loops)} loops between the sessions")
    panel.legend(loc="best", fontsize="small")
    figure.savefig(out, dpi=100)
    print(f"wrote {out}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--dataset", default=str(DEFAULT_DATASET), help="a TUM RGB-D folder with groundtruth.txt")
    parser.add_argument("--first-end", type=int, default=120, help="session a: frames 0 to this - 1")
    parser.add_argument("--second-start", type=int, default=80, help="session b: frames this to the end")
    parser.add_argument("--keep", help="save the two session folders here (default: a temporary folder)")
    parser.add_argument("--out", default="merge_sessions.png")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(args.keep) if args.keep else Path(scratch)
        try:
            first = wi.run_tum(args.dataset, max_frames=args.first_end)
            first.save_session(folder / "a", overwrite=True)
            wi.run_tum(args.dataset, first_frame=args.second_start).save_session(folder / "b", overwrite=True)
            merge = wi.merge_sessions([folder / "a", folder / "b"])
        except (ValueError, FileNotFoundError, RuntimeError) as error:
            print(f"merge_sessions.py: {error}", file=sys.stderr)
            return 1
    for index, session in enumerate(merge.sessions[1:], start=1):
        print(f"session {index}: {'merged' if session.merged else 'no overlap, left out'}, "
              f"{session.loops_agreeing} agreeing loops of {session.loops_found}, "
              f"{session.free_space_violation * 100:.2f} % of the landmarks in the other's free space")
    if first.ground_truth is None:
        print("no ground truth: nothing to compare with")
        return 0
    merged = every_frame_once(merge)
    ate = wi.ate(first.ground_truth, merged)
    print(f"merged trajectory: {len(merged)} frames, ATE RMSE {ate.rmse * 100:.2f} cm "
          f"(one rigid alignment for both sessions)")
    plot(merge, first.ground_truth, ate.alignment, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

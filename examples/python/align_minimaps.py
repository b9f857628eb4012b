#!/usr/bin/python3
"""Aligns two mini-maps with every weight strategy and plots them before and after.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/align_minimaps.py \\
        [SOURCE.txt TARGET.txt | --map ../shared/data/map_fr1_desk.txt] [--out align_minimaps.png]

With two map files (e.g. wicp_rgbd_slam's minimaps/minimap_000.txt and _001.txt) they are aligned as they
are. With --map (the default: the shared data set's real map) the map's first mini-map of
--frames-per-minimap frames is split into its alternate landmarks (two disjoint clouds of one scene, whose
true relation is the identity: consecutive mini-maps of one session may share little of the scene), and the
source is displaced by --displace, so the error of each strategy against the known motion can be printed.
"""

import argparse
import sys
from pathlib import Path
from typing import List, Optional, Tuple

import numpy as np
import numpy.typing as npt

import weighted_icp as wi

DEFAULT_MAP = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "map_fr1_desk.txt"


def motion(x: float, y: float, yaw_deg: float) -> npt.NDArray[np.float64]:
    """A rigid motion: yaw about z, then a translation in x and y."""
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:2, 3] = [x, y]
    return m


def errors(found: npt.NDArray[np.float64], truth: npt.NDArray[np.float64]) -> Tuple[float, float]:
    """Rotation (degrees) and translation (metres) of found^-1 * truth."""
    residual = np.linalg.inv(found) @ truth
    angle = np.degrees(np.arccos(np.clip((np.trace(residual[:3, :3]) - 1.0) / 2.0, -1.0, 1.0)))
    return float(angle), float(np.linalg.norm(residual[:3, 3]))


def load_pair(args: argparse.Namespace) -> Tuple[wi.LandmarkMap, wi.LandmarkMap, Optional[npt.NDArray[np.float64]]]:
    """The two mini-maps and, when the source was displaced here, the motion that undoes it."""
    if args.maps:
        return (wi.LandmarkMap.load(args.maps[0], min_observations=args.min_observations),
                wi.LandmarkMap.load(args.maps[1], min_observations=args.min_observations), None)
    session = wi.LandmarkMap.load(args.map)
    first = session.split_into_mini_maps(args.frames_per_minimap)[0].with_min_observations(args.min_observations)
    source, target = first.alternate_halves()
    displacement = motion(*args.displace)
    source.transform(displacement)
    return source, target, np.linalg.inv(displacement)


def plot(source: wi.LandmarkMap, target: wi.LandmarkMap, results: List[Tuple[str, wi.AlignmentResult]],
         out: str) -> None:
    """Top views: before, then after each strategy, the target coloured by that strategy's weights."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("warning: matplotlib is not installed (Debian: python3-matplotlib); no plot", file=sys.stderr)
        return
    xyz = source.positions
    # Panels as tall as the maps' top view is (equal axes), so the figure has no empty bands above and below.
    both = np.vstack([xyz[:, :2], target.positions[:, :2]])
    extent = np.ptp(both, axis=0)
    height = float(np.clip(4.2 * extent[1] / max(extent[0], 1e-9), 2.0, 8.0)) + 1.2
    figure, panels = plt.subplots(1, len(results) + 1, figsize=(4.2 * (len(results) + 1), height),
                                  sharex=True, sharey=True, constrained_layout=True)
    panels[0].scatter(target.positions[:, 0], target.positions[:, 1], s=3, c="0.6", label="target")
    panels[0].scatter(xyz[:, 0], xyz[:, 1], s=3, c="#d62728", label="source")
    panels[0].set_title("before")
    panels[0].legend(loc="best", fontsize="small")
    for panel, (strategy, result) in zip(panels[1:], results):
        moved = xyz @ result.transformation[:3, :3].T + result.transformation[:3, 3]
        weighted = panel.scatter(target.positions[:, 0], target.positions[:, 1], s=3,
                                 c=wi.weights(target, strategy), cmap="viridis")
        panel.scatter(moved[:, 0], moved[:, 1], s=3, c="#d62728")
        figure.colorbar(weighted, ax=panel, location="bottom", shrink=0.8, label=f"target weight ({strategy})")
        panel.set_title(f"after: {strategy} ({result.iterations} it.)")
    for panel in panels:
        panel.set_aspect("equal", adjustable="box")  # shared axes: the box adapts, not the limits
        panel.set_xlabel("x (m)")
    panels[0].set_ylabel("y (m)")
    figure.savefig(out, dpi=100, bbox_inches="tight")
    print(f"wrote {out}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("maps", nargs="*", help="SOURCE.txt TARGET.txt (two mini-maps)")
    parser.add_argument("--map", default=str(DEFAULT_MAP), help="a session map to cut into mini-maps")
    parser.add_argument("--frames-per-minimap", type=int, default=80)
    parser.add_argument("--min-observations", type=int, default=2)
    parser.add_argument("--displace", type=float, nargs=3, default=[0.1, -0.05, 5.0], metavar=("X", "Y", "YAW"),
                        help="move the source first (metres, metres, degrees)")
    parser.add_argument("--k", type=int, default=5)
    parser.add_argument("--out", default="align_minimaps.png")
    args = parser.parse_args()
    if args.maps and len(args.maps) != 2:
        parser.error("give two map files, or none")
    try:
        source, target, truth = load_pair(args)
    except (ValueError, FileNotFoundError) as error:
        print(f"align_minimaps.py: {error}", file=sys.stderr)
        return 1
    print(f"source {len(source)} landmarks, target {len(target)} landmarks")
    results = []
    for strategy in wi.strategies():
        result = wi.align(source, target, strategy=strategy, k=args.k)
        results.append((strategy, result))
        line = (f"{strategy:>14}: converged {result.converged}, {result.iterations:3d} iterations, "
                f"fitness {result.fitness_score:.6f}, {result.time_ms:.1f} ms")
        if truth is not None:
            rotation, translation = errors(result.transformation, truth)
            line += f", error {rotation:.3f} deg {translation * 100:.2f} cm"
        print(line)
    plot(source, target, results, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

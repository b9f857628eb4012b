#!/usr/bin/python3
"""The command-line tools' pictures, from the tables they write (examples/common/plotting.cpp):

    plot_results.py trajectory --data DIR --out trajectory.png [--title T]
        DIR/groundtruth.csv (t,x,y,z) and DIR/pairs.csv (t,gt_x..gt_z,est_x..est_z,error): the estimate
        (already aligned onto the ground truth) against it, as evo and the TUM tools draw them: top view
        coloured by the error, x / y / z against time, and the error along the trajectory.
    plot_results.py alignment --data DIR --out alignment.png [--title T]
        DIR/source.csv (x,y,z,aligned_x,aligned_y,aligned_z) and DIR/target.csv (x,y,z,weight): the two
        landmark clouds before and after alignment, top view, the target coloured by weight.
    plot_results.py paths --data DIR --out paths.png [--title T]
        DIR/paths.csv (path,t,x,y,z: camera paths in one frame, one run's or each merged session's), DIR/names.txt
        (one legend label per path) and DIR/loops.csv (qx,qy,qz,mx,my,mz,used: the loops, their two keyframes'
        positions): the paths seen along the direction they vary least ("from above" whatever the frame) and
        from the side, loops as segments (dotted: refused by the pose graph).

Exit status: 0 written, 1 bad input, 3 matplotlib is not installed (the tools turn that into a warning).
"""

import argparse
import csv
import os
import sys

NO_MATPLOTLIB = 3


def load(path):
    """A CSV of numbers as a dict of column name -> list of floats."""
    try:
        with open(path, newline="") as handle:
            rows = list(csv.DictReader(handle))
    except OSError as error:
        sys.exit(f"plot_results.py: {path}: {error.strerror}")
    if not rows:
        return {}
    return {name: [float(row[name]) for row in rows] for name in rows[0]}


def trajectory_figure(plt, data, title):
    """Top view, per-axis against time and the error along the trajectory."""
    truth = load(os.path.join(data, "groundtruth.csv"))
    pairs = load(os.path.join(data, "pairs.csv"))
    if not pairs:
        sys.exit("plot_results.py: no estimated pose pairs with the ground truth; nothing to draw")
    figure = plt.figure(figsize=(15, 7.5), constrained_layout=True)
    grid = figure.add_gridspec(3, 3)
    top = figure.add_subplot(grid[:, 0])
    top.plot(truth["x"], truth["y"], color="0.5", linestyle="--", linewidth=1, label="ground truth")
    points = top.scatter(pairs["est_x"], pairs["est_y"], c=pairs["error"], cmap="viridis", s=8,
                         label="estimate (aligned)")
    figure.colorbar(points, ax=top, label="position error (m)", shrink=0.7)
    top.set_aspect("equal", adjustable="datalim")
    top.set(xlabel="x (m)", ylabel="y (m)", title="top view")
    top.legend(loc="best", fontsize="small")
    start = pairs["t"][0]
    seconds = [t - start for t in pairs["t"]]
    truth_seconds = [t - start for t in truth["t"]]
    for row, axis in enumerate("xyz"):
        panel = figure.add_subplot(grid[row, 1])
        panel.plot(truth_seconds, truth[axis], color="0.5", linestyle="--", linewidth=1, label="ground truth")
        panel.plot(seconds, pairs["est_" + axis], color="#1f77b4", linewidth=1, label="estimate")
        panel.set_ylabel(f"{axis} (m)")
        panel.set_xlim(min(seconds), max(seconds))
        if row == 0:
            panel.set_title("position against time")
            panel.legend(loc="best", fontsize="small")
        if row == 2:
            panel.set_xlabel("time (s)")
    error = figure.add_subplot(grid[:, 2])
    error.plot(seconds, pairs["error"], color="#d62728", linewidth=1)
    rmse = (sum(e * e for e in pairs["error"]) / len(pairs["error"])) ** 0.5
    error.axhline(rmse, color="k", linestyle=":", label=f"RMSE {rmse * 100:.2f} cm")
    error.set(xlabel="time (s)", ylabel="position error (m)", title="ATE along the trajectory")
    error.legend(loc="best", fontsize="small")
    figure.suptitle(title)
    return figure


def alignment_figure(plt, data, title):
    """The two clouds, top view, before and after: target coloured by weight, source in red."""
    source = load(os.path.join(data, "source.csv"))
    target = load(os.path.join(data, "target.csv"))
    if not source or not target:
        sys.exit("plot_results.py: an empty cloud; nothing to draw")
    figure, panels = plt.subplots(1, 2, figsize=(14, 6.5), sharex=True, sharey=True, constrained_layout=True)
    for panel, (prefix, label) in zip(panels, [("", "before"), ("aligned_", "after")]):
        cloud = panel.scatter(target["x"], target["y"], c=target["weight"], cmap="viridis", s=6,
                              label="target (colour: weight)")
        panel.scatter(source[prefix + "x"], source[prefix + "y"], s=6, facecolors="none", edgecolors="#d62728",
                      linewidths=0.6, label="source")
        panel.set_aspect("equal", adjustable="box")  # shared axes: the box adapts, not the limits
        panel.set(xlabel="x (m)", ylabel="y (m)", title=f"{label} alignment (top view)")
        panel.legend(loc="best", fontsize="small")
    figure.colorbar(cloud, ax=panels, label="target weight", shrink=0.7)
    figure.suptitle(title)
    return figure


def principal_axes(points):
    """The unit axes along which `points` (rows of x, y, z) vary most, next and least (numpy, which matplotlib
    needs anyway)."""
    import numpy
    if len(points) < 3:  # too few to tell: the frame's own axes
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    _, vectors = numpy.linalg.eigh(numpy.cov(numpy.asarray(points, dtype=float).T))
    return [list(vectors[:, k]) for k in (2, 1, 0)]


def paths_figure(plt, data, title):
    """Camera paths from above and from the side, loops as segments."""
    paths = load(os.path.join(data, "paths.csv"))
    loops = load(os.path.join(data, "loops.csv"))
    try:
        with open(os.path.join(data, "names.txt")) as handle:
            names = [line.rstrip("\n") for line in handle]
    except OSError as error:
        sys.exit(f"plot_results.py: names.txt: {error.strerror}")
    if not paths:
        sys.exit("plot_results.py: no path has a pose; nothing to draw")
    points = list(zip(paths["x"], paths["y"], paths["z"]))
    axes = principal_axes(points)

    def project(x, y, z, a, b):
        p = (x, y, z)
        return (sum(p[i] * axes[a][i] for i in range(3)), sum(p[i] * axes[b][i] for i in range(3)))

    figure, panels = plt.subplots(1, 2, figsize=(15, 7), constrained_layout=True)
    views = [(0, 1, "from above (the plane the paths span most)"), (0, 2, "from the side")]
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for panel, (a, b, label) in zip(panels, views):
        for s, name in enumerate(names):
            rows = [k for k, path in enumerate(paths["path"]) if int(path) == s]
            if not rows:
                continue
            xy = [project(paths["x"][k], paths["y"][k], paths["z"][k], a, b) for k in rows]
            colour = colours[s % len(colours)]
            panel.plot([p[0] for p in xy], [p[1] for p in xy], color=colour, linewidth=1.2, label=name)
            panel.scatter([xy[0][0]], [xy[0][1]], color=colour, marker="o", s=30)
        for k in range(len(loops.get("used", []))):
            q = project(loops["qx"][k], loops["qy"][k], loops["qz"][k], a, b)
            m = project(loops["mx"][k], loops["my"][k], loops["mz"][k], a, b)
            used = loops["used"][k] > 0.5
            colour = "k" if used else "#d62728"
            # A right loop joins two keyframes at one place: its segment is short, so its ends are marked too.
            panel.plot([q[0], m[0]], [q[1], m[1]], color=colour, linewidth=0.8, linestyle="-" if used else ":",
                       marker="x", markersize=4, alpha=0.7)
        panel.set_aspect("equal", adjustable="datalim")
        panel.set(xlabel="principal axis 1 (m)", ylabel=f"principal axis {b + 1} (m)", title=label)
    used = sum(1 for u in loops.get("used", []) if u > 0.5)
    panels[0].plot([], [], color="k", linewidth=0.8, marker="x", markersize=4,
                   label=f"loops ({used})")
    if used < len(loops.get("used", [])):
        panels[0].plot([], [], color="#d62728", linewidth=0.8, linestyle=":", marker="x", markersize=4,
                       label=f"refused by the pose graph ({len(loops['used']) - used})")
    panels[0].legend(loc="best", fontsize="small")
    figure.suptitle(title + "  (o: a path's first frame)")
    return figure


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("kind", choices=["trajectory", "alignment", "paths"])
    parser.add_argument("--data", required=True, help="folder with the tables")
    parser.add_argument("--out", required=True, help="the PNG to write")
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    try:
        import matplotlib
        matplotlib.use("Agg")  # no display needed
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"plot_results.py: matplotlib is not installed for {sys.executable} (Debian: python3-matplotlib)",
              file=sys.stderr)
        return NO_MATPLOTLIB
    draw = {"trajectory": trajectory_figure, "alignment": alignment_figure, "paths": paths_figure}[args.kind]
    figure = draw(plt, args.data, args.title)
    figure.savefig(args.out, dpi=110, format="png")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""Violin plots of a wicp_sweep_* results.csv, in the manner of the paper's
figures: one panel per metric, violins grouped by the swept variable, one
colour per weight strategy.

    /usr/bin/python3 scripts/plot_sweep.py DIR/results.csv [--out DIR/violin.png]

The title names the maps and settings from run.json beside the CSV when it
is there. Exits non-zero, saying why, on a missing or malformed CSV.
summarize_sweep.py reads results through load_results() and group_of().
"""

import argparse
import csv
import io
import json
import os
import sys

STRATEGIES = ["base", "covariance", "observations", "mean-distance"]
COLOURS = {"base": "#7f7f7f", "covariance": "#1f77b4", "observations": "#2ca02c", "mean-distance": "#d62728"}
REQUIRED_COLUMNS = ["sweep", "strategy", "k", "x", "y", "z", "roll", "pitch", "yaw", "fitness_score",
                    "iterations", "refine_iterations", "converged", "time_ms", "rotation_error_deg",
                    "translation_error_m"]
SWEEP_TITLES = {"k": "Neighbourhood size (k) sweep", "yaw": "Yaw sweep", "xy": "XY offset sweep",
                "xy_yaw": "XY offset plus yaw sweep"}
GROUP_AXES = {"k": "k (neighbours; base is plain ICP, k = 1)",
              "yaw": "yaw of the displacement (deg), both directions",
              "xy": "XY offset of the displacement (m), four quadrants",
              "xy_yaw": "yaw of the displacement (deg), quadrants (±0.5 m, ±0.5 m)"}


def group_of(sweep, row):
    """The swept value a row belongs to, as (sort key, label)."""
    if sweep == "k":
        return int(row["k"]), row["k"]
    if sweep == "yaw":  # both directions of one angle form a group
        yaw = abs(float(row["yaw"]))
        return yaw, f"±{yaw:g}" if yaw else "0"
    if sweep == "xy":  # the four quadrants of one magnitude form a group
        a, b = abs(float(row["x"])), abs(float(row["y"]))
        return (a, b), f"±{a:g}, ±{b:g}"
    if sweep == "xy_yaw":  # the four quadrants at one yaw form a group
        yaw = float(row["yaw"])
        return yaw, f"{yaw:+g}"
    raise ValueError(f"unknown sweep '{sweep}'")


def load_results(path):
    """(sweep name, rows as dicts); raises ValueError naming the file."""
    try:
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            missing = [c for c in REQUIRED_COLUMNS if c not in (reader.fieldnames or [])]
            if missing:
                raise ValueError(f"{path}: not a sweep results file (missing columns: {', '.join(missing)})")
            rows = list(reader)
    except OSError as e:
        raise ValueError(f"cannot read {path}: {e.strerror}") from e
    if not rows:
        raise ValueError(f"{path}: no result rows")
    sweeps = {r["sweep"] for r in rows}
    if len(sweeps) != 1:
        raise ValueError(f"{path}: expected one sweep, found {', '.join(sorted(sweeps))}")
    sweep = sweeps.pop()
    unknown = {r["strategy"] for r in rows} - set(STRATEGIES)
    if unknown:
        raise ValueError(f"{path}: unknown strategies {', '.join(sorted(unknown))}")
    for line, row in enumerate(rows, start=2):
        try:
            group_of(sweep, row)
            for column in ("fitness_score", "iterations", "refine_iterations"):
                float(row[column])
            for column in ("rotation_error_deg", "translation_error_m"):
                if row[column]:
                    float(row[column])
        except ValueError as e:
            raise ValueError(f"{path}:{line}: {e}") from e
    return sweep, rows


def run_info(csv_path):
    """run.json written beside the CSV by the sweep tool, or {}."""
    path = os.path.join(os.path.dirname(os.path.abspath(csv_path)), "run.json")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def title(sweep, info):
    text = SWEEP_TITLES[sweep]
    if "maps" in info:
        settings = [f"k = {info['k']}"] if "k" in info else []
        settings.append("with refinement" if info.get("refine") else "no refinement")
        text += f"\n{info['maps']} ({', '.join(settings)})"
    return text


def panels(rows):
    """(column, axis label, log scale) for each metric the rows have."""
    out = [("fitness_score", "fitness score (m²)", True)]
    for column, label in (("rotation_error_deg", "rotation error (deg)"),
                          ("translation_error_m", "translation error (m)")):
        if any(r[column] for r in rows):
            out.append((column, label, False))
    out.append(("iterations", "iterations", False))
    if any(int(r["refine_iterations"]) for r in rows):
        out.append(("refine_iterations", "refinement iterations", False))
    return out


def plot(csv_path, png_path):
    import matplotlib  # here, so summarize_sweep.py works without matplotlib

    matplotlib.use("Agg")  # files only; no display needed
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.patches import Patch
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    from PIL import Image

    sweep, rows = load_results(csv_path)
    groups = sorted({group_of(sweep, r) for r in rows})
    position = {key: i for i, (key, _) in enumerate(groups)}
    strategies = [s for s in STRATEGIES if any(r["strategy"] == s for r in rows)]
    width = 0.8 / len(strategies)
    metrics = panels(rows)

    header = 0.3  # inches above the panels for the title and the legend
    height = 2.2 * len(metrics) + 0.6 + header
    fig, axes = plt.subplots(len(metrics), 1, figsize=(10, height), sharex=True, squeeze=False)
    for ax, (column, label, log) in zip(axes[:, 0], metrics):
        for s_index, strategy in enumerate(strategies):
            for key, _ in groups:
                values = np.array([float(r[column]) for r in rows
                                   if r["strategy"] == strategy and group_of(sweep, r)[0] == key and r[column]])
                if values.size == 0:
                    continue
                x = position[key] + (s_index - (len(strategies) - 1) / 2) * width
                # The density of log values on a log axis: a linear density would be distorted.
                shown = np.log10(np.maximum(values, 1e-300)) if log else values
                # A density needs spread; single or identical values are shown as points only.
                if values.size > 1 and np.ptp(shown) > 1e-9 * max(1.0, np.abs(shown).max()):
                    body = ax.violinplot(shown, positions=[x], widths=width * 0.95, showextrema=False)["bodies"][0]
                    if log:
                        vertices = body.get_paths()[0].vertices
                        vertices[:, 1] = 10.0 ** vertices[:, 1]
                    body.set_facecolor(COLOURS[strategy])
                    body.set_edgecolor(COLOURS[strategy])
                    body.set_alpha(0.45)
                    ax.hlines(np.median(values), x - width * 0.35, x + width * 0.35, color="black", lw=1.2)
                ax.scatter(np.full(values.size, x), values, s=9, color=COLOURS[strategy], edgecolor="black",
                           linewidth=0.4, zorder=3)
        if log:
            ax.set_yscale("log")
            # 1-2-5 labels: a single decade would otherwise get cluttered minor labels.
            ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0), numticks=8))
            ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:.3g}"))
            ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_ylabel(label)
        ax.grid(axis="y", alpha=0.3)
        for boundary in range(1, len(groups)):
            ax.axvline(boundary - 0.5, color="0.85", lw=0.8)
    bottom = axes[-1, 0]
    bottom.set_xticks(range(len(groups)))
    bottom.set_xticklabels([label for _, label in groups])
    bottom.set_xlim(-0.5, len(groups) - 0.5)
    bottom.set_xlabel(GROUP_AXES[sweep])
    fig.suptitle(title(sweep, run_info(csv_path)), y=1 - 0.05 / height, va="top", fontsize=11)
    fig.legend(handles=[Patch(facecolor=COLOURS[s], alpha=0.6, label=s) for s in strategies],
               loc="upper center", ncol=len(strategies), frameon=False, bbox_to_anchor=(0.5, 1 - 0.45 / height))
    fig.tight_layout(rect=(0, 0, 1, 1 - header / height))
    # A 256-colour palette keeps the PNG about a third of the RGBA size with no visible change.
    buffer = io.BytesIO()
    fig.savefig(buffer, dpi=150, format="png")
    plt.close(fig)
    buffer.seek(0)
    image = Image.open(buffer).convert("RGB").quantize(colors=256)
    directory = os.path.dirname(os.path.abspath(png_path))
    temporary = os.path.join(directory, f".{os.path.basename(png_path)}.tmp.png")
    try:  # written beside and renamed, so a failure never leaves half a PNG
        image.save(temporary, format="PNG", optimize=True, dpi=(150, 150))
        os.replace(temporary, png_path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("csv", help="results.csv of a wicp_sweep_* tool")
    parser.add_argument("--out", help="PNG to write (default: violin.png beside the CSV)")
    args = parser.parse_args()
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(args.csv)), "violin.png")
    try:
        plot(args.csv, out)
    except (ValueError, OSError, ImportError) as e:
        print(f"plot_sweep.py: error: {e}", file=sys.stderr)
        return 1
    print(f"plot_sweep.py: wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

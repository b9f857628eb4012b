#!/usr/bin/python3
"""The front-end ablation of issue #11: wicp_rgbd_slam on every sequence of the cross-sequence set
(fr1 head, fr3 head, the synthetic sequence, and their variants made by wicp_make_variant) once per
option set, and a Markdown table (sequence x option set: ATE RMSE, frames not tracked (each keeps the motion
model's predicted pose), the frame-to-frame RPE, median and 90th-percentile tracking time per frame).

Option sets are wicp_rgbd_slam command-line flags passed through unchanged, so any option the tool
has (today's and future ones) slots in without changing this script:

    /usr/bin/python3 scripts/run_ablation.py --scratch /tmp/ablation --out /tmp/ablation/table.md \
        --set default= --set dense-prior="--dense-odometry prior" --set pnp-iterative="--pnp iterative"

Without --set, every option of wicp_rgbd_slam's ablation groups is switched on its own against the default.
A variant joins wicp_make_variant kinds with "+" ("there-and-back+kinect": a revisit in the held-out Kinect's
format; "kinect" = jpeg,mm-depth,focal). Variants are written into --scratch (refused inside the source
tree); the table is written atomically (temporary file, then rename) after every row and printed.
After the table comes a summary, one line per option set against the first (the default): the geometric
mean of the ATE and RPE ratios over the rows both ran, how many rows it lowers or raises by more than
0.02 cm, its largest rise, the frames it left untracked and its tracking time against the default's.
Exit 1 when a tool cannot be found or a variant cannot be made, 2 on a bad command line. A run that fails
shows as "failed" in its cell (its stderr is kept in --scratch/logs/).
"""

import argparse
import json
import math
import os
import shlex
import subprocess
import sys
from pathlib import Path

SOURCE_DIR = Path(__file__).resolve().parent.parent

# Every choice of wicp_rgbd_slam's ablation groups that is not the default, each on its own.
DEFAULT_SETS = [
    ("default", ""),
    ("dense-off", "--dense-odometry off"),
    ("dense-prior+fallback", "--dense-odometry prior+fallback"),
    ("dense-kind-rgbd", "--dense-odometry-kind rgbd"),
    ("gate-paper", "--quality-gate paper"),
    ("gate-brisque", "--quality-measure brisque"),
    ("no-gate", "--no-quality-gate"),
    ("equalization-global", "--equalization global"),
    ("equalization-none", "--equalization none"),
    ("describe-equalized", "--describe equalized"),
    ("feature-smoothing-1", "--feature-smoothing 1"),
    ("feature-width-full", "--feature-width full"),
    ("matcher-kd-tree", "--matcher kd-tree"),
    ("matcher-brute-force", "--matcher brute-force"),
    ("matcher-flann", "--matcher flann"),
    ("region-projection", "--match-region projection"),
    ("region-homography", "--match-region homography"),
    ("modified-brief", "--descriptor modified-brief"),
    ("dynamic-epipolar", "--dynamic-distance epipolar-history"),
    ("dynamic-both", "--dynamic-distance both"),
    ("pnp-iterative", "--pnp iterative"),
    ("pnp-candidate", "--pnp-prediction candidate"),
    ("pnp-frame-thresholds", "--pnp-thresholds frame"),
    ("gate-free-retry-off", "--gate-free-retry off"),
    ("motion-period", "--motion-timing period"),
    ("no-keyframe-before-loss", "--keyframe-before-loss off"),
]
# "kinect" is the held-out Kinect's format, as in wicp_benchmark_cross_sequence.
VARIANT_KINDS = {"kinect": "jpeg,mm-depth,focal"}
SAME_CM = 0.02  # ATE differences (cm) up to this count as none in the summary: below what one LSH draw moves
TUM_FOLDERS = {"fr1_head": "tum_fr1_xyz_head", "fr3_head": "tum_fr3_teddy_head"}


def parse_arguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scratch", required=True, help="folder for variants, runs and logs (outside the source tree)")
    parser.add_argument("--out", help="Markdown table to write (default: SCRATCH/ablation.md)")
    parser.add_argument("--build", default=str(SOURCE_DIR / "build"), help="build folder with examples/wicp_*")
    parser.add_argument("--data", default=str(SOURCE_DIR.parent / "shared" / "data"),
                        help="folder with tum_fr1_xyz_head and tum_fr3_teddy_head")
    parser.add_argument("--sequences", default="fr1_head,fr3_head,synthetic", help="comma-separated")
    parser.add_argument("--variants", default="original,jpeg,mm-depth,focal,unregistered,blur,low-light,burst,kinect",
                        help="comma-separated: original, or wicp_make_variant kinds (kinect = jpeg,mm-depth,focal) "
                             "joined by +")
    parser.add_argument("--max-frames", type=int, default=0, help="frames per TUM sequence (0 = all)")
    parser.add_argument("--synthetic-frames", type=int, default=40, help="synthetic sequence length")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=FLAGS",
                        help="an option set: a column name and the wicp_rgbd_slam flags it adds (repeatable)")
    parser.add_argument("--common", default="--deterministic",
                        help="flags added to every run (default --deterministic: reproducible ATE; bundle "
                             "adjustment then runs inside tracking, so keyframes' times include it)")
    arguments = parser.parse_args()
    if arguments.max_frames < 0 or arguments.synthetic_frames < 1:
        parser.error("--max-frames must be at least 0 and --synthetic-frames at least 1")
    sets = []
    for text in arguments.set:
        name, sep, flags = text.partition("=")
        if not sep or not name:
            parser.error(f"--set {text!r}: expected NAME=FLAGS (FLAGS may be empty)")
        sets.append((name, flags))
    arguments.sets = sets or DEFAULT_SETS
    if len({name for name, _ in arguments.sets}) != len(arguments.sets):
        parser.error("--set names must be unique")
    scratch = Path(arguments.scratch).resolve()
    if scratch == SOURCE_DIR or SOURCE_DIR in scratch.parents:
        parser.error(f"--scratch {scratch} is inside the source tree {SOURCE_DIR}")
    arguments.scratch = scratch
    return arguments


def tool(build, name):
    path = Path(build) / "examples" / name
    if not path.is_file():
        raise RuntimeError(f"{path} not found: build it first (ninja -C {build} {name})")
    return str(path)


def make_variant(arguments, sequence, variant):
    """The folder (or None: the built-in synthetic sequence) and extra flags for one row."""
    if variant == "original":
        if sequence == "synthetic":
            return None, ["--synthetic-frames", str(arguments.synthetic_frames)]
        return str(Path(arguments.data) / TUM_FOLDERS[sequence]), []
    folder = arguments.scratch / "variants" / f"{sequence}_{variant}"
    kinds = ",".join(VARIANT_KINDS.get(kind, kind) for kind in variant.split("+"))
    command = [tool(arguments.build, "wicp_make_variant"), "--variant", kinds,
               "--out", str(folder), "--overwrite"]
    if sequence == "synthetic":
        command += ["--synthetic-frames", str(arguments.synthetic_frames)]
    else:
        command += ["--dataset", str(Path(arguments.data) / TUM_FOLDERS[sequence])]
    made = subprocess.run(command, capture_output=True, text=True)
    if made.returncode != 0:
        raise RuntimeError(f"wicp_make_variant failed for {sequence}, {variant}: {made.stderr.strip()}")
    return str(folder), []


def run_slam(arguments, folder, extra, flags, log_name):
    """report.json of one wicp_rgbd_slam run, or None when it failed."""
    out = arguments.scratch / "runs" / log_name
    command = [tool(arguments.build, "wicp_rgbd_slam"), "--out", str(out), "--overwrite"] + extra
    if folder:
        command += ["--dataset", folder]
    if arguments.max_frames and folder:
        command += ["--max-frames", str(arguments.max_frames)]
    command += shlex.split(arguments.common) + shlex.split(flags)
    done = subprocess.run(command, capture_output=True, text=True)
    logs = arguments.scratch / "logs"
    logs.mkdir(parents=True, exist_ok=True)
    (logs / f"{log_name}.txt").write_text(" ".join(shlex.quote(c) for c in command) + "\n" + done.stdout + done.stderr)
    if done.returncode == 2:  # a bad command line: every run of this set would fail alike
        raise RuntimeError(f"wicp_rgbd_slam refused the flags {flags!r}: {done.stderr.strip()}")
    if done.returncode != 0:
        return None
    with open(out / "report.json") as report:
        return json.load(report)


def cell(report):
    if report is None:
        return "failed"
    ate = report.get("ate_rmse_m")
    ate_text = f"{ate * 100:.2f}" if ate is not None else "–"
    # Frame to frame: one wrong step long ago moves the ATE of every later frame, not this.
    rpe = report.get("rpe_frame_translation_rmse_m")
    rpe_text = f"{rpe * 1000:.1f}" if rpe is not None else "–"
    missing = report["frames"] - report["tracked_frames"]
    text = (f"{ate_text} ({missing}) · {rpe_text} · {report['median_ms_per_frame']:.0f} / "
            f"{report['p90_ms_per_frame']:.0f}")
    if report.get("dense_fallback_frames", 0) > 0:
        text += f" [{report['dense_fallback_frames']} dense]"
    if report.get("loops_accepted", 0) > 0:
        text += f" [{report['loops_accepted']} loops]"
    return text


def geometric_mean(ratios):
    return math.exp(sum(math.log(r) for r in ratios) / len(ratios)) if ratios else None


def summary_line(name, reports, baseline):
    """One option set against the baseline set over the rows both ran: what it gains and what it costs."""
    ate_ratios, rpe_ratios, lower, higher, worst = [], [], 0, 0, None
    untracked = failed = 0
    time_ratios = []
    for row, report in reports.items():
        base = baseline.get(row)
        if report is None:
            failed += 1
            continue
        untracked += report["frames"] - report["tracked_frames"]
        if base is None:
            continue
        if base["median_ms_per_frame"] > 0:
            time_ratios.append(report["median_ms_per_frame"] / base["median_ms_per_frame"])
        ate, base_ate = report.get("ate_rmse_m"), base.get("ate_rmse_m")
        if ate and base_ate:
            ate_ratios.append(ate / base_ate)
            change = (ate - base_ate) * 100
            lower += change < -SAME_CM
            higher += change > SAME_CM
            if worst is None or change > worst[0]:
                worst = (change, row, base_ate * 100, ate * 100)
        rpe, base_rpe = report.get("rpe_frame_translation_rmse_m"), base.get("rpe_frame_translation_rmse_m")
        if rpe and base_rpe:
            rpe_ratios.append(rpe / base_rpe)

    def ratio(value):
        return f"{value:.3f}" if value is not None else "–"

    worst_text = f"{worst[1]} {worst[2]:.2f} → {worst[3]:.2f}" if worst and worst[0] > SAME_CM else "none"
    return (f"| {name} | {ratio(geometric_mean(ate_ratios))} | {lower} / {higher} | {worst_text} | "
            f"{ratio(geometric_mean(rpe_ratios))} | {untracked} | {ratio(geometric_mean(time_ratios))} | {failed} |")


def summary(names, reports_by_set):
    """The summary table: every option set against the first."""
    baseline = reports_by_set[names[0]]
    lines = [
        "",
        f"Against {names[0]} over the rows both ran (geometric means of the ratios; a row counts as lower or "
        f"higher when its ATE moves by more than {SAME_CM} cm):",
        "",
        "| option set | ATE ratio | rows lower / higher | largest rise (cm) | RPE ratio | frames not tracked | "
        "median time ratio | failed runs |",
        "|---|---|---|---|---|---|---|---|",
    ]
    return lines + [summary_line(name, reports_by_set[name], baseline) for name in names]


def write_atomically(path, text):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.tmp{os.getpid()}")
    temporary.write_text(text)
    os.replace(temporary, path)


def table_header(arguments, names):
    return [
        "ATE RMSE cm (frames not tracked, posed by prediction) · frame-to-frame RPE mm · median / p90 tracking ms "
        "per frame [frames the dense fallback posed] [loops accepted]",
        f"(wicp_rgbd_slam {arguments.common}; each column adds its flags)",
        "",
        "| sequence | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]


def run_row(arguments, sequence, variant):
    """The row's name and one report (or None) per option set, each run's result told on stderr as it ends."""
    folder, extra = make_variant(arguments, sequence, variant)
    row = sequence + ("" if variant == "original" else ", " + variant)
    reports = []
    for name, flags in arguments.sets:
        reports.append(run_slam(arguments, folder, extra, flags, f"{sequence}_{variant}_{name}"))
        print(f"  {row} · {name}: {cell(reports[-1])}", file=sys.stderr, flush=True)
    return row, reports


def main():
    arguments = parse_arguments()
    arguments.scratch.mkdir(parents=True, exist_ok=True)
    out = arguments.out or arguments.scratch / "ablation.md"
    names = [name for name, _ in arguments.sets]
    reports_by_set = {name: {} for name in names}
    lines = table_header(arguments, names)
    for header in lines:
        print(header, flush=True)
    for sequence in arguments.sequences.split(","):
        if sequence != "synthetic" and sequence not in TUM_FOLDERS:
            raise SystemExit(f"run_ablation.py: error: unknown sequence {sequence!r}")
        if sequence != "synthetic" and not (Path(arguments.data) / TUM_FOLDERS[sequence]).is_dir():
            print(f"skipping {sequence}: {Path(arguments.data) / TUM_FOLDERS[sequence]} not found", file=sys.stderr)
            continue
        for variant in arguments.variants.split(","):
            row, reports = run_row(arguments, sequence, variant)
            for name, report in zip(names, reports):
                reports_by_set[name][row] = report
            lines.append(f"| {row} | " + " | ".join(cell(report) for report in reports) + " |")
            print(lines[-1], flush=True)
            write_atomically(out, "\n".join(lines) + "\n")  # the rows so far survive an interrupted run
    summary_lines = summary(names, reports_by_set)
    for line in summary_lines:
        print(line, flush=True)
    write_atomically(out, "\n".join(lines + summary_lines) + "\n")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except RuntimeError as error:
        print(f"run_ablation.py: error: {error}", file=sys.stderr)
        sys.exit(1)

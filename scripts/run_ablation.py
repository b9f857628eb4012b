#!/usr/bin/python3
"""The front-end ablation of issue #11: wicp_rgbd_slam on every sequence of the cross-sequence set
(fr1 head, fr3 head, the synthetic sequence, and their variants made by wicp_make_variant) once per
option set, and a Markdown table (sequence x option set: ATE RMSE, frames not tracked (each keeps the motion
model's predicted pose), the frame-to-frame RPE, median and 90th-percentile tracking time per frame).

Option sets are wicp_rgbd_slam command-line flags passed through unchanged, so any option the tool
has (today's and future ones) slots in without changing this script:

    /usr/bin/python3 scripts/run_ablation.py --scratch /tmp/ablation --out /tmp/ablation/table.md \
        --set default= --set dense-prior="--dense-odometry prior" --set pnp-iterative="--pnp iterative"

Without --set, every option of docs/frontend_ablation.md is switched on its own against the default.
Variants are written into --scratch (refused inside the source tree); the table is written atomically
(temporary file, then rename) and printed. Exit 1 when a tool cannot be found or a variant cannot be
made, 2 on a bad command line. A run that fails shows as "failed" in its cell (its stderr is kept in
--scratch/logs/).
"""

import argparse
import json
import os
import shlex
import subprocess
import sys
from pathlib import Path

SOURCE_DIR = Path(__file__).resolve().parent.parent

DEFAULT_SETS = [
    ("default", ""),
    ("dense-prior", "--dense-odometry prior"),
    ("dense-off", "--dense-odometry off"),
    ("dense-prior+fallback", "--dense-odometry prior+fallback"),
    ("equalization-global", "--equalization global"),
    ("equalization-none", "--equalization none"),
    ("pnp-iterative", "--pnp iterative"),
    ("quality-brisque", "--quality-measure brisque"),
]
# "kinect" is the held-out Kinect's format, as in wicp_benchmark_cross_sequence.
VARIANT_KINDS = {"kinect": "jpeg,mm-depth,focal"}
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
                        help="comma-separated: original, wicp_make_variant kinds, or kinect")
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
    command = [tool(arguments.build, "wicp_make_variant"), "--variant", VARIANT_KINDS.get(variant, variant),
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
    return text


def write_atomically(path, text):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.tmp{os.getpid()}")
    temporary.write_text(text)
    os.replace(temporary, path)


def main():
    arguments = parse_arguments()
    arguments.scratch.mkdir(parents=True, exist_ok=True)
    names = [name for name, _ in arguments.sets]
    lines = [
        "ATE RMSE cm (frames not tracked, posed by prediction) · frame-to-frame RPE mm · median / p90 tracking ms "
        "per frame",
        f"(wicp_rgbd_slam {arguments.common}; each column adds its flags)",
        "",
        "| sequence | " + " | ".join(names) + " |",
        "|---|" + "---|" * len(names),
    ]
    for header in lines:
        print(header, flush=True)
    for sequence in arguments.sequences.split(","):
        if sequence != "synthetic" and sequence not in TUM_FOLDERS:
            raise SystemExit(f"run_ablation.py: error: unknown sequence {sequence!r}")
        if sequence != "synthetic" and not (Path(arguments.data) / TUM_FOLDERS[sequence]).is_dir():
            print(f"skipping {sequence}: {Path(arguments.data) / TUM_FOLDERS[sequence]} not found", file=sys.stderr)
            continue
        for variant in arguments.variants.split(","):
            folder, extra = make_variant(arguments, sequence, variant)
            row = sequence + ("" if variant == "original" else ", " + variant)
            cells = [cell(run_slam(arguments, folder, extra, flags, f"{sequence}_{variant}_{name}"))
                     for name, flags in arguments.sets]
            lines.append(f"| {row} | " + " | ".join(cells) + " |")
            print(lines[-1], flush=True)
    write_atomically(arguments.out or arguments.scratch / "ablation.md", "\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except RuntimeError as error:
        print(f"run_ablation.py: error: {error}", file=sys.stderr)
        sys.exit(1)

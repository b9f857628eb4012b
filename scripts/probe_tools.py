#!/usr/bin/python3
"""Probes every command-line tool with wrong inputs and options and classifies what each run did (issue #10).

Usage (run with /usr/bin/python3, after a build):
    /usr/bin/python3 scripts/probe_tools.py [--build build] [--data ../shared/data] [--scratch DIR]
                                            [--out table.md] [--timeout 120] [--tool NAME ...]

Every case is one run of one tool on inputs made in a scratch folder (never in the repository or ../shared):
missing, empty, binary, truncated or inconsistent files, NaN and huge values, images that are missing, black or
of the wrong size, corrupt sessions and vocabularies, a full disk (RLIMIT_FSIZE, the write refused rather than
the process killed), an existing output folder; and options that are negative, zero, huge, not numbers, unknown
names, missing values or unknown options. Each run is classified:

    refused clearly   exit 1-4 with an error line "<tool>: error: ..." (or wicp_align's reported degenerate
                      problem, exit 4) and no crash
    accepted          exit 0
    crashed           killed by a signal, or a sanitizer / std::terminate report
    hung              still running after --timeout seconds (killed)
    unclear           a non-zero exit without an error line
    partial output    a failed run changed its output folder or left a temporary folder beside it

A case also says what it expects (refused, accepted or either); the table counts outcomes per tool and lists
every case whose outcome is crashed, hung, unclear, partial output or not what it expected. Exit status: 0 when
no such case was found, 1 otherwise, 2 on a usage error.
"""

import argparse
import dataclasses
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable, Dict, List, Optional

REFUSE, ACCEPT, EITHER = "refused", "accepted", "either"


@dataclasses.dataclass
class Case:
    """One run of one tool."""

    tool: str
    what: str  # a short description for the table
    args: List[str]
    expect: str = REFUSE
    out: Optional[Path] = None  # the output folder or file whose state a failed run must not change
    file_limit: Optional[int] = None  # RLIMIT_FSIZE in bytes: a full disk


@dataclasses.dataclass
class Outcome:
    case: Case
    kind: str
    status: Optional[int]
    seconds: float
    detail: str


def snapshot(path: Optional[Path]) -> Optional[Dict[str, object]]:
    """The output's state: every file below it (size, mtime) and the names beside it (temporary folders)."""
    if path is None:
        return None
    state: Dict[str, object] = {"exists": path.exists(), "files": {}, "siblings": []}
    if path.is_dir():
        for f in sorted(path.rglob("*")):
            st = f.stat()
            state["files"][str(f.relative_to(path))] = (st.st_size, st.st_mtime_ns)  # type: ignore[index]
    elif path.exists():
        st = path.stat()
        state["files"]["."] = (st.st_size, st.st_mtime_ns)  # type: ignore[index]
    if path.parent.exists():
        state["siblings"] = sorted(p.name for p in path.parent.iterdir())
    return state


def run_case(case: Case, build: Path, timeout: float, scratch: Path) -> Outcome:
    exe = build / "examples" / case.tool
    # Outputs of earlier cases are removed first (a run they leave behind would make the next case fail for
    # another reason); folders standing for "an earlier run" (scratch/existing) and inputs are kept.
    if case.out is not None and (scratch / "out") in case.out.parents:
        if case.out.is_dir():
            shutil.rmtree(case.out)
        elif case.out.exists():
            case.out.unlink()
    before = snapshot(case.out)

    def limits() -> None:
        if case.file_limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # the write fails with EFBIG instead of killing
            resource.setrlimit(resource.RLIMIT_FSIZE, (case.file_limit, case.file_limit))

    start = time.monotonic()
    env = dict(os.environ, MPLBACKEND="Agg")
    try:
        proc = subprocess.run([str(exe)] + case.args, cwd=scratch, capture_output=True, timeout=timeout,
                              preexec_fn=limits, env=env, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return Outcome(case, "hung", None, time.monotonic() - start, f"killed after {timeout:.0f} s")
    seconds = time.monotonic() - start
    err = proc.stderr.decode("utf-8", "replace")
    out = proc.stdout.decode("utf-8", "replace")
    last_error = next((line for line in reversed(err.splitlines()) if "error" in line), "")
    crash_markers = ("terminate called", "Segmentation fault", "AddressSanitizer", "runtime error:",
                     "ThreadSanitizer", "core dumped", "Assertion")
    if proc.returncode < 0 or any(m in err for m in crash_markers):
        sig = -proc.returncode if proc.returncode < 0 else None
        name = signal.Signals(sig).name if sig else "a crash report"
        return Outcome(case, "crashed", proc.returncode, seconds, f"{name}: {err.strip()[-200:]}")
    if proc.returncode != 0 and before is not None and snapshot(case.out) != before:
        return Outcome(case, "partial output", proc.returncode, seconds,
                       f"exit {proc.returncode} changed {case.out.name if case.out else ''}: {last_error[:160]}")
    if proc.returncode == 0:
        return Outcome(case, "accepted", 0, seconds, (out.strip().splitlines() or [""])[-1][:160])
    degenerate = case.tool == "wicp_align" and proc.returncode == 4 and "degenerate" in out
    if f"{case.tool}: error" in err or degenerate:
        return Outcome(case, "refused clearly", proc.returncode, seconds,
                       (last_error or "degenerate: " + out.strip().splitlines()[-1])[:200])
    return Outcome(case, "unclear", proc.returncode, seconds, f"no error line; stderr: {err.strip()[-200:]!r}")


# ----------------------------------------------------------------------------------------------------------
# Inputs, made once in the scratch folder.


class Fixtures:
    def __init__(self, scratch: Path, data: Path, build: Path):
        self.s = scratch
        self.data = data
        self.build = build
        self.real_map = data / "map_fr1_desk.txt"
        self.fr1 = data / "tum_fr1_xyz_head"
        (scratch / "in").mkdir(parents=True, exist_ok=True)

    def path(self, name: str) -> Path:
        return self.s / "in" / name

    def text(self, name: str, content: str) -> Path:
        p = self.path(name)
        p.write_text(content)
        return p

    def binary(self, name: str, content: bytes) -> Path:
        p = self.path(name)
        p.write_bytes(content)
        return p

    def make(self) -> None:
        lines = self.real_map.read_text().splitlines(keepends=True)
        frames = [l for l in lines if l.startswith("FRAME")]
        landmarks = [l for l in lines if l.startswith("LANDMARK")]
        # A small valid map: every frame, the first 400 landmarks; and its parts.
        small = frames + landmarks[:400]
        self.good_map = self.text("good_map.txt", "".join(small))
        self.text("empty.txt", "")
        self.binary("garbage.bin", bytes((i * 7919 + 13) % 256 for i in range(4096)) + b"\0\xff\xfe")
        text = "".join(small)
        self.text("truncated_map.txt", text[: len(text) // 2])
        bad = landmarks[0].split()
        self.text("nan_map.txt", "".join(frames) + " ".join(bad[:2] + ["nan"] + bad[3:]) + "\n")
        self.text("inf_map.txt", "".join(frames) + " ".join(bad[:2] + ["inf"] + bad[3:]) + "\n")
        self.text("huge_map.txt", "".join(frames) + "".join(
            " ".join([f"LANDMARK {i}", "3e38", "3e38", "3e38"] + bad[5:]) + "\n" for i in range(20)))
        self.text("unknown_record_map.txt", "".join(frames) + "POINT 1 2 3\n")
        self.text("bad_count_map.txt", "".join(frames) + " ".join(bad[:14] + ["5"] + bad[15:]) + "\n")
        self.text("unknown_frame_map.txt", frames[0] + " ".join(bad[:15] + ["99999"] + bad[16:]) + "\n")
        self.text("zero_quaternion_map.txt", " ".join(frames[0].split()[:5] + ["0", "0", "0", "0"]) + "\n")
        self.text("collinear_map.txt", "".join(frames) + "".join(
            " ".join([f"LANDMARK {i}", f"{0.1 * i}", "0", "0"] + bad[5:]) + "\n" for i in range(30)))
        self.text("non_psd_covariance_map.txt", "".join(frames) + " ".join(
            bad[:5] + ["1", "0", "0", "0", "-1", "0", "0", "0", "1"] + bad[14:]) + "\n")
        self.directory = self.path("a_directory")
        self.directory.mkdir(exist_ok=True)
        # Trajectories.
        gt = (self.fr1 / "groundtruth.txt").read_text()
        self.gt = self.text("gt.txt", gt)
        gt_lines = [l for l in gt.splitlines() if l and not l.startswith("#")]
        self.text("traj_nan.txt", "\n".join(gt_lines[:10] + [" ".join(gt_lines[10].split()[:1] + ["nan"] * 7)]) + "\n")
        self.text("traj_shifted.txt", "\n".join(
            " ".join([f"{float(l.split()[0]) + 1e5:.6f}"] + l.split()[1:]) for l in gt_lines) + "\n")
        self.text("traj_short_line.txt", gt_lines[0] + "\n1305031102.2 1 2 3\n")
        self.text("traj_one_pose.txt", gt_lines[0] + "\n")
        # TUM folders made from fr1's head: lists and images altered, the rest linked.
        self.tum_missing_images = self.tum_copy("tum_missing_images", drop_images=True)
        self.tum_bad_list = self.tum_copy("tum_bad_list", rgb_txt="# header\n1305031102.175304\nnot a line at all\n")
        self.tum_black = self.tum_copy("tum_black", image=("rgb", "black"))
        self.tum_zero_depth = self.tum_copy("tum_zero_depth", image=("depth", "zero"))
        self.tum_small_depth = self.tum_copy("tum_small_depth", image=("depth", "small"))
        self.tum_empty = self.path("tum_empty")
        self.tum_empty.mkdir(exist_ok=True)
        self.bad_camera = self.text("bad_camera.yaml", "%YAML:1.0\nfx: -5\nfy: 525\ncx: 320\ncy: 240\n")
        self.garbage_camera = self.text("garbage_camera.yaml", "%YAML:1.\n---<:p\n1: -\n")
        self.bad_vocabulary = self.text("bad_vocabulary.txt", "WICP_VOCABULARY 1\nbranching 10\ndepth 3\nwords x\n")
        # A valid session (a short synthetic run), and corrupt copies of it.
        run = self.s / "good_run"
        subprocess.run([str(self.build / "examples" / "wicp_rgbd_slam"), "--synthetic-frames", "40", "--out", str(run),
                        "--overwrite", "--deterministic"], check=True, capture_output=True, timeout=600)
        self.session = run / "session"
        self.session_truncated = self.session_copy("session_truncated", "keyframes.txt",
                                                   lambda t: t[: len(t) // 3])
        self.session_garbage = self.session_copy("session_garbage", "landmarks.txt", lambda t: "LANDMARK x y z\n")
        self.session_no_camera = self.session_copy("session_no_camera", "camera.yaml", None)
        self.good_minimaps = [run / "minimaps" / n for n in sorted(os.listdir(run / "minimaps"))]

    def tum_copy(self, name: str, drop_images: bool = False, rgb_txt: Optional[str] = None,
                 image: Optional[tuple] = None) -> Path:
        import numpy as np
        from PIL import Image
        d = self.path(name)
        if d.exists():
            shutil.rmtree(d)
        d.mkdir()
        for f in ("rgb.txt", "depth.txt", "groundtruth.txt"):
            shutil.copy(self.fr1 / f, d / f)
        if rgb_txt is not None:
            (d / "rgb.txt").write_text(rgb_txt)
        for kind in ("rgb", "depth"):
            (d / kind).mkdir()
            if drop_images:
                continue
            for f in sorted(os.listdir(self.fr1 / kind)):
                target = d / kind / f
                if image and image[0] == kind:
                    if image[1] == "black":
                        Image.fromarray(np.zeros((480, 640, 3), np.uint8)).save(target)
                    elif image[1] == "zero":
                        Image.fromarray(np.zeros((480, 640), np.uint16)).save(target)
                    else:
                        Image.fromarray(np.full((240, 320), 5000, np.uint16)).save(target)
                else:
                    os.symlink(self.fr1 / kind / f, target)
        return d

    def session_copy(self, name: str, file: str, change: Optional[Callable[[str], str]]) -> Path:
        d = self.path(name)
        if d.exists():
            shutil.rmtree(d)
        shutil.copytree(self.session, d)
        if change is None:
            (d / file).unlink()
        else:
            (d / file).write_text(change((d / file).read_text()))
        return d


# ----------------------------------------------------------------------------------------------------------
# The cases.

BAD_NUMBERS = ["-1", "0", "1e30", "abc", "nan", "4294967297"]


def option_cases(tool: str, base: List[str], options: List[str], out: Optional[Path] = None) -> List[Case]:
    """Every numeric option with wrong values (0 may be valid for some: either), an unknown option, a missing
    value."""
    cases = []
    for opt in options:
        for value in BAD_NUMBERS:
            expect = EITHER if value in ("0", "1e30", "4294967297") else REFUSE
            cases.append(Case(tool, f"--{opt} {value}", base + [f"--{opt}", value], expect, out))
    cases.append(Case(tool, "unknown option", base + ["--bogus-option"], REFUSE, out))
    if options:
        cases.append(Case(tool, "missing value", base + [f"--{options[0]}"], REFUSE, out))
    return cases


def map_file_cases(tool: str, make_args: Callable[[Path], List[str]], f: Fixtures,
                   out: Optional[Path] = None) -> List[Case]:
    files = ["empty.txt", "garbage.bin", "truncated_map.txt", "nan_map.txt", "inf_map.txt", "huge_map.txt",
             "unknown_record_map.txt", "bad_count_map.txt", "unknown_frame_map.txt", "zero_quaternion_map.txt",
             "non_psd_covariance_map.txt"]
    # An empty file is an empty map, which wicp_map reads as such (stats: 0 frames; tests/test_io_wicp_map.cpp).
    cases = [Case(tool, f"map: {name}", make_args(f.path(name)),
                  EITHER if tool == "wicp_map" and name == "empty.txt" else REFUSE, out) for name in files]
    cases.append(Case(tool, "map: missing file", make_args(f.path("does_not_exist.txt")), REFUSE, out))
    cases.append(Case(tool, "map: a directory", make_args(f.directory), REFUSE, out))
    return cases


def tum_cases(tool: str, make_args: Callable[[Path], List[str]], f: Fixtures, out: Optional[Path]) -> List[Case]:
    return [
        Case(tool, "dataset: images missing", make_args(f.tum_missing_images), REFUSE, out),
        Case(tool, "dataset: malformed rgb.txt", make_args(f.tum_bad_list), REFUSE, out),
        Case(tool, "dataset: all-black colour", make_args(f.tum_black), REFUSE, out),
        Case(tool, "dataset: all-zero depth", make_args(f.tum_zero_depth), REFUSE, out),
        Case(tool, "dataset: depth of another size", make_args(f.tum_small_depth), REFUSE, out),
        Case(tool, "dataset: empty folder", make_args(f.tum_empty), REFUSE, out),
        Case(tool, "dataset: missing folder", make_args(f.path("no_such_dataset")), REFUSE, out),
    ]


def cases_for(tool: str, f: Fixtures, scratch: Path) -> List[Case]:
    o = scratch / "out" / tool
    o.parent.mkdir(parents=True, exist_ok=True)
    existing = scratch / "existing" / tool  # a non-empty folder of an earlier run
    existing.mkdir(parents=True, exist_ok=True)
    (existing / "keep.txt").write_text("from an earlier run\n")
    gm = str(f.good_map)
    if tool == "wicp_align":
        return (map_file_cases(tool, lambda p: ["--source", str(p), "--target", gm], f)
                + map_file_cases(tool, lambda p: ["--source", gm, "--target", str(p)], f)
                + [Case(tool, "target collinear", ["--source", gm, "--target", str(f.path("collinear_map.txt"))],
                        REFUSE),
                   Case(tool, "--k above the target's landmarks", ["--source", gm, "--target", gm, "--k", "1000"],
                        REFUSE),
                   Case(tool, "--displace not six numbers", ["--source", gm, "--target", gm, "--displace", "1 2"]),
                   Case(tool, "--displace nan", ["--source", gm, "--target", gm, "--displace", "nan 0 0 0 0 0"]),
                   Case(tool, "--strategy unknown", ["--source", gm, "--target", gm, "--strategy", "heaviest"]),
                   Case(tool, "--plot into a missing folder", ["--source", gm, "--target", gm, "--plot",
                                                               str(scratch / "no" / "such" / "a.png")], REFUSE),
                   Case(tool, "valid maps", ["--source", gm, "--target", gm], ACCEPT)]
                + option_cases(tool, ["--source", gm, "--target", gm],
                               ["k", "max-iterations", "max-correspondence-distance", "min-observations", "threads"]))
    if tool == "wicp_map":
        cut_out = scratch / "out" / "wicp_map_cut"
        return (map_file_cases(tool, lambda p: ["stats", str(p)], f)
                + map_file_cases(tool, lambda p: ["convert", str(p), str(scratch / "out" / "c.ply")], f,
                                 scratch / "out" / "c.ply")
                + [Case(tool, "convert: unknown extension", ["convert", gm, str(scratch / "out" / "c.xyz")]),
                   Case(tool, "convert: full disk (.ply)", ["convert", gm, str(scratch / "out" / "full.ply")], REFUSE,
                        scratch / "out" / "full.ply", file_limit=4096),
                   Case(tool, "convert: full disk (.pcd)", ["convert", gm, str(scratch / "out" / "full.pcd")], REFUSE,
                        scratch / "out" / "full.pcd", file_limit=4096),
                   Case(tool, "cut: existing --out", ["cut", gm, "--out", str(existing), "--frames-per-minimap", "40"],
                        REFUSE, existing),
                   Case(tool, "cut: full disk", ["cut", gm, "--out", str(cut_out), "--frames-per-minimap", "40"],
                        REFUSE, cut_out, file_limit=2048),
                   Case(tool, "unknown command", ["explode", gm]),
                   Case(tool, "valid stats", ["stats", gm], ACCEPT)]
                + option_cases(tool, ["cut", gm, "--out", str(cut_out)], ["frames-per-minimap", "min-observations"],
                               cut_out))
    if tool == "wicp_evaluate":
        g = str(f.gt)
        files = ["empty.txt", "garbage.bin", "traj_nan.txt", "traj_short_line.txt", "traj_one_pose.txt",
                 "traj_shifted.txt"]
        return ([Case(tool, f"estimate: {n}", [g, str(f.path(n))]) for n in files]
                + [Case(tool, f"ground truth: {n}", [str(f.path(n)), g]) for n in files]
                + [Case(tool, "estimate: missing", [g, str(f.path("none.txt"))]),
                   Case(tool, "--rpe-unit unknown", [g, g, "--rpe-unit", "h"]),
                   Case(tool, "full disk for --plot", [g, g, "--plot", str(scratch / "out" / "ate.png")], EITHER,
                        scratch / "out" / "ate.png", file_limit=1024),
                   Case(tool, "valid", [g, g], ACCEPT)]
                + option_cases(tool, [g, g], ["max-difference", "rpe-delta"]))
    if tool == "wicp_rgbd_slam":
        short = ["--max-frames", "8", "--deterministic", "--no-loop-closure"]
        return (tum_cases(tool, lambda d: ["--dataset", str(d), "--camera", "fr1", "--out", str(o)] + short, f, o)
                + [Case(tool, "camera: invalid values", ["--dataset", str(f.fr1), "--camera", str(f.bad_camera),
                                                         "--out", str(o)] + short, REFUSE, o),
                   Case(tool, "camera: text OpenCV loops on", ["--dataset", str(f.fr1), "--camera",
                                                               str(f.garbage_camera), "--out", str(o)] + short,
                        REFUSE, o),
                   Case(tool, "camera: unknown name", ["--dataset", str(f.fr1), "--camera", "fr9", "--out", str(o)]
                        + short, REFUSE, o),
                   Case(tool, "vocabulary: corrupt", ["--synthetic-frames", "5", "--vocabulary",
                                                      str(f.bad_vocabulary), "--out", str(o)], REFUSE, o),
                   Case(tool, "--out exists, not empty", ["--synthetic-frames", "5", "--out", str(existing)], REFUSE,
                        existing),
                   Case(tool, "--out is a file", ["--synthetic-frames", "5", "--out", str(f.good_map)], REFUSE,
                        f.good_map),
                   Case(tool, "full disk", ["--synthetic-frames", "12", "--out", str(o), "--deterministic"], REFUSE,
                        o, file_limit=65536),
                   Case(tool, "--first-frame beyond the sequence", ["--dataset", str(f.fr1), "--first-frame", "500",
                                                                    "--out", str(o)], REFUSE, o),
                   Case(tool, "unknown --matcher", ["--synthetic-frames", "5", "--matcher", "magic", "--out", str(o)],
                        REFUSE, o),
                   Case(tool, "valid short run", ["--synthetic-frames", "10", "--out", str(scratch / "out" / "ok"),
                                                  "--overwrite"], ACCEPT)]
                + option_cases(tool, ["--out", str(o), "--synthetic-frames", "5"],
                               ["max-frames", "first-frame", "minimap-keyframes", "synthetic-frames", "seed",
                                "frames-per-loop", "depth-noise", "room-scale", "focal-error", "kd-backtracks"], o))
    if tool == "wicp_merge":
        s = str(f.session)
        return ([Case(tool, "one session only", ["--session", s, "--out", str(o)], REFUSE, o),
                 Case(tool, "session: missing folder", ["--session", s, "--session", str(f.path("none")), "--out",
                                                        str(o)], REFUSE, o),
                 Case(tool, "session: truncated keyframes", ["--session", s, "--session", str(f.session_truncated),
                                                             "--out", str(o)], REFUSE, o),
                 Case(tool, "session: garbage landmarks", ["--session", s, "--session", str(f.session_garbage),
                                                           "--out", str(o)], REFUSE, o),
                 Case(tool, "session: camera missing", ["--session", s, "--session", str(f.session_no_camera),
                                                        "--out", str(o)], REFUSE, o),
                 Case(tool, "session: a map file", ["--session", s, "--session", gm, "--out", str(o)], REFUSE, o),
                 Case(tool, "vocabulary: corrupt", ["--session", s, "--session", s, "--vocabulary",
                                                    str(f.bad_vocabulary), "--out", str(o)], REFUSE, o),
                 Case(tool, "--out exists, not empty", ["--session", s, "--session", s, "--out", str(existing)],
                      REFUSE, existing),
                 Case(tool, "full disk", ["--session", s, "--session", s, "--out", str(o)], EITHER, o,
                      file_limit=4096)]
                + option_cases(tool, ["--session", s, "--session", s, "--out", str(o)],
                               ["min-loops", "minimap-keyframes"], o))
    if tool == "wicp_demo":
        return ([Case(tool, "--out exists, not empty", ["--out", str(existing), "--frames", "80",
                                                        "--frames-per-minimap", "40"], REFUSE, existing),
                 Case(tool, "--displace not six numbers", ["--out", str(o), "--displace", "1 2 3"], REFUSE, o),
                 Case(tool, "full disk", ["--out", str(o), "--frames", "80", "--frames-per-minimap", "40"], REFUSE,
                      o, file_limit=8192),
                 Case(tool, "--frames-per-minimap not below --frames", ["--out", str(o), "--frames", "40",
                                                                        "--frames-per-minimap", "40"], REFUSE, o)]
                + option_cases(tool, ["--out", str(o), "--frames", "80", "--frames-per-minimap", "40"],
                               ["seed", "frames", "landmarks", "frames-per-minimap", "k", "min-observations",
                                "threads"], o))
    if tool.startswith("wicp_sweep_"):
        return (map_file_cases(tool, lambda p: ["--source", str(p), "--target", gm, "--out", str(o), "--no-plot"], f,
                               o)
                + [Case(tool, "--map and --source together", ["--map", gm, "--source", gm, "--target", gm, "--out",
                                                              str(o)], REFUSE, o),
                   Case(tool, "--source-frames without --target-frames", ["--map", gm, "--source-frames", "0-100",
                                                                          "--out", str(o)], REFUSE, o),
                   Case(tool, "--source-frames malformed", ["--map", gm, "--source-frames", "x-1", "--target-frames",
                                                            "0-100", "--out", str(o)], REFUSE, o),
                   Case(tool, "--preset unknown", ["--map", gm, "--preset", "theirs", "--out", str(o)], REFUSE, o),
                   Case(tool, "--out exists, not empty", ["--map", gm, "--out", str(existing)], REFUSE, existing)]
                + option_cases(tool, ["--map", gm, "--out", str(o), "--no-plot"],
                               ["max-iterations", "min-observations", "threads"], o))
    if tool == "wicp_vocabulary":
        voc = str(scratch / "out" / "voc.txt")
        return ([Case(tool, "train: no source", ["train", "--out", voc]),
                 Case(tool, "evaluate: corrupt vocabulary", ["evaluate", "--vocabulary", str(f.bad_vocabulary),
                                                             "--dataset", str(f.fr1)]),
                 Case(tool, "evaluate: vocabulary and self-trained", ["evaluate", "--vocabulary", voc,
                                                                      "--self-trained", "--dataset", str(f.fr1)]),
                 Case(tool, "unknown command", ["explain"])]
                + [Case(tool, c.what, ["train", "--out", voc] + c.args, c.expect)
                   for c in tum_cases(tool, lambda d: ["--dataset", str(d), "--camera", "fr1"], f, None)[:6]]
                + option_cases(tool, ["train", "--out", voc, "--synthetic", "1"], ["branching", "depth", "every"]))
    if tool == "wicp_make_variant":
        return (tum_cases(tool, lambda d: ["--dataset", str(d), "--camera", "fr1", "--variant", "jpeg", "--out",
                                           str(o)], f, o)[:2]
                + [Case(tool, "unknown variant", ["--dataset", str(f.fr1), "--variant", "sepia", "--out", str(o)],
                        REFUSE, o),
                   Case(tool, "--out exists, not empty", ["--dataset", str(f.fr1), "--variant", "jpeg", "--out",
                                                          str(existing)], REFUSE, existing),
                   Case(tool, "full disk", ["--dataset", str(f.fr1), "--variant", "jpeg", "--out", str(o)], REFUSE, o,
                        file_limit=16384)]
                + option_cases(tool, ["--dataset", str(f.fr1), "--variant", "jpeg,blur,low-light,burst,focal",
                                      "--out", str(o)],
                               ["jpeg-quality", "depth-factor", "focal", "blur-length", "gain", "gamma", "noise",
                                "burst-period"], o))
    if tool == "wicp_synthetic_rgbd":
        return ([Case(tool, "--out exists, not empty", ["--out", str(existing), "--frames", "2"], REFUSE, existing),
                 Case(tool, "full disk", ["--out", str(o), "--frames", "3"], REFUSE, o, file_limit=65536)]
                + option_cases(tool, ["--out", str(o), "--frames", "2"],
                               ["frames", "seed", "fps", "depth-noise-coefficient"], o))
    if tool == "wicp_global_sweep":
        return (map_file_cases(tool, lambda p: ["--map", str(p), "--yaws", "0", "--xy", "0:0"], f)
                + [Case(tool, "--xy malformed", ["--map", gm, "--xy", "1;2"]),
                   Case(tool, "--method unknown", ["--map", gm, "--method", "best"])]
                + option_cases(tool, ["--synthetic", "--yaws", "0", "--xy", "0:0", "--overlaps", "0.5"],
                               ["landmarks", "min-observations", "shrink", "yaw-hypotheses", "vote-cell"]))
    raise SystemExit(f"probe_tools: no cases for {tool}")


TOOLS = ["wicp_align", "wicp_map", "wicp_evaluate", "wicp_rgbd_slam", "wicp_merge", "wicp_demo", "wicp_sweep_k",
         "wicp_sweep_yaw", "wicp_sweep_xy", "wicp_sweep_xy_yaw", "wicp_vocabulary", "wicp_make_variant",
         "wicp_synthetic_rgbd", "wicp_global_sweep"]
KINDS = ["refused clearly", "accepted", "crashed", "hung", "unclear", "partial output"]


def is_problem(o: Outcome) -> bool:
    if o.kind in ("crashed", "hung", "unclear", "partial output"):
        return True
    return (o.case.expect == REFUSE and o.kind != "refused clearly") or (
        o.case.expect == ACCEPT and o.kind != "accepted")


def table(outcomes: List[Outcome], seconds: float) -> str:
    rows = ["| tool | cases | " + " | ".join(KINDS) + " | not as expected |",
            "|---|---|" + "---|" * (len(KINDS) + 1)]
    for tool in TOOLS:
        mine = [o for o in outcomes if o.case.tool == tool]
        if not mine:
            continue
        counts = [sum(o.kind == k for o in mine) for k in KINDS]
        rows.append(f"| `{tool}` | {len(mine)} | " + " | ".join(map(str, counts)) +
                    f" | {sum(is_problem(o) for o in mine)} |")
    total = [sum(o.kind == k for o in outcomes) for k in KINDS]
    rows.append(f"| all | {len(outcomes)} | " + " | ".join(map(str, total)) +
                f" | {sum(is_problem(o) for o in outcomes)} |")
    problems = [o for o in outcomes if is_problem(o)]
    text = "\n".join(rows) + f"\n\n{len(outcomes)} runs in {seconds:.0f} s.\n"
    if problems:
        text += "\nCases not as expected:\n\n" + "\n".join(
            f"- `{o.case.tool}` {o.case.what}: {o.kind} (exit {o.status}, expected {o.case.expect}): {o.detail}"
            for o in problems) + "\n"
    return text


def main() -> int:
    root = Path(__file__).resolve().parent.parent
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=Path, default=root / "build")
    parser.add_argument("--data", type=Path, default=root.parent / "shared" / "data")
    parser.add_argument("--scratch", type=Path, default=None, help="default: a new temporary folder, removed")
    parser.add_argument("--out", type=Path, default=None, help="also write the markdown table here")
    parser.add_argument("--timeout", type=float, default=120.0, help="seconds before a run counts as hung")
    parser.add_argument("--tool", action="append", choices=TOOLS, help="only these tools (repeatable)")
    args = parser.parse_args()
    for tool in args.tool or TOOLS:
        if not (args.build / "examples" / tool).exists():
            print(f"probe_tools: {args.build / 'examples' / tool} is not built", file=sys.stderr)
            return 2
    if not (args.data / "map_fr1_desk.txt").exists():
        print(f"probe_tools: {args.data} has no map_fr1_desk.txt", file=sys.stderr)
        return 2
    scratch = args.scratch or Path(tempfile.mkdtemp(prefix="wicp_probe_"))
    start = time.monotonic()
    try:
        fixtures = Fixtures(scratch, args.data, args.build)
        fixtures.make()
        outcomes = []
        for tool in args.tool or TOOLS:
            cases = cases_for(tool, fixtures, scratch)
            for i, case in enumerate(cases, 1):
                outcome = run_case(case, args.build, args.timeout, scratch)
                outcomes.append(outcome)
                flag = "  <-- " + outcome.kind if is_problem(outcome) else ""
                print(f"[{tool} {i}/{len(cases)}] {case.what}: {outcome.kind} ({outcome.seconds:.1f} s){flag}",
                      flush=True)
        report = table(outcomes, time.monotonic() - start)
    finally:
        if args.scratch is None:
            shutil.rmtree(scratch, ignore_errors=True)
    print("\n" + report)
    if args.out:
        args.out.write_text(report)
    return 1 if any(is_problem(o) for o in outcomes) else 0


if __name__ == "__main__":
    sys.exit(main())

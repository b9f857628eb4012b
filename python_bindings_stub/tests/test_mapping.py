"""Loop closure and session merging from Python: the same trajectories, loops and sessions as the tools, errors."""

import filecmp
import json
import subprocess
from pathlib import Path
from typing import Dict, List

import numpy as np
import pytest

import weighted_icp as wi
from conftest import TOOLS_DIR

# A synthetic room whose camera comes back to its start after 45 of 60 frames (the C++ loop-closure tests' run).
FRAMES, FRAMES_PER_LOOP, SEED = 60, 45, 7
# Two overlapping halves for the merge: frames 0-34 and 25-59.
FIRST_END, SECOND_START = 35, 25


def tool(name: str, *args: str) -> None:
    """Runs a built tool; fails the test, with its error output, when it does not exit 0."""
    path = TOOLS_DIR / name
    if not path.exists():
        pytest.fail(f"{path} is not built (ninja -C build {name})")
    done = subprocess.run([str(path), *args], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, f"{name} {' '.join(args)}: exit {done.returncode}: {done.stderr}"


@pytest.fixture(scope="module")
def revisit(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The synthetic sequence as a TUM folder (wicp_synthetic_rgbd), in this module's own scratch folder."""
    folder = tmp_path_factory.mktemp("revisit") / "sequence"
    tool("wicp_synthetic_rgbd", "--out", str(folder), "--frames", str(FRAMES), "--frames-per-loop",
         str(FRAMES_PER_LOOP), "--seed", str(SEED))
    return folder


def tool_run(sequence: Path, out: Path, *args: str) -> Dict[str, object]:
    """wicp_rgbd_slam --deterministic over the sequence into `out`; its report.json."""
    tool("wicp_rgbd_slam", "--dataset", str(sequence), "--deterministic", "--out", str(out), *args)
    report: Dict[str, object] = json.loads((out / "report.json").read_text())
    return report


def loop_rows(path: Path) -> List[List[float]]:
    """The rows of a loops.txt (comments skipped)."""
    return [[float(v) for v in line.split()] for line in path.read_text().splitlines() if not line.startswith("#")]


def test_a_run_closes_the_loops_the_tool_closes(revisit: Path, tmp_path: Path) -> None:
    report = tool_run(revisit, tmp_path / "tool")
    slam = wi.run_tum(str(revisit), deterministic=True)

    # The corrected trajectory, to the precision trajectory.txt is written with.
    written = wi.read_trajectory(tmp_path / "tool" / "trajectory.txt")
    assert slam.trajectory.shape == written.shape
    np.testing.assert_allclose(slam.trajectory, written, rtol=0, atol=1e-9)
    assert slam.loop_stats == {key: report[key] for key in
                               ("loops_detected", "loops_accepted", "pose_graph_optimisations")}
    loops = slam.loops
    assert len(loops) == report["loops_accepted"] >= 1
    rows = loop_rows(tmp_path / "tool" / "loops.txt")
    assert len(rows) == len(loops)
    for loop, row in zip(loops, rows):
        assert (loop.query_session, loop.match_session) == (0, 0) and loop.used
        assert (loop.query_timestamp, loop.match_timestamp) == pytest.approx((row[0], row[1]), abs=1e-9)
        assert loop.query_in_match.shape == (4, 4)
        np.testing.assert_allclose(loop.query_in_match[:3, 3], row[2:5], atol=1e-9)
        assert loop.inliers == int(row[9]) and loop.query > loop.match

    # Every candidate with its verdict, as loop_candidates.txt lists them.
    listed = [line.split(maxsplit=6) for line in (tmp_path / "tool" / "loop_candidates.txt").read_text().splitlines()
              if not line.startswith("#")]
    candidates = slam.loop_candidates()
    assert len(candidates) == len(listed) > len(loops)
    for candidate, fields in zip(candidates, listed):
        assert (candidate.query, candidate.match, candidate.verdict) == (int(fields[0]), int(fields[1]), fields[5])
        assert candidate.query_timestamp == pytest.approx(float(fields[2]), abs=1e-6)
        assert candidate.reason == (fields[6] if len(fields) > 6 else "")
    assert sum(c.verdict == "accepted" for c in candidates) == len(loops)

    # Closing loops is what changes the trajectory: without it, none is closed and the poses differ.
    open_loop = wi.run_tum(str(revisit), deterministic=True, loop_closure=False)
    assert open_loop.loops == [] and open_loop.loop_candidates() == [] and open_loop.loop_stats["loops_detected"] == 0
    assert not np.allclose(open_loop.trajectory, slam.trajectory, atol=1e-6)


def test_a_saved_session_is_the_tools_and_merges_as_wicp_merge_does(revisit: Path, tmp_path: Path) -> None:
    # The first half from Python, the second from the tool: a session is a session whichever wrote it.
    first = wi.run_tum(str(revisit), max_frames=FIRST_END, deterministic=True, loop_closure=False)
    first.save_session(tmp_path / "a")
    tool_run(revisit, tmp_path / "tool_a", "--max-frames", str(FIRST_END), "--no-loop-closure")
    for name in ("keyframes.txt", "landmarks.txt", "frames.txt", "camera.yaml", "session.txt"):
        assert filecmp.cmp(tmp_path / "a" / name, tmp_path / "tool_a" / "session" / name, shallow=False), name
    tool_run(revisit, tmp_path / "tool_b", "--first-frame", str(SECOND_START), "--no-loop-closure")
    second = wi.run_tum(str(revisit), first_frame=SECOND_START, deterministic=True, loop_closure=False)
    assert second.trajectory[0, 0] == pytest.approx(wi.read_trajectory(tmp_path / "tool_b" / "trajectory.txt")[0, 0])

    passes = []
    merge = wi.merge_sessions([tmp_path / "a", str(tmp_path / "tool_b" / "session")],
                              progress=lambda name, done, total: passes.append((name, done, total)))
    tool("wicp_merge", "--session", str(tmp_path / "a"), "--session", str(tmp_path / "tool_b" / "session"),
         "--out", str(tmp_path / "merged"))
    report = json.loads((tmp_path / "merged" / "report.json").read_text())

    assert [s.merged for s in merge.sessions] == [True, True] == [report["session_0_merged"], report["session_1_merged"]]
    # trajectory.txt repeats the timestamps of the frames both runs tracked: read as plain rows.
    np.testing.assert_allclose(merge.trajectory, np.loadtxt(tmp_path / "merged" / "trajectory.txt", comments="#"),
                               atol=1e-9)
    link = merge.sessions[1]
    assert link.loops_agreeing == report["session_1_loops_agreeing"] >= 2
    assert link.linked_to == 0 and link.folder == str(tmp_path / "tool_b" / "session")
    np.testing.assert_allclose(link.world_in_first, np.array(report["session_1_world_in_first"]), atol=1e-9)
    np.testing.assert_allclose(link.trajectory, wi.read_trajectory(tmp_path / "merged" / "trajectory_session_1.txt"),
                               atol=1e-9)
    assert len(merge.loops) == report["loops_accepted"] == len(loop_rows(tmp_path / "merged" / "loops.txt"))
    assert all(loop.query_session == 1 and loop.match_session == 0 for loop in merge.loops)
    assert len(merge.map) > len(first.session_map())
    assert passes and passes[-1][1] == passes[-1][2]

    # The two runs share frames 25-34: the second session's world lands where the first put those frames.
    a, b = merge.sessions[0].trajectory, merge.sessions[1].trajectory
    shared = np.intersect1d(a[:, 0], b[:, 0])
    assert len(shared) == FIRST_END - SECOND_START
    gaps = [np.linalg.norm(a[a[:, 0] == t, 1:4] - b[b[:, 0] == t, 1:4]) for t in shared]
    assert max(gaps) < 0.02, gaps


def test_a_session_is_not_overwritten_by_mistake(revisit: Path, tmp_path: Path) -> None:
    slam = wi.run_tum(str(revisit), max_frames=3, deterministic=True, loop_closure=False)
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "mine.txt").write_text("keep me")
    with pytest.raises(FileExistsError, match="overwrite=True"):
        slam.save_session(tmp_path / "s")
    assert (tmp_path / "s" / "mine.txt").read_text() == "keep me"
    slam.save_session(tmp_path / "s", overwrite=True)
    assert (tmp_path / "s" / "keyframes.txt").exists() and not (tmp_path / "s" / "mine.txt").exists()


def test_bad_sessions_and_vocabularies_are_named(revisit: Path, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="at least one"):
        wi.merge_sessions([])
    with pytest.raises(FileNotFoundError, match="nowhere"):
        wi.merge_sessions([tmp_path / "nowhere"])
    slam = wi.run_tum(str(revisit), max_frames=3, deterministic=True, loop_closure=False)
    slam.save_session(tmp_path / "s")
    landmarks = tmp_path / "s" / "landmarks.txt"
    lines = landmarks.read_text().splitlines()
    bad_line = next(i for i, line in enumerate(lines) if line and not line.startswith("#"))
    lines[bad_line] = "not a landmark"
    landmarks.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError, match=f"landmarks.txt:{bad_line + 1}"):
        wi.merge_sessions([tmp_path / "s"])

    with pytest.raises(FileNotFoundError, match="no_words.txt"):
        wi.RgbdSlam("fr1", vocabulary=tmp_path / "no_words.txt")
    words = tmp_path / "words.txt"
    words.write_text("not a vocabulary\n")
    with pytest.raises(ValueError, match="words.txt:1"):
        wi.RgbdSlam("fr1", vocabulary=words)
    with pytest.raises(ValueError, match="words.txt:1"):
        wi.merge_sessions([tmp_path / "s"], vocabulary=words)
    with pytest.raises(ValueError, match="no use with loop_closure=False"):
        wi.RgbdSlam("fr1", loop_closure=False, vocabulary=words)
    with pytest.raises(ValueError, match="first_frame 60 leaves no frame"):
        wi.run_tum(str(revisit), first_frame=FRAMES)


def test_a_merge_stops_on_a_progress_error(revisit: Path, tmp_path: Path) -> None:
    for name, end in (("a", FIRST_END), ("b", 0)):
        wi.run_tum(str(revisit), max_frames=end, first_frame=0 if name == "a" else SECOND_START, deterministic=True,
                   loop_closure=False).save_session(tmp_path / name)

    def stop(name: str, done: int, total: int) -> None:
        raise KeyboardInterrupt("stop the merge")

    with pytest.raises(KeyboardInterrupt, match="stop the merge"):
        wi.merge_sessions([tmp_path / "a", tmp_path / "b"], progress=stop)

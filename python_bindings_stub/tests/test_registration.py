"""align() and weighted_correspondences(): the numbers of wicp_align, and what they refuse."""

from pathlib import Path

import numpy as np
import pytest

import weighted_icp as wi
from conftest import run_tool


def displacement(x: float, y: float, yaw_deg: float) -> np.ndarray:
    """A rigid motion: yaw about z, then a translation."""
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[:2, 3] = [x, y]
    return m


@pytest.fixture(scope="module")
def halves(real_map_path: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple:
    """Alternate halves of the real map's first 80 frames, the source displaced, saved for wicp_align."""
    part = wi.LandmarkMap.load(real_map_path).mini_map(0, 79)
    source, target = part.alternate_halves()
    source.transform(displacement(0.05, -0.03, 4.0))
    folder = tmp_path_factory.mktemp("halves")
    source.save(folder / "a.txt")
    target.save(folder / "b.txt")
    return folder / "a.txt", folder / "b.txt"


@pytest.mark.parametrize("strategy", ["base", "covariance", "observations", "mean-distance"])
def test_align_gives_the_numbers_of_wicp_align(halves: tuple, strategy: str) -> None:
    a_path, b_path = halves
    tool = run_tool("wicp_align", "--source", str(a_path), "--target", str(b_path), "--strategy", strategy, "--k", "5")
    a = wi.LandmarkMap.load(a_path, min_observations=2)
    b = wi.LandmarkMap.load(b_path, min_observations=2)
    if strategy == "base":
        r = wi.align(a.positions, b.positions, strategy="base", k=5)
    else:
        r = wi.align(a.positions, b.positions, target_weights=wi.weights(b, strategy), k=5)
    assert np.array_equal(r.transformation, np.array(tool["transformation"]))
    assert r.fitness_score == tool["fitness_score"]
    assert r.iterations == tool["iterations"]
    assert r.converged == tool["converged"]
    assert r.stopped_at_iteration_limit == tool["stopped_at_iteration_limit"]
    assert r.correspondences == tool["correspondences"]
    # The same through the maps and the strategy's name.
    by_map = wi.align(a, b, strategy=strategy, k=5)
    assert np.array_equal(by_map.transformation, r.transformation)


def test_refine_and_float32_match_the_tool(halves: tuple) -> None:
    a_path, b_path = halves
    tool = run_tool("wicp_align", "--source", str(a_path), "--target", str(b_path), "--strategy", "covariance",
                    "--refine", "--max-iterations", "40")
    a = wi.LandmarkMap.load(a_path, min_observations=2)
    b = wi.LandmarkMap.load(b_path, min_observations=2)
    # The aligner works on float coordinates: float32 input gives the same numbers.
    r = wi.align(a.positions.astype(np.float32), b.positions.astype(np.float32),
                 target_weights=wi.weights(b, "covariance").astype(np.float32), refine=True, max_iterations=40)
    assert np.array_equal(r.transformation, np.array(tool["transformation"]))
    assert r.refine_iterations == tool["refine_iterations"]


def test_align_recovers_a_known_motion_from_views() -> None:
    rng = np.random.default_rng(3)
    target = rng.uniform(-2, 2, size=(400, 3))
    motion = displacement(0.04, 0.02, 3.0)
    # A non-contiguous view: every other row of a larger array, read in place.
    big = np.zeros((800, 3))
    big[::2] = (target - motion[:3, 3]) @ motion[:3, :3]
    r = wi.align(big[::2], target, k=1)
    assert r.converged and not r.degenerate
    assert np.allclose(r.transformation, motion, atol=1e-4)
    assert r.time_ms >= 0


def test_initial_guess_is_used() -> None:
    rng = np.random.default_rng(4)
    target = rng.uniform(-1, 1, size=(200, 3))
    r = wi.align(target, target, k=1, initial_guess=np.eye(4), max_iterations=5)
    assert np.allclose(r.transformation, np.eye(4), atol=1e-6)


def test_degenerate_problems_are_reported_not_run() -> None:
    line = np.array([[t, 0.0, 0.0] for t in range(10)])
    r = wi.align(line, line, k=1)
    assert r.degenerate and "collinear" in r.reason
    assert np.isnan(r.fitness_score)


@pytest.mark.parametrize(
    "source, message",
    [
        (np.zeros((5, 2)), "source must have shape (N, 3)"),
        (np.zeros((5, 3), dtype=np.int64), "source must be an (N, 3) array of float64 or float32"),
        (np.zeros(15), "source must have shape (N, 3)"),
        ("not an array", "source must be"),
        (np.zeros((0, 3)), "source has no points"),
    ],
)
def test_bad_source_names_the_argument(source: object, message: str) -> None:
    with pytest.raises(ValueError) as error:
        wi.align(source, np.random.default_rng(0).uniform(size=(10, 3)))  # type: ignore[arg-type]
    assert message in str(error.value)


def test_bad_arguments_raise_value_error() -> None:
    cloud = np.random.default_rng(1).uniform(size=(20, 3))
    with pytest.raises(ValueError, match="target_weights must have shape \\(20,\\)"):
        wi.align(cloud, cloud, target_weights=np.ones(19))
    with pytest.raises(ValueError, match=r"target_weights\[3\]"):
        wi.align(cloud, cloud, target_weights=np.array([1.0, 1, 1, -1] + [1] * 16))
    with pytest.raises(ValueError, match="k must be between 1 and 1000"):
        wi.align(cloud, cloud, k=0)
    with pytest.raises(ValueError, match="initial_guess must have shape \\(4, 4\\)"):
        wi.align(cloud, cloud, initial_guess=np.eye(3))
    with pytest.raises(ValueError, match="strategy"):
        wi.align(cloud, cloud, strategy="nope")
    with pytest.raises(ValueError, match="LandmarkMap target"):
        wi.align(cloud, cloud, strategy="covariance")
    with pytest.raises(ValueError, match="max_iterations"):
        wi.align(cloud, cloud, max_iterations=0)
    with pytest.raises(ValueError, match="max_correspondence_distance"):
        wi.align(cloud, cloud, max_correspondence_distance=-1.0)


def test_weighted_correspondences_pick_the_heaviest_of_k() -> None:
    target = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.2, 0, 0], [5.0, 0, 0]])
    source = np.array([[0.0, 0, 0]])
    weights = np.array([1.0, 1.0, 3.0, 9.0])
    s, t, d = wi.weighted_correspondences(source, target, weights, k=3)
    assert list(s) == [0] and list(t) == [2]
    assert d[0] == pytest.approx(0.04, rel=1e-6)
    # k = 1 is the nearest; a distance gate drops what is farther.
    assert list(wi.weighted_correspondences(source, target, weights, k=1)[1]) == [0]
    s, t, d = wi.weighted_correspondences(source + 10.0, target, weights, k=1, max_distance=0.5)
    assert len(s) == len(t) == len(d) == 0
    assert s.dtype == np.int64 and d.dtype == np.float64


def test_weighted_correspondences_match_the_aligners_choice(real_map_path: Path) -> None:
    m = wi.LandmarkMap.load(real_map_path, min_observations=2)
    a, b = m.alternate_halves()
    w = wi.weights(b, "observations")
    s, t, d = wi.weighted_correspondences(a.positions, b.positions, w, k=5)
    assert len(s) == len(a)
    # Each chosen target is the heaviest of the source point's 5 nearest.
    # Distances on the float coordinates the index holds; near-ties at the 5th neighbour are left out.
    source32 = a.positions.astype(np.float32).astype(np.float64)
    target32 = b.positions.astype(np.float32).astype(np.float64)
    checked = 0
    for i in range(0, len(a), 17):
        distances = np.linalg.norm(target32 - source32[i], axis=1)
        order = np.argsort(distances, kind="stable")
        if distances[order[5]] - distances[order[4]] < 1e-6:
            continue
        assert w[t[i]] == w[order[:5]].max()
        checked += 1
    assert checked > 150


def test_align_global_recovers_a_half_turn_and_levels_camera_frame_maps(real_map_path: Path) -> None:
    even, odd = wi.LandmarkMap.load(real_map_path, min_observations=2).alternate_halves()
    moved = displacement(1.5, -1.0, 180.0)
    odd.transform(moved)
    r = wi.align_global(odd, even, strategy="covariance")
    assert np.allclose(r.transformation, np.linalg.inv(moved), atol=2e-3)
    # The same maps in their first camera's frame, where up is near -y, turned about the true up: 'auto' levels
    # each map by its cameras; a search about z alone cannot find the turn.
    even, odd = wi.LandmarkMap.load(real_map_path, min_observations=2).alternate_halves()
    first = even.frames[0]
    for m in (even, odd):
        m.transform(np.linalg.inv(first))
    up = first[:3, :3].T @ np.array([0.0, 0.0, 1.0])
    c, s = np.cos(np.radians(120.0)), np.sin(np.radians(120.0))
    cross = np.array([[0, -up[2], up[1]], [up[2], 0, -up[0]], [-up[1], up[0], 0]])
    turn = np.eye(4)
    turn[:3, :3] = c * np.eye(3) + s * cross + (1 - c) * np.outer(up, up)
    turn[:3, 3] = [0.4, -0.3, 0.2]
    odd.transform(turn)
    r = wi.align_global(odd, even, strategy="covariance")
    assert np.allclose(r.transformation, np.linalg.inv(turn), atol=5e-3)
    about_z = wi.align_global(odd, even, strategy="covariance", up_axis="z")
    assert not np.allclose(about_z.transformation, np.linalg.inv(turn), atol=5e-2)


def test_align_global_aligns_a_whole_map_onto_a_mini_map_the_other_way_as_the_tool_does(
        real_map_path: Path, tmp_path: Path) -> None:
    # Half of the whole map onto the other half's ten frames 60-69: the source has many times the target's landmarks,
    # so the search and the weighted ICP run the target onto the source, weighted by the source's covariances.
    even, odd = wi.LandmarkMap.load(real_map_path, min_observations=2).alternate_halves()
    mini = even.mini_map(60, 69).with_min_observations(2)
    assert len(odd) > 10 * len(mini)
    moved = displacement(2.0, -2.0, 90.0)
    odd.transform(moved)
    odd.save(tmp_path / "whole.txt")
    mini.save(tmp_path / "mini.txt")
    tool = run_tool("wicp_align", "--global", "--source", str(tmp_path / "whole.txt"), "--target",
                    str(tmp_path / "mini.txt"), "--strategy", "covariance")
    assert tool["reversed"] is True
    r = wi.align_global(wi.LandmarkMap.load(tmp_path / "whole.txt", min_observations=2),
                        wi.LandmarkMap.load(tmp_path / "mini.txt", min_observations=2), strategy="covariance")
    # The source's weights are the strategy's, as the tool's: the same numbers.
    assert np.array_equal(r.transformation, np.array(tool["transformation"]))
    assert r.correspondences == tool["correspondences"]
    truth = np.linalg.inv(moved)
    assert np.linalg.norm(r.transformation[:3, 3] - truth[:3, 3]) < 0.05
    turn = r.transformation[:3, :3] @ truth[:3, :3].T
    assert np.degrees(np.arccos(np.clip((np.trace(turn) - 1) / 2, -1, 1))) < 2.0


def test_align_global_refuses_a_bad_up_axis() -> None:
    points = np.random.default_rng(1).uniform(-1, 1, (50, 3))
    with pytest.raises(ValueError, match="up_axis"):
        wi.align_global(points, points, up_axis="y")
    with pytest.raises(ValueError, match="up_axis"):
        wi.align_global(points, points, up_axis=[0, 0, 0])

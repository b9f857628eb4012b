"""LandmarkMap: loading, arrays, cuts, saving, weights, and errors naming the file and line."""

from pathlib import Path

import numpy as np
import pytest

import weighted_icp as wi

SMALL_MAP = """# two frames, three landmarks
FRAME 0 0 0 0 1 0 0 0
FRAME 1 1 0 0 1 0 0 0
LANDMARK 10 0 0 2 0.01 0 0 0 0.01 0 0 0 0.04 2 0 100 100 1 110 100
LANDMARK 11 1 0 2 0.02 0 0 0 0.02 0 0 0 0.02 1 1 200 100
LANDMARK 12 0 1 2 0.01 0 0 0 0.01 0 0 0 0.01 3 0 300 100 1 310 100 0 320 90
"""


@pytest.fixture()
def small_map(tmp_path: Path) -> Path:
    path = tmp_path / "small.txt"
    path.write_text(SMALL_MAP)
    return path


def test_arrays_have_the_contract_shapes_and_dtypes(small_map: Path) -> None:
    m = wi.LandmarkMap.load(small_map)
    assert len(m) == 3
    assert m.positions.shape == (3, 3) and m.positions.dtype == np.float64
    assert np.array_equal(m.positions[1], [1.0, 0.0, 2.0])
    assert m.covariances.shape == (3, 3, 3)
    assert m.covariances[0, 2, 2] == 0.04
    assert np.issubdtype(m.observation_counts.dtype, np.integer)
    assert list(m.observation_counts) == [2, 1, 3]
    assert list(m.ids) == [10, 11, 12]
    assert list(m.frame_ids) == [0, 1]
    assert np.array_equal(m.frames[1][:3, 3], [1.0, 0.0, 0.0])
    assert m.mean_observation_distances[1] == pytest.approx(np.hypot(0.0, 2.0))


def test_min_observations_and_cuts(small_map: Path) -> None:
    assert len(wi.LandmarkMap.load(small_map, min_observations=2)) == 2
    m = wi.LandmarkMap.load(small_map)
    assert len(m.with_min_observations(3)) == 1
    first = m.mini_map(0, 0)
    assert list(first.frame_ids) == [0] and list(first.observation_counts) == [1, 2]
    assert [len(x) for x in m.split_into_mini_maps(1)] == [2, 3]
    a, b = m.alternate_halves()
    assert len(a) + len(b) == 3


def test_weights_follow_the_strategies(small_map: Path) -> None:
    m = wi.LandmarkMap.load(small_map)
    assert np.array_equal(wi.weights(m, "observations"), [2.0, 1.0, 3.0])
    assert np.array_equal(wi.weights(m, "base"), [1.0, 1.0, 1.0])
    cov = wi.weights(m, "covariance")
    assert cov[0] == pytest.approx(1.0 / (1.0 + np.linalg.norm(m.covariances[0])))
    assert wi.weights(m, "mean-distance").shape == (3,)
    assert sorted(wi.strategies()) == sorted(["base", "covariance", "observations", "mean-distance"])
    with pytest.raises(ValueError, match="observations"):
        wi.weights(m, "no-such-strategy")


def test_save_round_trips_and_transform_moves(small_map: Path, tmp_path: Path) -> None:
    m = wi.LandmarkMap.load(small_map)
    moved = m.copy()
    motion = np.eye(4)
    motion[:3, 3] = [1.0, 2.0, 3.0]
    moved.transform(motion)
    assert np.allclose(moved.positions, m.positions + [1.0, 2.0, 3.0])
    assert np.array_equal(m.positions[0], [0.0, 0.0, 2.0])  # the copy is independent
    moved.save(tmp_path / "moved.txt")
    again = wi.LandmarkMap.load(tmp_path / "moved.txt")
    assert np.array_equal(again.positions, moved.positions)
    assert np.array_equal(again.covariances, moved.covariances)
    with pytest.raises(ValueError, match="rigid motion"):
        moved.transform(np.diag([2.0, 2.0, 2.0, 1.0]))


def test_from_positions(tmp_path: Path) -> None:
    xyz = np.random.default_rng(2).uniform(size=(7, 3)).astype(np.float32)
    m = wi.LandmarkMap.from_positions(xyz)
    assert np.array_equal(m.positions, xyz.astype(np.float64))
    assert list(m.observation_counts) == [0] * 7
    with pytest.raises(ValueError, match="covariances must have shape"):
        wi.LandmarkMap.from_positions(xyz, covariances=np.zeros((6, 3, 3)))


@pytest.mark.parametrize(
    "line, what",
    [
        ("LANDMARK 13 0 0 x 1 0 0 0 1 0 0 0 1 0", "13"),
        ("LANDMARK 14 0 0 1 1 0 0 0 1 0 0 0 1 1 7 1 1", "frame"),
        ("FRAME 2 0 0 0", "FRAME"),
    ],
)
def test_malformed_maps_name_the_file_and_line(tmp_path: Path, line: str, what: str) -> None:
    path = tmp_path / "bad.txt"
    path.write_text(SMALL_MAP + line + "\n")
    with pytest.raises(ValueError) as error:
        wi.LandmarkMap.load(path)
    message = str(error.value)
    assert str(path) in message and ":7" in message, message


def test_missing_file_is_file_not_found(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError):
        wi.LandmarkMap.load(tmp_path / "none.txt")


def test_real_map_counts(real_map_path: Path) -> None:
    m = wi.LandmarkMap.load(str(real_map_path), min_observations=2)
    assert len(m) == 6081  # the data set's README
    assert len(m.frames) == 240
    assert (m.observation_counts >= 2).all()

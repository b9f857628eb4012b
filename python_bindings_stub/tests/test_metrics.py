"""ate(), rpe() and compare_ate(): wicp_evaluate's numbers, on files and on arrays."""

from pathlib import Path

import numpy as np
import pytest

import weighted_icp as wi
from conftest import run_tool


def drifting(truth: np.ndarray) -> np.ndarray:
    """The ground truth with a growing offset and a constant rotation: an estimate with error."""
    est = truth.copy()
    est[:, 1] += 0.01 * np.arange(len(est)) ** 0.5
    est[:, 2] -= 0.002 * np.arange(len(est))
    return est


def test_ate_and_rpe_match_wicp_evaluate(tum_folder: Path, tmp_path: Path) -> None:
    truth = wi.read_trajectory(tum_folder / "groundtruth.txt")
    assert truth.shape[1] == 8
    est_path = tmp_path / "est.txt"
    wi.write_trajectory(drifting(truth), est_path)
    tool = run_tool("wicp_evaluate", str(tum_folder / "groundtruth.txt"), str(est_path))
    ate = wi.ate(str(tum_folder / "groundtruth.txt"), est_path)
    rpe = wi.rpe(tum_folder / "groundtruth.txt", est_path)
    assert ate.pairs == tool["pairs"]
    assert ate.rmse == tool["ate_rmse_m"] and ate.translation.median == tool["ate_median_m"]
    assert np.array_equal(ate.alignment, np.array(tool["alignment"]))
    assert rpe.pairs == tool["rpe_pairs"]
    assert rpe.translation.rmse == tool["rpe_translation_rmse_m"]
    assert rpe.rotation_deg.rmse == tool["rpe_rotation_rmse_deg"]
    # Arrays read back from the files give the same numbers as the files.
    from_arrays = wi.ate(wi.read_trajectory(tum_folder / "groundtruth.txt"), wi.read_trajectory(est_path))
    assert from_arrays.rmse == ate.rmse


def test_compare_ate_matches_wicp_evaluate_versus(tum_folder: Path, tmp_path: Path) -> None:
    truth = wi.read_trajectory(tum_folder / "groundtruth.txt")
    rng = np.random.default_rng(4)
    precise, coarse = truth.copy(), truth.copy()
    precise[:, 1:4] += rng.normal(0.0, 0.001, (len(truth), 3))
    coarse[:, 1:4] += rng.normal(0.0, 0.01, (len(truth), 3))
    wi.write_trajectory(precise, tmp_path / "precise.txt")
    wi.write_trajectory(coarse, tmp_path / "coarse.txt")
    gt = str(tum_folder / "groundtruth.txt")
    tool = run_tool("wicp_evaluate", gt, str(tmp_path / "precise.txt"), "--versus", str(tmp_path / "coarse.txt"))
    c = wi.compare_ate(gt, tmp_path / "precise.txt", tmp_path / "coarse.txt")
    assert c.common_poses == tool["common_poses"] == c.first.pairs
    assert c.first_lower_fraction == tool["estimate_lower_fraction"] and c.first_lower_fraction > 0.95
    assert c.second.rmse == tool["versus_ate_rmse_m"] and c.first_rmse < c.second_rmse
    assert wi.compare_ate(gt, tmp_path / "coarse.txt", tmp_path / "precise.txt").first_lower_fraction < 0.05
    with pytest.raises(ValueError, match="resamples"):
        wi.compare_ate(gt, precise, coarse, resamples=0)


def test_poses_pair_form_equals_rows() -> None:
    t = np.arange(20) * 0.1
    poses = np.tile(np.eye(4), (20, 1, 1))
    poses[:, 0, 3] = t
    rows = np.zeros((20, 8))
    rows[:, 0], rows[:, 1], rows[:, 7] = t, t, 1.0
    est = poses.copy()
    est[:, 1, 3] = 0.01 * np.sin(t * 5)
    a = wi.ate((t, poses), (t, est))
    assert a.pairs == 20 and a.rmse > 0
    assert wi.ate(rows, (t, poses)).rmse == pytest.approx(0.0, abs=1e-12)
    r = wi.rpe((t, poses), (t, est), delta=2, unit="f")
    assert r.pairs > 0


def test_bad_trajectories_raise_value_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="gt must have shape \\(N, 8\\)"):
        wi.ate(np.zeros((5, 7)), np.zeros((5, 8)))
    with pytest.raises(ValueError, match="quaternion"):
        wi.ate(np.zeros((5, 8)), np.zeros((5, 8)))
    with pytest.raises(ValueError, match="unit must be"):
        wi.rpe(np.zeros((0, 8)), np.zeros((0, 8)), unit="m")
    bad = tmp_path / "bad.txt"
    bad.write_text("1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n")
    with pytest.raises(ValueError, match=f"{bad}:2"):
        wi.read_trajectory(bad)

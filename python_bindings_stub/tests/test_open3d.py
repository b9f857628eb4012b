"""A round trip through Open3D: weighted_icp cloud -> open3d.geometry.PointCloud -> back, then aligned."""

from pathlib import Path

import numpy as np
import pytest

import weighted_icp as wi

o3d = pytest.importorskip("open3d", reason="Open3D is not installed (Debian: python3-open3d)")


def test_round_trip_keeps_points_and_alignment(real_map_path: Path) -> None:
    m = wi.LandmarkMap.load(real_map_path, min_observations=2)
    a, b = m.alternate_halves()
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(b.positions))
    # Weights ride along as grey levels, as Open3D clouds carry no scalar field.
    w = wi.weights(b, "observations")
    cloud.colors = o3d.utility.Vector3dVector(np.repeat((w / w.max())[:, None], 3, axis=1))
    back = np.asarray(cloud.points)
    assert back.dtype == np.float64 and np.array_equal(back, b.positions)
    back_w = np.asarray(cloud.colors)[:, 0] * w.max()
    direct = wi.align(a.positions, b.positions, target_weights=w)
    through = wi.align(a.positions, back, target_weights=back_w)
    assert np.allclose(through.transformation, direct.transformation, atol=1e-9)
    # And into a map again, for the map API.
    assert np.array_equal(wi.LandmarkMap.from_positions(back).positions, b.positions)

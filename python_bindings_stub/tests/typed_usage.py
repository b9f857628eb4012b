"""Checked by mypy --strict against the shipped stubs (ctest python.stubs): the documented uses type-check.

Not collected by pytest (no test_ prefix); it is never run, only type-checked.
"""

import numpy as np
import numpy.typing as npt

import weighted_icp as wi


def contract(path: str, source_xyz: npt.NDArray[np.float64], target_xyz: npt.NDArray[np.float32]) -> float:
    m = wi.LandmarkMap.load(path, min_observations=2)
    positions: npt.NDArray[np.float64] = m.positions
    counts: npt.NDArray[np.int64] = m.observation_counts
    w: npt.NDArray[np.float64] = wi.weights(m, "observations")
    r: wi.AlignmentResult = wi.align(source_xyz, target_xyz, target_weights=w, k=5, max_iterations=150)
    matrix: npt.NDArray[np.float64] = r.transformation
    by_map = wi.align(m, m, strategy="covariance", refine=True, initial_guess=np.eye(4), threads=1)
    s, t, d = wi.weighted_correspondences(source_xyz, positions, w, k=3, max_distance=0.5)
    halves = m.alternate_halves()
    minimaps: list[wi.LandmarkMap] = m.split_into_mini_maps(10)
    e = wi.ate("gt.txt", wi.read_trajectory("est.txt"))
    p = wi.rpe("gt.txt", "est.txt", delta=1.0, unit="s")
    slam = wi.RgbdSlam(wi.Camera.load("fr1"), deterministic=True)
    step = slam.track(np.zeros((480, 640, 3), np.uint8), np.zeros((480, 640), np.uint16), 0.0)
    slam.run("folder", max_frames=5, progress=lambda done, total, status: None)
    xyz, weights = slam.landmarks("covariance")
    return (r.fitness_score + float(matrix[0, 0]) + by_map.time_ms + float(d.sum()) + len(halves[0]) +
            len(minimaps) + float(counts.sum()) + e.rmse + p.translation.rmse + float(xyz.sum() + weights.sum()) +
            float(step.tracking_ms) + len(s) + len(t) + float(slam.trajectory.sum()) + (1 if r.converged else 0) +
            r.iterations)


def mapping(folder: str, vocabulary: str) -> float:
    slam = wi.run_tum(folder, deterministic=True, vocabulary=vocabulary, first_frame=2, max_frames=50)
    loops: list[wi.Loop] = slam.loops
    refused = [c.reason for c in slam.loop_candidates() if c.verdict != "accepted" and c.score > 0.1]
    closed: int = slam.loop_stats["loops_accepted"]
    slam.save_session("a", overwrite=True)
    wi.RgbdSlam("fr1", loop_closure=False).run(folder, first_frame=40)
    merge: wi.SessionMerge = wi.merge_sessions(["a", "b"], min_agreeing_loops=2, max_free_space_violation=0.02,
                                               progress=lambda name, done, total: None)
    second: wi.MergedSession = merge.sessions[1]
    frames = second.trajectory
    return (float(merge.trajectory.sum()) + float(second.world_in_first[0, 3]) + len(merge.map) + closed + len(refused) +
            sum(loop.inliers + float(loop.query_in_match[0, 3]) for loop in loops + merge.loops) +
            (0.0 if frames is None else float(frames.sum())))

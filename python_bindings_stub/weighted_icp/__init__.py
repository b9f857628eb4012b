"""weighted_icp: confidence-weighted ICP for sparse landmark maps, with numpy arrays in and out.

    import weighted_icp as wi
    m = wi.LandmarkMap.load("a.txt", min_observations=2)
    r = wi.align(source_xyz, target_xyz, target_weights=wi.weights(m, "observations"), k=5)
    r.transformation, r.fitness_score, r.iterations, r.converged

The compiled half is weighted_icp._weighted_icp; everything is re-exported here.
See docs/python.md in the source tree.
"""

from ._weighted_icp import (
    AbsoluteTrajectoryError,
    AlignmentResult,
    AteComparison,
    Camera,
    ErrorStatistics,
    LandmarkMap,
    Loop,
    LoopCandidate,
    MergedSession,
    RelativePoseError,
    RgbdSlam,
    SessionMerge,
    TrackResult,
    __version__,
    align,
    align_global,
    ate,
    compare_ate,
    merge_sessions,
    read_trajectory,
    rpe,
    run_tum,
    strategies,
    tum_frames,
    weighted_correspondences,
    weights,
    write_trajectory,
)

__all__ = [
    "AbsoluteTrajectoryError",
    "AlignmentResult",
    "AteComparison",
    "Camera",
    "ErrorStatistics",
    "LandmarkMap",
    "Loop",
    "LoopCandidate",
    "MergedSession",
    "RelativePoseError",
    "RgbdSlam",
    "SessionMerge",
    "TrackResult",
    "__version__",
    "align",
    "align_global",
    "ate",
    "compare_ate",
    "merge_sessions",
    "read_trajectory",
    "rpe",
    "run_tum",
    "strategies",
    "tum_frames",
    "weighted_correspondences",
    "weights",
    "write_trajectory",
]

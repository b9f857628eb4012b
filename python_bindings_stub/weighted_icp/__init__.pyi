"""Type stubs of weighted_icp (the compiled module weighted_icp._weighted_icp, re-exported)."""

import os
from typing import Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_PathLike = Union[str, "os.PathLike[str]"]
_FloatArray = npt.NDArray[np.float64]
_Points = Union["LandmarkMap", npt.NDArray[np.float64], npt.NDArray[np.float32]]
_TrajectoryLike = Union[_PathLike, npt.NDArray[np.float64], Tuple[npt.ArrayLike, npt.ArrayLike]]

class LandmarkMap:
    """A landmark map: frame poses and, per landmark, position, covariance and observations."""

    def __init__(self) -> None: ...
    @staticmethod
    def load(path: _PathLike, min_observations: int = 0) -> LandmarkMap:
        """Reads a map in the paper's format; ValueError naming file and line when malformed."""
    @staticmethod
    def from_positions(positions: npt.ArrayLike, covariances: Optional[npt.ArrayLike] = None) -> LandmarkMap:
        """A map of bare landmarks from an (N, 3) array and optional (N, 3, 3) covariances."""
    def save(self, path: _PathLike) -> None:
        """Writes the map in the paper's format, atomically."""
    def copy(self) -> LandmarkMap:
        """An independent copy."""
    def __len__(self) -> int: ...
    @property
    def positions(self) -> _FloatArray:
        """(N, 3) float64 landmark positions."""
    @property
    def covariances(self) -> _FloatArray:
        """(N, 3, 3) float64 position covariances."""
    @property
    def observation_counts(self) -> npt.NDArray[np.int64]:
        """(N,) int64 observation counts."""
    @property
    def ids(self) -> npt.NDArray[np.uint64]:
        """(N,) uint64 landmark ids."""
    @property
    def mean_observation_distances(self) -> _FloatArray:
        """(N,) float64 mean distance to the observing cameras."""
    @property
    def frames(self) -> Dict[int, _FloatArray]:
        """{frame id: (4, 4) camera-to-world pose}."""
    @property
    def frame_ids(self) -> npt.NDArray[np.uint64]:
        """(F,) uint64 frame ids, ascending."""
    def with_min_observations(self, min_observations: int) -> LandmarkMap:
        """The landmarks observed at least min_observations times."""
    def mini_map(self, first: int, last: int) -> LandmarkMap:
        """The mini-map of frames [first, last]."""
    def split_into_mini_maps(self, frames_per_minimap: int) -> List[LandmarkMap]:
        """Consecutive mini-maps of frames_per_minimap frames each."""
    def alternate_halves(self) -> Tuple[LandmarkMap, LandmarkMap]:
        """Two maps with alternate landmarks, related by the identity."""
    def transform(self, matrix: npt.ArrayLike) -> None:
        """Moves the map in place by a (4, 4) rigid motion."""

def weights(map: LandmarkMap, strategy: str) -> _FloatArray:
    """(N,) weights: 'base', 'covariance', 'observations' or 'mean-distance'."""

def strategies() -> List[str]:
    """The weight strategies' names."""

class AlignmentResult:
    """What align() found, as wicp_align --json reports it."""

    @property
    def transformation(self) -> _FloatArray:
        """(4, 4) source -> target."""
    @property
    def fitness_score(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def refine_iterations(self) -> int: ...
    @property
    def converged(self) -> bool: ...
    @property
    def stopped_at_iteration_limit(self) -> bool: ...
    @property
    def correspondences(self) -> int: ...
    @property
    def time_ms(self) -> float: ...
    @property
    def degenerate(self) -> bool: ...
    @property
    def reason(self) -> str: ...

def align(
    source: _Points,
    target: _Points,
    target_weights: Optional[npt.ArrayLike] = None,
    k: int = 5,
    strategy: Optional[str] = None,
    max_iterations: int = 150,
    max_correspondence_distance: Optional[float] = None,
    refine: bool = False,
    initial_guess: Optional[npt.ArrayLike] = None,
    threads: int = 0,
) -> AlignmentResult:
    """Aligns source onto target with the confidence-weighted ICP (wicp_align's numbers)."""

def align_global(
    source: _Points,
    target: _Points,
    target_weights: Optional[npt.ArrayLike] = None,
    k: int = 5,
    strategy: Optional[str] = None,
    max_iterations: int = 150,
    up_axis: Union[str, Sequence[float]] = "auto",
    threads: int = 0,
) -> AlignmentResult:
    """Aligns source onto target from any start (wicp_align --global); a source much larger than the
    target is aligned the other way, weighted by its own weights, the result inverted."""

def weighted_correspondences(
    source: _Points,
    target: _Points,
    weights: Optional[npt.ArrayLike] = None,
    k: int = 5,
    max_distance: Optional[float] = None,
    threads: int = 0,
) -> Tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], _FloatArray]:
    """(source_idx, target_idx, sq_dist) of the weighted correspondence rule."""

class ErrorStatistics:
    """RMSE, mean, median and maximum."""

    @property
    def rmse(self) -> float: ...
    @property
    def mean(self) -> float: ...
    @property
    def median(self) -> float: ...
    @property
    def max(self) -> float: ...

class AbsoluteTrajectoryError:
    """The ATE as evaluate_ate.py computes it."""

    @property
    def pairs(self) -> int: ...
    @property
    def translation(self) -> ErrorStatistics: ...
    @property
    def rmse(self) -> float: ...
    @property
    def alignment(self) -> _FloatArray: ...

class RelativePoseError:
    """The RPE as evaluate_rpe.py --fixed_delta computes it."""

    @property
    def pairs(self) -> int: ...
    @property
    def translation(self) -> ErrorStatistics: ...
    @property
    def rotation_deg(self) -> ErrorStatistics: ...

class AteComparison:
    """Two estimates' ATE compared pose by pose (wicp_evaluate --versus)."""

    @property
    def first(self) -> AbsoluteTrajectoryError: ...
    @property
    def second(self) -> AbsoluteTrajectoryError: ...
    @property
    def common_poses(self) -> int: ...
    @property
    def first_rmse(self) -> float: ...
    @property
    def second_rmse(self) -> float: ...
    @property
    def error_correlation(self) -> float: ...
    @property
    def resamples(self) -> int: ...
    @property
    def first_lower_fraction(self) -> float: ...

def ate(gt: _TrajectoryLike, est: _TrajectoryLike, max_difference: float = 0.02) -> AbsoluteTrajectoryError:
    """Absolute trajectory error of est against gt."""

def compare_ate(
    gt: _TrajectoryLike,
    first: _TrajectoryLike,
    second: _TrajectoryLike,
    max_difference: float = 0.02,
    resamples: int = 2000,
) -> AteComparison:
    """Is first's ATE lower than second's beyond the scatter of the poses?"""

def rpe(gt: _TrajectoryLike, est: _TrajectoryLike, delta: float = 1.0, unit: str = "s") -> RelativePoseError:
    """Relative pose error over pose pairs delta apart."""

def read_trajectory(path: _PathLike) -> _FloatArray:
    """A TUM trajectory file as (N, 8) rows."""

def write_trajectory(trajectory: _TrajectoryLike, path: _PathLike) -> None:
    """Writes a trajectory in TUM format, atomically."""

class Camera:
    """A pinhole RGB-D camera."""

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    depth_factor: float
    distortion: List[float]
    @property
    def depth_size(self) -> Tuple[int, int]:
        """(width, height) of the depth images: the depth camera's own or the colour images'."""
    def __init__(self) -> None: ...
    @staticmethod
    def load(spec: str) -> Camera:
        """'fr1', 'fr2', 'fr3' or a camera YAML."""
    @staticmethod
    def tum(freiburg: int) -> Camera:
        """TUM RGB-D freiburg 1, 2 or 3."""

class TrackResult:
    """What track() did with one frame."""

    @property
    def status(self) -> str: ...
    @property
    def reason(self) -> str: ...
    @property
    def has_pose(self) -> bool: ...
    @property
    def pose_predicted(self) -> bool: ...
    @property
    def pose(self) -> Optional[_FloatArray]: ...
    @property
    def keyframe(self) -> bool: ...
    @property
    def refused_by_quality_gate(self) -> bool: ...
    @property
    def features(self) -> int: ...
    @property
    def matches(self) -> int: ...
    @property
    def inliers(self) -> int: ...
    @property
    def tracking_ms(self) -> float: ...

class Loop:
    """A verified loop: the query keyframe's camera in the match keyframe's (x_match = query_in_match @ x_query)."""

    @property
    def query_session(self) -> int: ...
    @property
    def query(self) -> int: ...
    @property
    def query_timestamp(self) -> float: ...
    @property
    def match_session(self) -> int: ...
    @property
    def match(self) -> int: ...
    @property
    def match_timestamp(self) -> float: ...
    @property
    def query_in_match(self) -> _FloatArray:
        """(4, 4) float64."""
    @property
    def inliers(self) -> int: ...
    @property
    def fitness(self) -> float: ...
    @property
    def score(self) -> float: ...
    @property
    def used(self) -> bool: ...

class LoopCandidate:
    """A keyframe place recognition proposed as a revisit, and what became of it (loop_candidates.txt)."""

    @property
    def query(self) -> int: ...
    @property
    def match(self) -> int: ...
    @property
    def edge_match(self) -> int: ...
    @property
    def query_timestamp(self) -> float: ...
    @property
    def match_timestamp(self) -> float: ...
    @property
    def score(self) -> float: ...
    @property
    def verdict(self) -> str: ...
    @property
    def reason(self) -> str: ...

class RgbdSlam:
    """The RGB-D SLAM (wicp_rgbd_slam's): tracking, bundle adjustment, loop closing."""

    def __init__(
        self,
        camera: Union[Camera, str] = "fr1",
        minimap_keyframes: int = 10,
        matcher: str = "lsh",
        quality_gate: bool = True,
        deterministic: bool = False,
        options: Dict[str, str] = ...,
        loop_closure: bool = True,
        vocabulary: Optional[_PathLike] = None,
    ) -> None: ...
    def track(
        self, rgb: npt.NDArray[np.uint8], depth: npt.NDArray[np.generic], timestamp: float, bgr: bool = False
    ) -> TrackResult:
        """Tracks one frame (the GIL released)."""
    def run(
        self,
        folder: str,
        max_frames: int = 0,
        progress: Optional[Callable[[int, int, str], object]] = None,
        first_frame: int = 0,
    ) -> None:
        """Tracks frames first_frame to max_frames - 1 of a TUM folder, then finish()."""
    def finish(self) -> None:
        """Waits for the pending bundle adjustment and loop closing."""
    def save_session(self, folder: _PathLike, overwrite: bool = False) -> None:
        """finish(), then writes the session folder merge_sessions() reads."""
    @property
    def loops(self) -> List[Loop]: ...
    def loop_candidates(self) -> List[LoopCandidate]:
        """finish(), then every candidate place recognition proposed, with its verdict."""
    @property
    def loop_stats(self) -> Dict[str, int]: ...
    @property
    def camera(self) -> Camera: ...
    @property
    def trajectory(self) -> _FloatArray:
        """(N, 8) TUM rows."""
    @property
    def ground_truth(self) -> Optional[_FloatArray]: ...
    @property
    def keyframes(self) -> Tuple[npt.NDArray[np.uint64], _FloatArray, _FloatArray]: ...
    @property
    def tracking_ms(self) -> _FloatArray: ...
    def session_map(self) -> LandmarkMap: ...
    def mini_maps(self) -> List[LandmarkMap]: ...
    def landmarks(self, strategy: str = "covariance") -> Tuple[_FloatArray, _FloatArray]: ...

class MergedSession:
    """One session's part of merge_sessions()."""

    @property
    def folder(self) -> str: ...
    @property
    def merged(self) -> bool: ...
    @property
    def linked_to(self) -> int: ...
    @property
    def loops_found(self) -> int: ...
    @property
    def loops_agreeing(self) -> int: ...
    @property
    def loops_with_link_prior(self) -> int: ...
    @property
    def free_space_judged(self) -> int: ...
    @property
    def free_space_violation(self) -> float: ...
    @property
    def free_space_rigid_violation(self) -> float: ...
    @property
    def free_space_optimised(self) -> bool: ...
    @property
    def world_in_first(self) -> _FloatArray:
        """(4, 4) float64."""
    @property
    def trajectory(self) -> Optional[_FloatArray]: ...

class SessionMerge:
    """What merge_sessions() found."""

    @property
    def sessions(self) -> List[MergedSession]: ...
    @property
    def loops(self) -> List[Loop]: ...
    @property
    def trajectory(self) -> _FloatArray:
        """(N, 8) TUM rows of every merged session's frames."""
    @property
    def map(self) -> LandmarkMap: ...

def merge_sessions(
    sessions: Sequence[_PathLike],
    vocabulary: Optional[_PathLike] = None,
    min_agreeing_loops: int = 2,
    max_free_space_violation: float = 0.02,
    loops_with_link_prior: bool = True,
    progress: Optional[Callable[[str, int, int], object]] = None,
) -> SessionMerge:
    """Merges session folders into the first one's frame, as wicp_merge."""

def tum_frames(folder: str) -> List[Tuple[float, str, str]]:
    """[(timestamp, rgb path, depth path)] of a TUM folder, associated as run() does."""

def run_tum(
    folder: str,
    camera: Optional[Union[Camera, str]] = None,
    max_frames: int = 0,
    progress: Optional[Callable[[int, int, str], object]] = None,
    minimap_keyframes: int = 10,
    deterministic: bool = False,
    options: Dict[str, str] = ...,
    loop_closure: bool = True,
    vocabulary: Optional[_PathLike] = None,
    first_frame: int = 0,
) -> RgbdSlam:
    """A new RgbdSlam run over a TUM folder."""

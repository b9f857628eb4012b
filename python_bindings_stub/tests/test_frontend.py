"""RgbdSlam from Python: a TUM folder, frame by frame (the same poses), progress, errors."""

from pathlib import Path
from typing import List, Tuple

import numpy as np
import pytest

import weighted_icp as wi

FRAMES = 8


def read_frames(folder: Path, count: int) -> List[Tuple[float, np.ndarray, np.ndarray]]:
    """(timestamp, RGB uint8, raw depth uint16) of the first frames, paired as run() pairs them."""
    image = pytest.importorskip("PIL.Image", reason="Pillow (python3-pil) reads the PNGs in this test")
    frames = []
    for t, rgb_path, depth_path in wi.tum_frames(str(folder))[:count]:
        rgb = np.asarray(image.open(rgb_path).convert("RGB"))
        raw = np.asarray(image.open(depth_path)).astype(np.uint16)
        frames.append((t, rgb, raw))
    return frames


def test_track_frame_by_frame_equals_run(tum_folder: Path) -> None:
    whole = wi.RgbdSlam("fr1", deterministic=True)
    calls = []
    whole.run(str(tum_folder), max_frames=FRAMES, progress=lambda done, total, status: calls.append((done, total)))
    assert calls[-1] == (FRAMES, FRAMES) and len(calls) == FRAMES

    stepwise = wi.RgbdSlam(wi.Camera.tum(1), deterministic=True)
    results = [stepwise.track(rgb, depth, t) for t, rgb, depth in read_frames(tum_folder, FRAMES)]
    stepwise.finish()
    assert results[0].status == "initialized" and results[0].has_pose
    assert np.array_equal(whole.trajectory, stepwise.trajectory)
    assert whole.trajectory.shape[1] == 8
    ids, stamps, poses = whole.keyframes
    assert len(ids) == len(stamps) == len(poses) >= 1 and poses.shape[1:] == (4, 4)
    xyz, weights = whole.landmarks("observations")
    assert xyz.shape[0] == weights.shape[0] == len(whole.session_map()) > 0
    assert whole.ground_truth is not None
    assert wi.ate(whole.ground_truth, whole.trajectory).pairs >= 3


def test_run_tum_guesses_the_camera_and_stops_on_a_callback_error(tum_folder: Path) -> None:
    def stop(done: int, total: int, status: str) -> None:
        if done == 2:
            raise KeyboardInterrupt("stop here")

    with pytest.raises(KeyboardInterrupt):
        wi.run_tum(str(tum_folder), max_frames=FRAMES, progress=stop)
    slam = wi.run_tum(str(tum_folder), max_frames=3, deterministic=True)
    assert slam.camera.fx == pytest.approx(517.306408)
    assert len(slam.tracking_ms) == 3


def test_run_tum_names_a_missing_folder_and_reads_a_folders_camera_file(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="kinn: no such folder"):
        wi.run_tum(str(tmp_path / "kinn"))
    with pytest.raises(ValueError, match="pass camera="):
        wi.run_tum(str(tmp_path))  # exists, but neither camera.yaml nor a TUM name
    (tmp_path / "camera.yaml").write_text(
        "%YAML:1.0\nfx: 585.\nfy: 585.\ncx: 320.\ncy: 240.\nk1: 0.\nk2: 0.\np1: 0.\np2: 0.\nk3: 0.\n"
        "width: 640\nheight: 480\ndepth_factor: 1000.\n")
#The folder's camera is read (as wicp_rgbd_slam reads it); it has no frames, which is the next error.
    with pytest.raises(RuntimeError, match="rgb.txt"):
        wi.run_tum(str(tmp_path))


def test_track_refuses_wrong_images() -> None:
    slam = wi.RgbdSlam("fr1")
    rgb = np.zeros((480, 640, 3), dtype=np.uint8)
    depth = np.zeros((480, 640), dtype=np.uint16)
    with pytest.raises(ValueError, match="rgb must be"):
        slam.track(rgb.astype(np.float32), depth, 0.0)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="rgb is 320x240"):
        slam.track(rgb[:240, :320], depth, 0.0)
    with pytest.raises(ValueError, match="depth must be"):
        slam.track(rgb, depth.astype(np.int32), 0.0)
    with pytest.raises(ValueError, match="camera"):
        wi.RgbdSlam(camera=5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="depth is 320x240 but the camera's depth images are 640x480"):
        slam.track(rgb, depth[:240, :320], 0.0)
#A black frame without depth is not an error : the tracker reports it.
    assert not slam.track(rgb, depth, 0.0).has_pose


def test_a_depth_camera_of_its_own_size_takes_depth_of_that_size(tmp_path: Path) -> None:
    camera_file = tmp_path / "camera.yaml"
    camera_file.write_text(
        "%YAML:1.0\nfx: 525.\nfy: 525.\ncx: 319.5\ncy: 239.5\nk1: 0\nk2: 0\np1: 0\np2: 0\nk3: 0\n"
        "width: 640\nheight: 480\ndepth_factor: 1000.\ndepth_fx: 262.5\ndepth_fy: 262.5\ndepth_cx: 159.5\n"
        "depth_cy: 119.5\ndepth_tx: 0.025\ndepth_ty: 0\ndepth_tz: 0\ndepth_rx: 0\ndepth_ry: 0\ndepth_rz: 0\n"
        "depth_width: 320\ndepth_height: 240\n"
    )
    camera = wi.Camera.load(str(camera_file))
    assert camera.depth_size == (320, 240)
    assert wi.Camera.tum(1).depth_size == (640, 480)
    slam = wi.RgbdSlam(camera)
    rgb = np.zeros((480, 640, 3), dtype=np.uint8)
    with pytest.raises(ValueError, match="depth is 640x480 but the camera's depth images are 320x240"):
        slam.track(rgb, np.zeros((480, 640), dtype=np.uint16), 0.0)
    assert not slam.track(rgb, np.zeros((240, 320), dtype=np.uint16), 0.0).has_pose


def test_options_choose_the_papers_techniques_by_the_tools_names(tum_folder: Path) -> None:
    default = wi.run_tum(str(tum_folder), max_frames=4, deterministic=True)
    spelled_out = wi.run_tum(
        str(tum_folder), max_frames=4, deterministic=True, options={"descriptor": "orb", "pnp": "ap3p"}
    )
    assert np.array_equal(default.trajectory, spelled_out.trajectory)
    other = wi.run_tum(str(tum_folder), max_frames=4, deterministic=True, options={"descriptor": "modified-brief"})
    assert other.trajectory.shape == default.trajectory.shape
    assert not np.array_equal(default.trajectory, other.trajectory)
    with pytest.raises(ValueError, match=r"options: pnp: unknown PnP method 'epnp' \(expected ap3p or iterative\)"):
        wi.RgbdSlam("fr1", options={"pnp": "epnp"})
    with pytest.raises(ValueError, match="options: unknown front-end option 'pnp_method' \\(expected matcher, "):
        wi.RgbdSlam("fr1", options={"pnp_method": "ap3p"})


def test_the_constructors_help_names_every_option_key() -> None:
    doc = wi.RgbdSlam.__init__.__doc__ or ""
    listed = doc.split("(keys: ")[1].split(";")[0].split(", ")
    assert {"gate-free-retry", "motion-timing", "keyframe-before-loss", "feature-smoothing"} <= set(listed)
    for key in listed:
#A key the front end knows : its value is what is refused, not the key.
        with pytest.raises(ValueError, match=f"options: {key}: "):
            wi.RgbdSlam("fr1", options={key: "no-such-value"})

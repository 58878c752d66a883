"""The camera's view from Python: static references and the scale from the scene give what
``host-harness track`` gives (the same library call), and bad settings are named."""

import csv

import numpy as np
import pytest

import vibcam


@pytest.fixture(scope="module")
def shaken(tmp_path_factory, harness):
    """Half a minute of the shear frame seen by a camera that shakes, four references."""
    d = tmp_path_factory.mktemp("view") / "shaken"
    r = harness(
        "simulate-field", "--render", "--minutes", "0.5", "--references", "4",
        "--shake-px", "0.5", "--roll-deg", "0.2", "--out", str(d),
    )
    assert r.returncode == 0, r.stderr
    return d


def _column(path, col):
    with open(path) as f:
        return [float(r[col]) if r[col] else np.nan for r in csv.DictReader(f)]


def test_references_and_world_match_the_command_line(shaken, harness, tmp_path):
    out = tmp_path / "t"
    r = harness(
        "track", "--frames", str(shaken / "frames"), "--fps", "60",
        "--points", str(shaken / "points.csv"), "--threshold", "127", "--tracker", "weighted",
        "--reference", str(shaken / "references.csv"), "--world", str(shaken / "world.csv"),
        "--out", str(out),
    )
    assert r.returncode == 0, r.stderr
    t = vibcam.track(
        str(shaken / "frames"), str(shaken / "points.csv"), fps=60, threshold=127,
        tracker="weighted", reference=str(shaken / "references.csv"),
        world=str(shaken / "world.csv"), return_flags=True,
    )
    k = t.positions.shape[1]
    cx = np.array(_column(out / "displacement.csv", "cx")).reshape(-1, k)
    raw = np.array(_column(out / "displacement.csv", "cx_raw")).reshape(-1, k)
    mm = np.array(_column(out / "displacement.csv", "disp_mm")).reshape(-1, k)
    # the CSV holds f32 text: the same numbers
    assert np.allclose(t.positions[..., 0], cx, atol=1e-4)
    assert np.allclose(t.raw_positions[..., 0], raw, atol=1e-4)
    assert np.allclose(t.displacement_mm, mm, atol=1e-6)
    dx = np.array(_column(out / "camera_motion.csv", "dx_px"))
    assert np.allclose(t.camera_motion[:, 0], dx, atol=1e-9)
    assert "camera motion: similarity from 4 reference(s)" in t.view_report
    assert "would be off by" in t.view_report


def test_view_settings_are_named(shaken):
    frames = str(shaken / "frames")
    pts = str(shaken / "points.csv")
    with pytest.raises(vibcam.InputError, match="camera_model is the model"):
        vibcam.track(frames, pts, fps=60, threshold=127, camera_model="similarity")
    with pytest.raises(vibcam.InputError, match="mm_per_px and target_size_mm: one scale only"):
        vibcam.analyze(frames, pts, fps=60, threshold=127, mm_per_px=1.0, target_size_mm=20)
    with pytest.raises(vibcam.InputError, match="world: 3 point"):
        vibcam.track(
            frames, pts, fps=60, threshold=127,
            world=[(0, 0, 0, 0), (10, 0, 5, 0), (0, 10, 0, 5)],
        )
    with pytest.raises(vibcam.InputError, match="scale: target 9"):
        vibcam.track(frames, pts, fps=60, threshold=127, scale=(1, 9, 100.0))


def test_analyze_takes_the_cameras_motion_out(shaken):
    r = vibcam.analyze(
        str(shaken / "frames"), str(shaken / "points.csv"), fps=60, threshold=127,
        tracker="weighted", reference=str(shaken / "references.csv"),
    )
    assert r.camera_motion is not None and r.camera_motion.shape[1] == 4
    assert "camera motion: similarity" in r.report
    assert abs(np.nanstd(r.camera_motion[:, 0]) - 0.5) < 0.1

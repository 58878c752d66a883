"""open_frames and the array inputs: frames read as an independent decoder (PIL) reads them,
arrays taken as the files are, bad arrays refused, and the GIL released while working."""

import threading
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import vibcam


def test_open_frames_reads_what_pil_reads(recording):
    reader = vibcam.open_frames(recording / "frames")
    assert reader.count == 1200 and reader.fps is None
    for i, frame in enumerate(reader):
        if i in (0, 1, 599, 1199):
            want = np.asarray(Image.open(recording / "frames" / f"frame_{i:05d}.png"))
            np.testing.assert_array_equal(frame, want)
            assert reader.label.endswith(f"frame_{i:05d}.png")
    assert i == 1199


def test_open_frames_of_a_multipage_tiff_and_16_bit(tmp_path):
    rng = np.random.default_rng(5)
    pages = [rng.integers(0, 65535, (12, 17), dtype=np.uint16) for _ in range(3)]
    path = tmp_path / "stack.tif"
    Image.fromarray(pages[0]).save(path, save_all=True,
                                   append_images=[Image.fromarray(p) for p in pages[1:]])
    got = list(vibcam.open_frames(path))
    assert len(got) == 3
    for g, p in zip(got, pages):
        assert g.dtype == np.uint16
        np.testing.assert_array_equal(g, p)


def test_colour_frames_are_their_luma(tmp_path):
    rng = np.random.default_rng(8)
    rgb = rng.integers(0, 256, (2, 9, 13, 3), dtype=np.uint8)
    for k, f in enumerate(rgb):
        Image.fromarray(f).save(tmp_path / f"c_{k}.png")
    from_files = np.stack(list(vibcam.open_frames(tmp_path)))
    want = np.rint(rgb @ np.array([0.299, 0.587, 0.114])).astype(np.uint8)
    np.testing.assert_array_equal(from_files, want)
    # an array of colour frames is taken the same way
    c1 = vibcam.centroid(rgb[0], 100, "weighted")
    c2 = vibcam.centroid(want[0], 100, "weighted")
    assert (c1.x, c1.y, c1.pixels) == (c2.x, c2.y, c2.pixels)


def test_centroid_of_an_array_is_the_closed_form():
    f = np.zeros((20, 30), np.uint8)
    f[5:9, 10:14] = 200
    f[7, 20] = 255
    c = vibcam.centroid(f, 100)
    w = (f > 100).astype(float)
    ys, xs = np.indices(f.shape)
    # the firmware divides exact integer moments in f32
    assert c.x == np.float32((w * xs).sum() / w.sum())
    assert c.y == np.float32((w * ys).sum() / w.sum())
    assert c.pixels == 17 and "saturated" in c.flags
    c = vibcam.centroid(f, 100, "weighted", roi=(8, 3, 8, 8))
    w = np.where(f > 100, f.astype(float) - 100, 0)[3:11, 8:16]
    ys, xs = np.indices(w.shape)
    assert abs(c.x - ((w * xs).sum() / w.sum() + 8)) < 1e-5
    assert abs(c.y - ((w * ys).sum() / w.sum() + 3)) < 1e-5
    empty = vibcam.centroid(np.zeros((4, 4), np.uint8), 10)
    assert not empty.found and "empty" in empty.flags


def test_bad_arrays_are_refused():
    with pytest.raises(vibcam.InputError, match="uint8 or uint16"):
        vibcam.centroid(np.zeros((4, 4)), 1)
    with pytest.raises(vibcam.InputError, match="shape"):
        vibcam.track(np.zeros((2, 3, 4, 5, 6), np.uint8), targets=1, threshold=1)
    with pytest.raises(vibcam.InputError, match="fps is needed"):
        vibcam.analyze(np.zeros((100, 8, 8), np.uint8), targets=1, threshold=1)
    with pytest.raises(vibcam.InputError, match="lk"):
        vibcam.track(np.zeros((3, 8, 8), np.uint8), targets=1, tracker="lk")


def test_the_gil_is_released_while_analysing(recording):
    frames = np.stack(list(vibcam.open_frames(recording / "frames")))
    t0 = time.perf_counter()
    vibcam.analyze(frames, fps=120, threshold=127, targets=5)
    alone = time.perf_counter() - t0
    worker = threading.Thread(
        target=vibcam.analyze, args=(frames,),
        kwargs=dict(fps=120, threshold=127, targets=5),
    )
    gaps, last = [], time.perf_counter()
    worker.start()
    while worker.is_alive():
        now = time.perf_counter()
        gaps.append(now - last)
        last = now
    # holding the GIL, the call would stop this loop for its whole duration
    assert max(gaps) < 0.5 * alone, (max(gaps), alone)


def test_every_refused_argument_is_an_input_error_naming_it(recording):
    # each of these raised Python's OverflowError, TypeError or ValueError from a conversion,
    # or (a threshold of 1.7) ran silently with another value
    f = np.zeros((8, 8), np.uint8)
    frames = np.zeros((3, 8, 8), np.uint8)
    cases = [
        (lambda: vibcam.centroid(f, -1), "threshold = -1"),
        (lambda: vibcam.centroid(f, 1.7), "threshold = 1.7"),
        (lambda: vibcam.centroid(f, float("nan")), "threshold = nan"),
        (lambda: vibcam.centroid(f, 10, roi=(0, 0, -2, 3)), r"roi\[2\] = -2"),
        (lambda: vibcam.centroid(f, 10, roi=(0, 0, 2)), "roi = "),
        (lambda: vibcam.track(frames, [(4, 4, -5, 5)], threshold=1), r"points\[0\].w = -5"),
        (lambda: vibcam.track(frames, [(4, 4, 5.5, 5)], threshold=1), r"points\[0\].w = 5.5"),
        (lambda: vibcam.track(frames, [(4, 4, 5, 5)], tracker="lk", search_px=2.5), "search_px = 2.5"),
        (lambda: vibcam.track(frames, targets=1, threshold=1, fps=float("nan")), "fps = nan"),
        (lambda: vibcam.track(frames, targets=1, threshold=1, gate_px=-1), "gate_px = -1"),
        (lambda: vibcam.track(frames, targets=99, threshold=1), "targets = 99"),
        (lambda: vibcam.frf(np.zeros((4, 100)), np.zeros(100), 10.0), "x: a 1-D array"),
        (lambda: vibcam.frf(np.zeros(100), np.zeros(100), float("inf")), "fs = inf"),
        (lambda: vibcam.frf(np.zeros(100), np.zeros(100), 10.0, nperseg=-3), "nperseg = -3"),
        (lambda: vibcam.upsample(["a", "b"], 1.0, 2.0), "x: not an array of numbers"),
        (lambda: vibcam.analyze(frames, targets=1, threshold=1, fps=60, bands=[(5, 2)]), r"bands\[0\]"),
        (lambda: vibcam.open_frames(recording / "frames", frame_range="5..2"), "comes before"),
        (lambda: vibcam.open_frames(recording / "frames", frame_range=(1, 2)), "frame_range = "),
    ]
    for call, needle in cases:
        with pytest.raises(vibcam.InputError, match=needle):
            call()
    # settings that do not go together are refused by the library's checks (the command line's
    # rules), named as Python's arguments, never as the command line's flags
    pair_cases = [
        (lambda: vibcam.track(frames, [(4, 4, 5, 5)], threshold=1, gate_px=3), "gate_px is the blobs' gate of targets"),
        (lambda: vibcam.track(frames, [(4, 4, 5, 5)], tracker="lk", threshold=3), "threshold with tracker lk"),
        (lambda: vibcam.track(frames, targets=1, threshold="auto"), "threshold auto: only with points"),
        (lambda: vibcam.track(frames, targets=2, tracker="lk"), "tracker lk follows the windows of points"),
        (lambda: vibcam.track(frames, [(4, 4, 5, 5)], threshold=1, roi=(0, 0, 4, 4)), "roi with points"),
        (lambda: vibcam.analyze(frames, targets=1, threshold=1, fps=60, bands=[(5, 31)]), "bands 5-31: reaches above"),
    ]
    for call, needle in pair_cases:
        with pytest.raises(vibcam.InputError, match=needle) as e:
            call()
        assert "--" not in str(e.value), str(e.value)
    # a frame range of a sequence reads those frames, labelled as in the whole sequence
    reader = vibcam.open_frames(recording / "frames", frame_range="3..5")
    assert reader.count == 3
    got = list(reader)
    assert len(got) == 3 and reader.label.endswith("frame_00004.png"), reader.label


def test_region_points_are_picks_and_their_defaults(tmp_path, harness):
    # the real striped beam of tests/data (pyidi's Photron showcase, MIT): the same points
    # as `pick --region`, the same defaults, and the stripes' texture fixes y, not x
    from conftest import ROOT
    from test_package import cli_defaults

    cih = ROOT / "tests" / "data" / "real" / "pyidi-showcase" / "data_showcase.cih"
    frame = next(iter(vibcam.open_frames(cih)))
    region = "0,0;640,0;640,40;0,40"
    points = tmp_path / "p.csv"
    r = harness("pick", "--frames", str(cih), "--region", region, "--spacing", "4",
                "--direction", "y", "--points-out", str(points), "--out",
                str(tmp_path / "p.html"))
    assert r.returncode == 0, r.stderr
    rows = np.loadtxt(points, delimiter=",", skiprows=1)
    xy = vibcam.region_points(frame, region, spacing=4, direction="y")
    assert xy.shape == (len(rows), 2) and len(rows) >= 500
    assert np.array_equal(xy, rows[:, 1:3])
    assert len(vibcam.region_points(frame, region, spacing=4)) * 10 < len(xy)
    import inspect

    flags = cli_defaults(harness, "pick")
    params = inspect.signature(vibcam.region_points).parameters
    for name in ["spacing", "window_px", "min_texture", "direction"]:
        d = params[name].default
        assert (float(flags[name]) == d) if not isinstance(d, str) else flags[name] == d, name
    for call, needle in [
        (lambda: vibcam.region_points(frame, region, spacing=0.5), "^spacing 0.5"),
        (lambda: vibcam.region_points(frame, region, window_px=4), "^window_px = 4"),
        (lambda: vibcam.region_points(frame, region, min_texture=2), "^min_texture 2"),
        (lambda: vibcam.region_points(frame, "0,0;1,1"), "^region: a polygon needs"),
        (lambda: vibcam.region_points(frame, region, direction="up"), "^direction: `up`"),
    ]:
        with pytest.raises(vibcam.InputError, match=needle):
            call()


def test_a_dense_field_gives_its_modes_and_each_modes_video(tmp_path, harness):
    # the speckled beam (its shapes known at every pixel): hundreds of points from its region,
    # the modes on reference channels, a magnified video per mode written where asked
    beam = tmp_path / "beam"
    r = harness("simulate-field", "--render", "--scene", "speckle", "--minutes", "0.134",
                "--fps", "50", "--exposure-ms", "1", "--out", str(beam))
    assert r.returncode == 0, r.stderr
    frame = next(iter(vibcam.open_frames(beam / "frames", fps=50)))
    region = (beam / "region.txt").read_text().strip()
    xy = vibcam.region_points(frame, region, spacing=3, window_px=11, direction="y")
    assert len(xy) >= 500
    points = tmp_path / "points.csv"
    points.write_text("target,x,y,w,h\n" + "".join(
        f"{i + 1},{x},{y},11,11\n" for i, (x, y) in enumerate(xy)))
    res = vibcam.analyze(beam / "frames", points, fps=50, tracker="lk",
                         magnify_dir=tmp_path / "videos")
    assert res.shapes.shape[1] == len(xy)
    assert any("reference channels" in n for n in res.notes)
    ssi = [i for i, m in enumerate(res.modes["method"]) if m == "ssi"]
    assert len(ssi) == 3
    for i in ssi:
        r_mode = res.modes["mode"][i]
        truth = np.sin(r_mode * np.pi * (xy[:, 0] - 16.0) / 288.0)
        s = res.shapes[i]
        mac = abs(np.vdot(truth, s)) ** 2 / (np.vdot(s, s).real * truth @ truth)
        assert mac >= 0.99, (r_mode, mac)
    assert [Path(v).name for v in res.videos] == [f"magnified_ssi_{k}.webm" for k in (1, 2, 3)]
    assert all(Path(v).stat().st_size > 1000 for v in res.videos)
    assert res.html.count('<video class="magnified"') == 3

"""The package against the command line on the same data: the same library runs behind both,
so the numbers must be equal, to the last digit the CSV files print (every float is written
as its shortest round-trip text, so parsing it gives the same float back)."""

import csv

import numpy as np
import pytest

import vibcam


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def cell(v):
    """A CSV cell as the package gives it: ``None`` when empty, a float when numeric."""
    if v == "":
        return None
    try:
        return float(v)
    except ValueError:
        return v


def same_rows(ours, theirs, what):
    assert len(ours) == len(theirs), what
    for i, (a, b) in enumerate(zip(ours, theirs)):
        assert list(a) == list(b.keys()), f"{what}: columns"
        for k in b:
            want, got = cell(b[k]), a[k]
            if isinstance(want, float) and got is not None and not isinstance(got, str):
                assert float(got) == want, f"{what} row {i + 2} `{k}`: {got!r} vs {want!r}"
            else:
                assert got == want, f"{what} row {i + 2} `{k}`: {got!r} vs {want!r}"


@pytest.mark.parametrize(
    "flags,kwargs",
    [
        (["--threshold", "127", "--targets", "5"], dict(threshold=127, targets=5)),
        (["--threshold", "127", "--targets", "5", "--mode", "weighted", "--mm-per-px",
          "0.1266", "--nperseg", "512"],
         dict(threshold=127, targets=5, tracker="weighted", mm_per_px=0.1266, nperseg=512)),
    ],
    ids=["binary", "weighted-mm"],
)
def test_analyze_equals_the_command_line(recording, harness, tmp_path, flags, kwargs):
    out = tmp_path / "cli"
    r = harness("analyze", "--frames", str(recording / "frames"), "--fps", "120", *flags,
                "--out", str(out))
    assert r.returncode == 0, r.stderr
    res = vibcam.analyze(recording / "frames", fps=120, **kwargs)
    same_rows(res.modes_rows(), rows(out / "modes.csv"), "modes.csv")
    same_rows(res.shapes_rows(), rows(out / "shapes.csv"), "shapes.csv")
    # the five modes of the rendered cantilever's band are there, all five targets kept
    assert list(res.targets) == [1, 2, 3, 4, 5]
    assert res.shapes.shape == (len(res.modes["method"]), 5)
    assert res.report.strip() and "ssi" in set(res.modes["method"])
    modes, shapes = res.to_pandas()
    assert list(modes.columns)[:3] == ["system", "target", "mode"]
    assert len(shapes) == 5 * len(modes)
    # how each mode was found, and what was not taken with its reason, as report.txt says
    assert len(res.evidence) == len(res.modes["method"]) and all(res.evidence)
    report = (out / "report.txt").read_text()
    for e in res.evidence:
        assert e in report
    for r in res.rejected:
        assert ": " in r and r in report
    # the notebook's view: report.html's page, one marker per target, one animation per mode
    html = res._repr_html_()
    assert html.count('class="marker"') == 5
    assert html.count('class="mode-shape"') == len(res.modes["method"])
    assert html.count('class="mode-shape"') == (out / "report.html").read_text().count(
        'class="mode-shape"')


def test_analyze_of_an_array_equals_the_files(recording):
    frames = np.stack(list(vibcam.open_frames(recording / "frames")))
    assert frames.shape == (1200, 80, 165) and frames.dtype == np.uint8
    a = vibcam.analyze(frames, fps=120, threshold=127, targets=5)
    b = vibcam.analyze(str(recording / "frames"), fps=120, threshold=127, targets=5)
    np.testing.assert_array_equal(a.shapes, b.shapes)
    np.testing.assert_array_equal(a.modes["f_hz"], b.modes["f_hz"])
    np.testing.assert_array_equal(a.displacement, b.displacement)


def test_track_equals_the_command_line(recording, harness, as_python, tmp_path):
    out = tmp_path / "track"
    r = harness("track", "--frames", str(recording / "frames"), "--fps", "120", "--threshold",
                "127", "--targets", "5", "--out", str(out))
    assert r.returncode == 0, r.stderr
    t = vibcam.track(recording / "frames", targets=5, threshold=127, fps=120,
                     return_flags=True)
    assert t.positions.shape == (1200, 5, 2)
    for row in rows(out / "displacement.csv"):
        k, j = int(row["frame"]), int(row["target"]) - 1
        # the CSV prints the firmware's f32 centroid
        assert np.float32(t.positions[k, j, 0]) == np.float32(row["cx"])
        assert np.float32(t.positions[k, j, 1]) == np.float32(row["cy"])
        assert t.flags[k, j] == int(row["flags"])
    # the same report (after report.txt's header) and the same page, with the same figure,
    # settings named Python's way
    header, body = (out / "report.txt").read_text().split("\n\n", 1)
    assert t.report == as_python(body)
    assert "\ncommand: host-harness track --frames " in header
    page, html = (out / "report.html").read_text(), t._repr_html_()
    assert html.count("<svg") == page.count("<svg") >= 1 and "<title>track: " in html
    # each page's header names its own call: the command line, or the Python call with the
    # arguments given, the others marked as defaults
    assert "<code>host-harness track --frames " in page
    call = f"vibcam.track('{recording / 'frames'}', targets=5, threshold=127, fps=120, " \
           "return_flags=True)"
    assert f"<code>{call}</code>" in html
    assert "<li class=\"setting default\">tracker = 'auto'</li>" in html
    frames_sha = [line.split("sha256 ")[1] for line in header.splitlines()
                  if line.startswith("input: ")]
    assert frames_sha and all(f'data-sha256="{h}"' in html for h in frames_sha)


def test_lucas_kanade_points_equal_the_command_line(recording, harness, tmp_path):
    out = tmp_path / "lk"
    points = recording / "points.csv"
    r = harness("track", "--frames", str(recording / "frames"), "--fps", "120", "--points",
                str(points), "--tracker", "lk", "--out", str(out), "--no-plots")
    assert r.returncode == 0, r.stderr
    from_file = vibcam.track(recording / "frames", points, tracker="lk")
    listed = [(float(p["x"]), float(p["y"]), int(p["w"]), int(p["h"])) for p in rows(points)]
    from_list = vibcam.track(recording / "frames", listed, tracker="lk")
    np.testing.assert_array_equal(from_file, from_list)
    for row in rows(out / "displacement.csv"):
        k, j = int(row["frame"]), int(row["target"]) - 1
        if row["cx"] == "":
            assert np.isnan(from_file[k, j, 0])
        else:
            assert np.float32(from_file[k, j, 0]) == np.float32(row["cx"])
            assert np.float32(from_file[k, j, 1]) == np.float32(row["cy"])
    # every position's evidence as the CSV gives it: score, forward-backward, the check
    t = vibcam.track(recording / "frames", points, tracker="lk", return_flags=True)
    assert t.score.shape == t.fb_px.shape == t.check.shape == t.flags.shape
    measured = 0
    for row in rows(out / "displacement.csv"):
        k, j = int(row["frame"]), int(row["target"]) - 1
        for got, cell in ((t.score[k, j], row["score"]), (t.fb_px[k, j], row["fb_px"])):
            if cell == "":
                assert np.isnan(got)
            else:
                assert abs(got - float(cell)) <= 5e-5
                measured += 1
        assert t.check[k, j] == row["check"]
    assert measured > 0


def test_study_equals_the_command_line(harness, tmp_path):
    out = tmp_path / "cli-study"
    r = harness("study", "--preset", "grandstand", "--runs", "6", "--seed", "3", "--out",
                str(out), "--no-plots")
    assert r.returncode == 0, r.stderr
    s = vibcam.study(preset="grandstand", runs=6, seed=3, progress=False)
    assert s.out is None
    assert s.summary_csv == (out / "summary.csv").read_text()
    # the printed table is the command's stdout, less the line naming its directory
    cli_lines = r.stdout.splitlines(True)
    assert cli_lines[-1].startswith("wrote ") and cli_lines[-1].rstrip().endswith(str(out))
    assert s.table == "".join(cli_lines[:-1])
    assert len(s.summary["mu_a"]) == len(rows(out / "summary.csv"))
    assert np.all(np.isfinite(s.summary["mu_f_hz"]))
    kept = vibcam.study(preset="grandstand", runs=6, seed=3, out=tmp_path / "py-study",
                        progress=False)
    assert (tmp_path / "py-study" / "summary.csv").read_text() == s.summary_csv
    assert kept.out == str(tmp_path / "py-study")


def cli_error(harness, *args):
    r = harness(*args)
    assert r.returncode == 2, (r.returncode, r.stderr)
    line = [ln for ln in r.stderr.splitlines() if ln.startswith("error: ")][-1]
    return line[len("error: "):]


def test_errors_carry_the_command_lines_messages(recording, harness, as_python, tmp_path):
    missing = str(tmp_path / "nowhere")
    msg = cli_error(harness, "track", "--frames", missing, "--fps", "120", "--targets", "1",
                    "--threshold", "9", "--out", str(tmp_path / "o1"))
    with pytest.raises(vibcam.InputError) as e:
        vibcam.track(missing, targets=1, threshold=9, fps=120)
    assert str(e.value) == as_python(msg) and missing in msg and "--frames" in msg
    bad = tmp_path / "bad_points.csv"
    bad.write_text("target,x,y,w,h\n1,10,10,31,31\n2,20,x,31,31\n")
    msg = cli_error(harness, "track", "--frames", str(recording / "frames"), "--fps", "120",
                    "--points", str(bad), "--threshold", "127", "--out", str(tmp_path / "o2"))
    with pytest.raises(vibcam.InputError) as e:
        vibcam.track(recording / "frames", bad, threshold=127)
    assert str(e.value) == as_python(msg) and "row 3" in msg
    msg = cli_error(harness, "analyze", "--frames", str(recording / "frames"), "--targets",
                    "5", "--threshold", "127", "--out", str(tmp_path / "o3"))
    with pytest.raises(vibcam.InputError) as e:
        vibcam.analyze(recording / "frames", targets=5, threshold=127)
    assert str(e.value) == as_python(msg) and "--fps is needed" in msg

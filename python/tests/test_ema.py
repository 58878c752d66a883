"""vibcam.ema on a synthetic impact hammer test (`host-harness simulate-hammer`): the camera's
displacements given as a pyidi-style ``.npy`` (points, samples, 2), the force as a CSV at
another rate; the modes against the truth the command wrote, and the same numbers as the
command line's ``ema`` on the same files."""

import csv

import numpy as np
import pytest

import vibcam


@pytest.fixture(scope="module")
def hammer(tmp_path_factory, harness):
    d = tmp_path_factory.mktemp("hammer") / "test"
    r = harness("simulate-hammer", "--out", str(d))
    assert r.returncode == 0, r.stderr
    cam = np.loadtxt(d / "camera.csv", delimiter=",", skiprows=1)
    # pyidi's layout: (points, samples, 2), (y, x) per sample; x stays still here
    disp = np.zeros((cam.shape[1] - 1, cam.shape[0], 2))
    disp[:, :, 0] = cam[:, 1:].T
    np.save(d / "displacements.npy", disp)
    np.save(d / "two_d.npy", cam[:, 1:].T.copy())
    return d


def truth(d):
    with open(d / "truth.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    modes = sorted({int(r["mode"]) for r in rows})
    out = []
    for m in modes:
        rs = [r for r in rows if int(r["mode"]) == m]
        out.append((float(rs[0]["f_hz"]), float(rs[0]["damping"]),
                    np.array([float(r["shape"]) for r in rs])))
    return out


def mac(a, b):
    return abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)


def test_ema_of_a_pyidi_array_finds_the_modes_and_equals_the_command_line(hammer, harness,
                                                                          as_python, tmp_path):
    r = vibcam.ema(hammer / "displacements.npy", hammer / "force.csv", response_fs=2000,
                   excitation_col="force_n", impact=True, f_max_hz=200)
    assert r.responses == [f"point {p} y" for p in range(1, 6)]
    t = truth(hammer)
    assert len(r.modes["f_hz"]) == len(t) == 3
    for i, (f, z, shape) in enumerate(t):
        assert abs(r.modes["f_hz"][i] - f) < 1e-3 * f
        assert abs(r.modes["damping"][i] - z) < 0.05 * z
        assert r.modes["f_hz_lo"][i] <= r.modes["f_hz"][i] <= r.modes["f_hz_hi"][i]
        assert mac(r.shapes[i], shape) > 0.99
    assert r.h1.shape == (5, len(r.freq_hz)) and np.iscomplexobj(r.h1)
    out = tmp_path / "cli"
    p = harness("ema", "--response", str(hammer / "displacements.npy"), "--response-fs", "2000",
                "--excitation", str(hammer / "force.csv"), "--excitation-col", "force_n",
                "--impact", "--f-max-hz", "200", "--out", str(out), "--no-plots")
    assert p.returncode == 0, p.stderr
    with open(out / "modes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [float(x["f_hz"]) for x in rows] == pytest.approx(list(r.modes["f_hz"]), rel=1e-12)
    assert [float(x["damping"]) for x in rows] == pytest.approx(list(r.modes["damping"]),
                                                                 rel=1e-12)
    # the same report, each setting it names spelled for its caller (--response-col, response_col)
    assert as_python(p.stdout) == r.report and "--response-col" in p.stdout
    html = r._repr_html_()
    assert html.count('class="mode-shape"') == 3 and "<table id=\"modes\">" in html


def test_ema_errors_name_pythons_arguments(hammer):
    with pytest.raises(vibcam.InputError, match="response_fs"):
        vibcam.ema(hammer / "displacements.npy", hammer / "force.csv",
                   excitation_col="force_n", impact=True)
    with pytest.raises(vibcam.InputError, match="exp_window"):
        vibcam.ema(hammer / "camera.csv", hammer / "force.csv", excitation_col="force_n",
                   impact=True, exp_window=2.0)
    with pytest.raises(vibcam.InputError, match="no channel `push`"):
        vibcam.ema(hammer / "camera.csv", hammer / "force.csv", excitation_col="push")


def test_shapes_are_drawn_on_a_geometry_and_a_wrong_one_is_named(hammer, tmp_path):
    g = tmp_path / "beam.csv"
    g.write_text("node,x_mm,y_mm\n" + "".join(f"{i},{100 * i},0\n" for i in range(1, 6))
                 + "from,to\n1,2\n2,3\n3,4\n4,5\n")
    r = vibcam.ema(hammer / "camera.csv", hammer / "force.csv", excitation_col="force_n",
                   impact=True, f_max_hz=200, geometry=g)
    html = r._repr_html_()
    assert html.count('<line class="wire"') == 4 * html.count('class="mode-shape"') == 12
    assert "geometry=" in html and "Lines of the geometry" in html
    g.write_text("from,to\n1,9\n")
    with pytest.raises(vibcam.InputError, match="node 9 is not a response"):
        vibcam.ema(hammer / "camera.csv", hammer / "force.csv", excitation_col="force_n",
                   impact=True, geometry=g)


def test_a_two_dimensional_array_is_one_channel_per_point(hammer):
    r = vibcam.ema(hammer / "two_d.npy", hammer / "force.csv", response_fs=2000,
                   excitation_col="force_n", impact=True, f_max_hz=200)
    assert r.responses == [f"point {p}" for p in range(1, 6)]
    assert len(r.modes["f_hz"]) == 3


def test_a_real_camera_impact_test_gives_both_modes_by_default():
    # LADISK's free beam (tests/data/real/ladisk-ema-beam, MIT): pyidi's displacements at
    # 15 kHz over a LabVIEW force; the axis, band, window and delay from the data
    from pathlib import Path
    d = Path(__file__).resolve().parents[2] / "tests" / "data" / "real" / "ladisk-ema-beam"
    r = vibcam.ema(d / "displacements_lk.npy", d / "camera.lvm", response_fs=15000,
                   excitation_col="Force (Trigger)", impact=True)
    assert all(n.endswith(" y") for n in r.responses)
    f = sorted(r.modes["f_hz"])
    # sdypy-EMA's frequencies on the same displacements (the data's README), within 0.5 %
    for want in (695.91, 1898.64):
        assert any(abs(x - want) <= 0.005 * want for x in f), f
    assert "start to move" in r.report


def test_poles_given_as_an_earlier_modes_csv_give_exactly_those_modes(hammer, tmp_path):
    out = tmp_path / "all"
    r = vibcam.ema(hammer / "camera.csv", hammer / "force.csv", excitation_col="force_n",
                   impact=True, f_max_hz=200, out=out)
    lines = (out / "modes.csv").read_text().splitlines()
    picked = tmp_path / "picked.csv"
    picked.write_text("\n".join([lines[0], lines[1], lines[3]]) + "\n")
    p = vibcam.ema(hammer / "camera.csv", hammer / "force.csv", excitation_col="force_n",
                   impact=True, f_max_hz=200, poles=picked)
    f_all, f = list(r.modes["f_hz"]), list(p.modes["f_hz"])
    assert f == pytest.approx([f_all[0], f_all[2]], rel=1e-12)


def test_a_roving_hammer_gives_the_shapes_over_the_hit_points(harness, tmp_path):
    d = tmp_path / "roving"
    r = harness("simulate-hammer", "--hit-points", "1,2,3,4,5", "--daq-hz", "10000",
                "--out", str(d))
    assert r.returncode == 0, r.stderr
    records = [(p, d / f"camera_{p}.csv", d / f"force_{p}.csv") for p in range(1, 6)]
    r = vibcam.ema(roving=records, response_cols=["p4"], excitation_col="force_n",
                   impact=True, f_max_hz=200)
    assert r.shape_points == [1, 2, 3, 4, 5] and r.responses == ["p4"]
    assert r.shapes.shape == (3, 5) and r.h1.shape == (5, len(r.freq_hz))
    for i, (f, z, shape) in enumerate(truth(d)):
        assert abs(r.modes["f_hz"][i] - f) < 1e-3 * f
        assert mac(r.shapes[i], shape) > 0.99
    assert "roving hammer: 5 records" in r.report
    with pytest.raises(ValueError, match="instead of response and excitation"):
        vibcam.ema(d / "camera_1.csv", d / "force_1.csv", roving=records, impact=True)
    with pytest.raises(ValueError, match="the hit point 0"):
        vibcam.ema(roving=[(0, d / "camera_1.csv", d / "force_1.csv")], impact=True)
    with pytest.raises(vibcam.InputError, match="roving: hit point 2 is given twice"):
        vibcam.ema(roving=records[:2] + records[1:2], excitation_col="force_n", impact=True)


def test_several_forces_are_a_list_of_excitation_channels(tmp_path):
    rng = np.random.default_rng(5)
    n, fs = 1 << 15, 1000.0
    f = rng.standard_normal((2, n))
    # point 1 driven by shaker a, point 2 by b, each a single mode at 40 / 90 Hz
    freq = np.fft.rfftfreq(n, 1 / fs)
    w = 2 * np.pi * freq

    def mode(fn, z):
        wn = 2 * np.pi * fn
        return 1.0 / (wn ** 2 - w ** 2 + 2j * z * wn * w)

    h = [[mode(40, 0.02) + 0.5 * mode(90, 0.01), 0.5 * mode(40, 0.02) - mode(90, 0.01)],
         [0.5 * mode(40, 0.02) - mode(90, 0.01), 0.25 * mode(40, 0.02) + mode(90, 0.01)]]
    F = np.fft.rfft(f, axis=1)
    x = [np.fft.irfft(h[o][0] * F[0] + h[o][1] * F[1], n) for o in range(2)]
    t = np.arange(n) / fs
    np.savetxt(tmp_path / "force.csv", np.column_stack([t, f.T]), delimiter=",",
               header="t_s,a,b", comments="")
    np.savetxt(tmp_path / "resp.csv", np.column_stack([t, np.array(x).T]), delimiter=",",
               header="t_s,x1,x2", comments="")
    r = vibcam.ema(tmp_path / "resp.csv", tmp_path / "force.csv", excitation_col=["a", "b"],
                   f_min_hz=10, f_max_hz=200)
    assert r.h1.shape == (4, len(r.freq_hz))
    assert sorted(round(v) for v in r.modes["f_hz"]) == [40, 90]
    assert "2 forces at once" in r.report

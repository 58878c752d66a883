"""vibcam.modal on a shear frame's record (`host-harness simulate-field`): the same numbers and
report as the command line's ``modal`` on the same file, the modes against the truth the
command wrote; two setups cut from the record merged by PoSER and by PreGER; refusals named
as Python's arguments."""

import csv

import numpy as np
import pytest

import vibcam


@pytest.fixture(scope="module")
def field(tmp_path_factory, harness):
    d = tmp_path_factory.mktemp("field") / "frame"
    r = harness("simulate-field", "--minutes", "3", "--out", str(d))
    assert r.returncode == 0, r.stderr
    return d


def truth(d):
    with open(d / "truth.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    out = []
    for m in sorted({int(r["mode"]) for r in rows}):
        rs = [r for r in rows if int(r["mode"]) == m]
        out.append((float(rs[0]["f_hz"]), np.array([float(r["shape"]) for r in rs])))
    return out


def mac(a, b):
    return abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)


def ssi_modes(r):
    return [i for i, m in enumerate(r.modes["method"]) if m == "ssi"]


def test_modal_equals_the_command_line_and_finds_the_frames_modes(field, harness, as_python,
                                                                   tmp_path):
    r = vibcam.modal(field / "displacement.csv")
    out = tmp_path / "cli"
    p = harness("modal", "--displacement", str(field / "displacement.csv"), "--out", str(out),
                "--no-plots")
    assert p.returncode == 0, p.stderr
    with open(out / "modes.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [x["method"] for x in rows] == list(r.modes["method"])
    assert [float(x["f_hz"]) for x in rows] == pytest.approx(list(r.modes["f_hz"]), rel=1e-12)
    damping = [float(x["damping"]) if x["damping"] else np.nan for x in rows]
    np.testing.assert_allclose(damping, r.modes["damping"], rtol=1e-12)
    assert as_python(p.stdout) == r.report
    assert r.fps == 60 and r.displacement.shape == (10800, 5) and r.lost is None
    assert r.filled == [0] * 5 and r.setups == []
    found = ssi_modes(r)
    for f, shape in truth(field):
        i = min(found, key=lambda i: abs(r.modes["f_hz"][i] - f))
        assert abs(r.modes["f_hz"][i] - f) < 0.01 * f
        assert mac(r.shapes[i], shape) > 0.99
    assert '<table id="modes">' in r._repr_html_()


@pytest.mark.parametrize("merge", ["poser", "preger"])
def test_two_setups_give_the_global_shapes(field, tmp_path, merge):
    data = np.loadtxt(field / "displacement.csv", delimiter=",", skiprows=1)
    # setup 1: storeys 1-3; setup 2: storeys 4, 2, 5, 1 (the references 2 and 1 elsewhere)
    np.savetxt(tmp_path / "one.csv", data[:, [0, 1, 2, 3]], delimiter=",",
               header="t_s,1,2,3", comments="")
    np.savetxt(tmp_path / "two.csv", data[:, [0, 4, 2, 5, 1]], delimiter=",",
               header="t_s,1,2,3,4", comments="")
    r = vibcam.modal(tmp_path / "one.csv", references=[1, 2], setups=[(tmp_path / "two.csv",
                                                                        [4, 2])], merge=merge,
                     out=tmp_path / "out")
    assert (tmp_path / "out" / "setups.csv").is_file()
    # global points: setup 1's 1, 2, 3, then setup 2's others: storeys 4 and 5
    assert r.shapes.shape[1] == 5
    for f, shape in truth(field):
        i = min(ssi_modes(r), key=lambda i: abs(r.modes["f_hz"][i] - f))
        assert abs(r.modes["f_hz"][i] - f) < 0.01 * f
        assert mac(r.shapes[i], shape) > 0.99, (merge, f)
    methods = {s["method"] for s in r.setups}
    if merge == "poser":
        assert {"ssi", "efdd"} <= methods
    else:
        # PreGER identifies SSI, FDD and EFDD on every setup together: no part per setup; the
        # EFDD modes' shapes are global too
        assert not methods & {"ssi", "fdd", "efdd"}
        efdd = [i for i, m in enumerate(r.modes["method"]) if m == "efdd"]
        for f, shape in truth(field):
            i = min(efdd, key=lambda i: abs(r.modes["f_hz"][i] - f))
            assert abs(r.modes["f_hz"][i] - f) < 0.01 * f
            assert mac(r.shapes[i], shape) > 0.99, ("efdd", f)
    assert all(isinstance(s["scale"], complex) for s in r.setups)
    assert (merge == "preger") == ("PreGER" in r.report)


def test_modal_errors_name_pythons_arguments(field):
    with pytest.raises(vibcam.InputError, match="merge = 'both'"):
        vibcam.modal(field / "displacement.csv", merge="both")
    with pytest.raises(vibcam.InputError, match="setups and references"):
        vibcam.modal(field / "displacement.csv", merge="preger")
    with pytest.raises(vibcam.InputError, match="^ssi_max_order = 401"):
        vibcam.modal(field / "displacement.csv", ssi_max_order=401)
    with pytest.raises(vibcam.InputError, match="references: target 9"):
        vibcam.modal(field / "displacement.csv", references=[9],
                     setups=[(field / "displacement.csv", [1])])


def test_poles_picked_are_exactly_the_ssi_modes_and_refusals_name_the_argument(field, tmp_path):
    r = vibcam.modal(field / "displacement.csv")
    ssi = ssi_modes(r)
    keep = [ssi[0], ssi[-1]]
    poles = tmp_path / "poles.csv"
    poles.write_text("f_hz,damping\n" + "".join(
        f"{float(r.modes['f_hz'][i])!r},{float(r.modes['damping'][i])!r}\n" for i in keep))
    p = vibcam.modal(field / "displacement.csv", poles=poles)
    got = ssi_modes(p)
    assert [p.modes["f_hz"][i] for i in got] == [r.modes["f_hz"][i] for i in keep]
    assert [p.modes["damping"][i] for i in got] == [r.modes["damping"][i] for i in keep]
    assert "given (poles)" in p.report
    assert 'id="pole-picker"' in p._repr_html_()
    with pytest.raises(vibcam.InputError, match="^poles with setups or bands"):
        vibcam.modal(field / "displacement.csv", poles=poles, bands=[(1, 2)])

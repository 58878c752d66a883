"""The package as `import vibcam` shows it: its version, and a namespace that holds what
`__all__` names (and private helpers), not the modules and typing names it uses."""

import re

import numpy as np
import pytest

from conftest import ROOT

import vibcam


def test_version_is_the_workspaces():
    text = (ROOT / "Cargo.toml").read_text()
    want = re.search(r'^version = "([^"]+)"', text, re.M).group(1)
    assert vibcam.__version__ == want


def test_the_namespace_holds_only_the_public_names():
    public = {n for n in dir(vibcam) if not n.startswith("_")}
    # `_vibcam` aside, every public name is one `__all__` lists
    assert public == set(vibcam.__all__), sorted(public ^ set(vibcam.__all__))
    for leaked in ["np", "os", "csv", "io", "math", "tempfile", "Optional", "Any", "Union"]:
        assert not hasattr(vibcam, leaked), leaked
    for name in vibcam.__all__:
        assert hasattr(vibcam, name), name


def cli_defaults(harness, command):
    """Each flag of `command` whose help states a `[default: X]`: {python_name: X}."""
    text = harness(command, "--help").stdout
    out = {}
    for m in re.finditer(r"^\s+(?:-\w, )?--([a-z0-9-]+)(.*?)(?=^\s+(?:-\w, )?--|\Z)", text,
                         re.M | re.S):
        d = re.search(r"\[default: ([^\]]+)\]", m.group(2))
        if d:
            out[m.group(1).replace("-", "_")] = d.group(1)
    return out


def test_defaults_agree_with_the_command_line(harness):
    # a setting has one default: where a Python argument and its command's flag both state
    # one, they are the same (None in Python means "the library's own", which the flag states)
    import inspect

    # Python's argument -> the command's flag, where the names differ
    renamed = {"tracker": "mode"}
    checked = 0
    for name in ["centroid", "track", "frf", "analyze", "ema", "modal", "study"]:
        flags = cli_defaults(harness, name)
        for p in inspect.signature(getattr(vibcam, name)).parameters.values():
            flag = renamed.get(p.name, p.name)
            if p.default is inspect.Parameter.empty or p.default is None or flag not in flags:
                continue
            want = flags[flag]
            if isinstance(p.default, bool):
                continue  # a switch: absent on the command line
            if isinstance(p.default, (int, float)):
                assert float(want) == p.default, (name, p.name, p.default, want)
            else:
                assert want == p.default, (name, p.name, p.default, want)
            checked += 1
    assert checked >= 10, checked


# Python's functions and the settings table: the table (`vibcam-common`'s `setting::table`)
# declares each shared setting once; Python's defaults and refusals are checked against it.
FUNCTIONS = ["centroid", "track", "frf", "analyze", "ema", "modal", "study", "open_frames"]


def test_every_default_is_the_settings_tables():
    import inspect

    checked = 0
    for name in FUNCTIONS:
        params = inspect.signature(getattr(vibcam, name)).parameters
        for row in vibcam._SETTINGS:
            if name not in row["commands"] or row["key"] not in params:
                continue
            default = params[row["key"]].default
            if row["given"]:
                # the command line fills it in: Python's default is the same value
                assert str(default) == row["default"] or (
                    isinstance(default, (int, float)) and float(default) == float(row["default"])
                ), (name, row["key"], default, row["default"])
            elif row["kind"] != "switch" and default is not inspect.Parameter.empty:
                # absent, or the job's own default: None in Python
                assert default is None, (name, row["key"], default)
            checked += 1
    assert checked >= 40, checked


def out_of_range(row):
    """Values the row refuses: just past each end, and a fraction for a whole number."""
    bad = []
    if row["min"] is not None:
        bad.append(row["min"] if row["min_open"] else row["min"] - 1)
    if row["max"] is not None:
        bad.append(row["max"] if row["max_open"] else row["max"] + 1)
    if row["kind"] == "whole":
        bad.append(row["min"] + 0.5)
    bad.append(float("nan"))
    return bad


def test_every_range_of_the_table_is_refused_naming_the_argument():
    import inspect

    from vibcam import _setting

    walked = 0
    for row in vibcam._SETTINGS:
        if row["kind"] not in ("whole", "number"):
            continue
        for name in row["commands"]:
            if name not in FUNCTIONS:
                continue
            params = inspect.signature(getattr(vibcam, name)).parameters
            if row["key"] not in params:
                continue
            for v in out_of_range(row):
                with pytest.raises(vibcam.InputError, match=f"^{row['key']} = "):
                    _setting(name, row["key"], v)
            # the ends themselves, where closed, are taken
            for end, is_open in ((row["min"], row["min_open"]), (row["max"], row["max_open"])):
                if end is not None and not is_open:
                    assert _setting(name, row["key"], end) == end
            walked += 1
    assert walked >= 15, walked


def test_a_refused_argument_of_a_public_function_names_it():
    # the same rows through the public functions (not only the helper)
    with pytest.raises(vibcam.InputError, match="^targets = 33: a whole number from 1 to 32"):
        vibcam.track(np.zeros((2, 8, 8), np.uint8), targets=33, fps=10, threshold=1)
    with pytest.raises(vibcam.InputError, match="^max_order = 201"):
        vibcam.ema("r.csv", "f.csv", max_order=201)
    with pytest.raises(vibcam.InputError, match="^gate_px = 0"):
        vibcam.track(np.zeros((2, 8, 8), np.uint8), targets=1, gate_px=0, fps=10, threshold=1)

"""The package as `import vibcam` shows it: its version, and a namespace that holds what
`__all__` names (and private helpers), not the modules and typing names it uses."""

import re

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
    for name in ["centroid", "track", "frf", "analyze", "ema", "study"]:
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

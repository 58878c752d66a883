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

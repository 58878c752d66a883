"""Shared fixtures: the repository, the host-harness binary the Python results are compared
with, and a 5-target synthetic recording rendered by it once per test session."""

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def harness_path() -> Path:
    """The host-harness binary: $VIBCAM_HARNESS, else the workspace's debug build."""
    p = Path(os.environ.get("VIBCAM_HARNESS", ROOT / "target" / "debug" / "host-harness"))
    if not p.is_file():
        raise RuntimeError(
            f"{p}: no host-harness binary; build it (cargo build -p host-harness) or set "
            "VIBCAM_HARNESS"
        )
    return p


def run_harness(*args: str) -> subprocess.CompletedProcess:
    """Runs host-harness; the completed process (stdout, stderr, returncode)."""
    return subprocess.run(
        [str(harness_path()), *args], capture_output=True, text=True, check=False
    )


@pytest.fixture(scope="session")
def harness():
    return run_harness


@pytest.fixture(scope="session")
def recording(tmp_path_factory) -> Path:
    """The 5-target cantilever recording of the README (1200 frames, 120 fps, 2 ms)."""
    d = tmp_path_factory.mktemp("rec") / "targets"
    r = run_harness(
        "render", "--preset", "cantilever", "--recording", str(d), "--targets", "5",
        "--exposure-ms", "2",
    )
    assert r.returncode == 0, r.stderr
    return d


@pytest.fixture
def as_python():
    """The command line's text with each flag spelled as Python's argument (`--response-col`
    -> `response_col`): the library names a setting to each caller in its own words."""
    return lambda text: re.sub(
        r"--([a-z][a-z0-9-]*)", lambda m: m.group(1).replace("-", "_"), text
    )

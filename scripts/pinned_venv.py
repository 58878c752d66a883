"""Running a script in a virtual environment with pinned packages: what the check and peer
scripts share (each names its environment, its pins and the import that shows they are in)."""

import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def rerun_in_venv(script, mark, dir_var, default_dir, probe, pins, env=None):
    """Re-executes `script` (with this process's arguments) with the python of the virtual
    environment `$dir_var` (default: `default_dir` in the repository), creating it when missing
    and installing `pins` when `import probe` fails there; `env` is added to the re-run's
    environment (set before numpy is imported there). Returns at once when already inside it:
    the re-run has `mark` set."""
    if os.environ.get(mark) == "1":
        return
    env_dir = Path(os.environ.get(dir_var, ROOT / default_dir))
    py = env_dir / "bin" / "python"
    if not py.exists():
        print(f"creating a virtual environment in {env_dir}", flush=True)
        venv.create(env_dir, with_pip=True)
    have = subprocess.run([str(py), "-c", f"import {probe}"], capture_output=True)
    if have.returncode != 0:
        subprocess.run([str(py), "-m", "pip", "install", "-q", *pins], check=True)
    os.environ[mark] = "1"
    os.environ.update(env or {})
    os.execv(str(py), [str(py), str(Path(script).resolve()), *sys.argv[1:]])

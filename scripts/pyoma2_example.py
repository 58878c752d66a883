#!/usr/bin/env python3
"""pyOMA-2's own first example beside ours: its 5-DOF shear-type building under white noise
(`pyoma2.functions.gen.example_data`: 5 storeys of 25.91 kg and 10 kN/m, damping 2 % in every
mode, accelerations at 100 Hz for 300 s, 10 % process and measurement noise, seed 12345), its
exact modes as the truth, analysed by `host-harness modal` and by pyOMA-2 (FDD, EFDD, SSI-cov)
through scripts/peer_oma.py. Run on demand; the table goes to docs/validation.md.

    python3 scripts/pyoma2_example.py OUT --harness target/release/host-harness [--nperseg 1024]

Writes (an earlier run's files replaced only with --force) OUT/displacement.csv (`t_s,1,...,5`: the example's accelerations; `modal` takes any
unit), OUT/truth.csv (`mode,f_hz,damping,target,shape`, as `simulate-field` writes it) and
OUT/peer-oma.md. Both sides single-threaded (OMP/OpenBLAS/MKL threads 1), in pyOMA-2's pinned
virtual environment (scripts/peer_oma.py).
"""
import argparse
import subprocess
import sys
from pathlib import Path

from peer_oma import ensure_venv

ONE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                "RAYON_NUM_THREADS")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="directory to write (created)")
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--nperseg", type=int, default=1024)
    ap.add_argument("--force", action="store_true", help="replace the files of an earlier run")
    args = ap.parse_args()
    out = Path(args.out)
    if (out / "displacement.csv").exists() and not args.force:
        sys.exit(f"{out / 'displacement.csv'} exists: --force to replace it")
    ensure_venv(__file__, ONE_THREAD)
    import numpy as np
    from pyoma2.functions.gen import example_data

    out.mkdir(parents=True, exist_ok=True)
    y, _u, (fn, xi, phi) = example_data()
    dt = 0.01
    with open(out / "displacement.csv", "w") as f:
        f.write("t_s," + ",".join(str(k + 1) for k in range(y.shape[1])) + "\n")
        for i, row in enumerate(y):
            f.write(f"{i * dt:.2f}," + ",".join(f"{v:.9e}" for v in row) + "\n")
    with open(out / "truth.csv", "w") as f:
        f.write("mode,f_hz,damping,target,shape\n")
        for m in range(len(fn)):
            shape = phi[:, m] / np.max(np.abs(phi[:, m]))
            for t, v in enumerate(shape):
                f.write(f"{m + 1},{fn[m]:.9f},{xi},{t + 1},{v:.9f}\n")
    peer = Path(__file__).resolve().parent / "peer_oma.py"
    sys.exit(subprocess.run([sys.executable, str(peer), str(out), "--harness", args.harness,
                             "--nperseg", str(args.nperseg), "--force"]).returncode)


if __name__ == "__main__":
    main()

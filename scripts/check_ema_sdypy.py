#!/usr/bin/env python3
"""Check `host-harness ema`'s modes beside sdypy-EMA on the same FRFs: read the output's
frf.uff with pyuff (datasets 58, function type 4, displacement over force), fit it with
sdypy-EMA (LSCF poles, the stable poles closest to ours, LSFD constants with residuals) and
assert that its natural frequencies are within 0.1 %, its damping ratios within 5 % and its
shapes (modal constants) within a MAC of 0.99 of ours (modes.csv, shapes.csv).

    python3 scripts/check_ema_sdypy.py EMA_OUT_DIR [--lower HZ] [--upper HZ] [--order N]

A roving-hammer test's frf.uff (several reference nodes, the points hit) is fitted as one set
of FRFs; each mode's constants form a matrix (responses x hit points) whose dominant singular
vector, over the larger of the two sets as `ema` gives it, is compared with ours.

The FRFs must be those the modes were fitted on: an `ema` run without an exponential window
(`--exp-window off`; with one, frf.uff holds the windowed FRFs and ours have its damping
removed). Runs inside the virtual environment of scripts/check_uff.py ($CHECK_UFF_VENV, else
.venv at the repository root; pinned pyuff and sdypy-EMA). Exit status 0 when every check
passes, 1 otherwise.
"""
import argparse
import csv
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import check_uff  # noqa: E402  (its ensure_venv re-executes this script in the venv)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="an output directory of `host-harness ema`")
    ap.add_argument("--lower", type=float, default=None,
                    help="lowest frequency of the fit, Hz (default: half the lowest mode's)")
    ap.add_argument("--upper", type=float, default=None,
                    help="highest frequency of the fit, Hz (default: 1.4 x the highest mode's)")
    ap.add_argument("--order", type=int, default=40, help="highest LSCF polynomial order")
    args = ap.parse_args()
    ensure_venv()

    import warnings

    import numpy as np
    import pyuff
    from sdypy import EMA

    out = Path(args.out)
    failures = []

    def check(ok, what):
        print(("ok    " if ok else "FAIL  ") + what)
        if not ok:
            failures.append(what)

    with open(out / "modes.csv") as fh:
        modes = [(float(r["f_hz"]), float(r["damping"])) for r in csv.DictReader(fh)]
    shapes = {}
    with open(out / "shapes.csv") as fh:
        for r in csv.DictReader(fh):
            shapes.setdefault(int(r["mode"]), {})[int(r["target"])] = complex(
                float(r["re"]), float(r["im"]))
    check(len(modes) > 0, f"{len(modes)} modes in modes.csv")

    sets = pyuff.UFF(str(out / "frf.uff")).read_sets()
    if isinstance(sets, dict):
        sets = [sets]
    for s in sets:
        check(s["func_type"] == 4 and s["ordinate_spec_data_type"] == 8
              and s["orddenom_spec_data_type"] == 13,
              f"response node {s['rsp_node']}: an FRF (type 4) of displacement (8) over "
              f"force (13)")
    sets.sort(key=lambda s: (s["ref_node"], s["rsp_node"]))
    refs = sorted({s["ref_node"] for s in sets})
    rsps = sorted({s["rsp_node"] for s in sets})
    check(len(sets) == len(refs) * len(rsps),
          f"{len(sets)} FRFs: {len(rsps)} responses x {len(refs)} reference nodes {refs}")
    freq = np.asarray(sets[0]["x"])
    frf = np.array([np.asarray(s["data"]) for s in sets])
    f_modes = [m[0] for m in modes]
    lower = args.lower if args.lower is not None else 0.5 * min(f_modes)
    upper = args.upper if args.upper is not None else 1.4 * max(f_modes)
    model = EMA.Model(frf=frf, freq=freq, lower=lower, upper=upper,
                      pol_order_high=args.order, frf_form="receptance")
    model.get_poles(method="lscf", show_progress=False)
    warnings.filterwarnings("ignore", category=RuntimeWarning)
    df = float(freq[1] - freq[0])
    model.select_closest_poles(f_modes, f_window=max(4.0, 0.1 * min(f_modes)))
    model.get_constants(method="lsfd", f_lower=lower, f_upper=upper)
    for i, ((f, z), f_s, z_s) in enumerate(zip(modes, model.nat_freq, model.nat_xi)):
        check(abs(f_s - f) <= 1e-3 * f,
              f"mode {i + 1}: sdypy-EMA {f_s:.5f} Hz, ema {f:.5f} Hz (within 0.1 %; lines "
              f"every {df:.4g} Hz)")
        check(abs(z_s - z) <= 0.05 * z,
              f"mode {i + 1}: sdypy-EMA damping {z_s:.6f}, ema {z:.6f} (within 5 %)")
        a = np.asarray(model.A[:, i])
        if len(refs) > 1:
            # the constants as a matrix, responses x hit points, and its dominant vector
            u, _, vh = np.linalg.svd(a.reshape(len(refs), len(rsps)).T)
            a = vh[0, :] if len(refs) > len(rsps) else u[:, 0]
        ours = np.array([shapes[i + 1][t] for t in sorted(shapes[i + 1])])
        mac = abs(np.vdot(a, ours)) ** 2 / (np.vdot(a, a).real * np.vdot(ours, ours).real)
        check(mac >= 0.99, f"mode {i + 1}: MAC of the shapes {mac:.5f} (>= 0.99)")
    print(f"{len(failures)} failed" if failures else "all checks passed")
    return 1 if failures else 0


def ensure_venv():
    """check_uff's venv, this script re-executed in it."""
    check_uff.ensure_venv_for(__file__)


if __name__ == "__main__":
    sys.exit(main())

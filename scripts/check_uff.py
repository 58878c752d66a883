#!/usr/bin/env python3
"""Check a universal file of FRFs (datasets 58) written by host-harness with the modal tools
test engineers use: read it with pyuff, assert the fields, fit it with sdypy-EMA (LSCF poles,
closest stable poles to the expected frequencies) and assert that the natural frequencies are
within one frequency bin of the expected ones.

    python3 scripts/check_uff.py FILE.uff --expect 7.1,32.4 [--bin HZ] [--lower HZ] [--upper HZ]

Runs itself inside a virtual environment with pinned pyuff and sdypy-EMA: the one named by
$CHECK_UFF_VENV, else .venv at the repository root (created, and the packages installed with
pip, when missing). Exit status 0 when every check passes, 1 otherwise.
"""
import argparse
import sys
from pathlib import Path

from pinned_venv import rerun_in_venv

PINS = ["pyuff==2.5.8", "sdypy-EMA==0.31.0"]
MARK = "CHECK_UFF_IN_VENV"


def ensure_venv():
    """Re-executes this script with the venv's python, creating the venv if needed."""
    ensure_venv_for(__file__)


def ensure_venv_for(script):
    """Re-executes `script` (with this process's arguments) with the venv's python, creating
    the venv if needed."""
    rerun_in_venv(script, MARK, "CHECK_UFF_VENV", ".venv", "pyuff, sdypy.EMA", PINS)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("uff", help="universal file with datasets 58")
    ap.add_argument("--expect", required=True,
                    help="expected natural frequencies, Hz, comma-separated")
    ap.add_argument("--bin", type=float, default=None,
                    help="tolerance, Hz (default: the file's abscissa increment, one bin)")
    ap.add_argument("--lower", type=float, default=None,
                    help="lowest frequency of the fit, Hz (default: half the lowest expected)")
    ap.add_argument("--upper", type=float, default=None,
                    help="highest frequency of the fit, Hz (default: 1.4 x the highest expected)")
    ap.add_argument("--order", type=int, default=40, help="highest LSCF polynomial order")
    ap.add_argument("--window", type=float, default=4.0,
                    help="sdypy-EMA's f_window, Hz: stable poles are searched within half of it "
                         "around each expected frequency (its default, 50, pulls the search "
                         "of a 7 Hz mode towards the others)")
    args = ap.parse_args()
    ensure_venv()

    import warnings

    import numpy as np
    import pyuff
    from sdypy import EMA

    expected = [float(v) for v in args.expect.split(",")]
    failures = []

    def check(ok, what):
        print(("ok    " if ok else "FAIL  ") + what)
        if not ok:
            failures.append(what)

    uff = pyuff.UFF(args.uff)
    types = list(uff.get_set_types())
    check(len(types) > 0 and all(t == 58 for t in types),
          f"{len(types)} datasets, all of type 58: {types}")
    sets = uff.read_sets()
    if isinstance(sets, dict):
        sets = [sets]
    x0 = None
    for i, s in enumerate(sets):
        x = np.asarray(s["x"])
        d = np.asarray(s["data"])
        tag = (f"set {i} (function {s['func_id']}, response node {s['rsp_node']} dir "
               f"{s['rsp_dir']}, reference node {s['ref_node']} dir {s['ref_dir']}, "
               f"'{s['id1']}')")
        check(s["func_type"] == 4, f"{tag}: function type 4 (FRF)")
        check(s["ord_data_type"] == 6 and np.iscomplexobj(d),
              f"{tag}: complex double ordinate, {len(d)} values")
        check(s["abscissa_spacing"] == 1 and s["abscissa_spec_data_type"] == 18
              and s["abscissa_axis_units_lab"] == "Hz",
              f"{tag}: even abscissa, frequency in Hz, step {s['abscissa_inc']}")
        check(s["ordinate_spec_data_type"] == 12 and s["orddenom_spec_data_type"] == 12
              and s["ordinate_axis_units_lab"] == "m/s^2"
              and s["orddenom_axis_units_lab"] == "m/s^2"
              and s["ordinate_len_unit_exp"] == 1,
              f"{tag}: acceleration over acceleration (m/s^2 / m/s^2)")
        check(len(x) == len(d) and np.all(np.isfinite(d)), f"{tag}: finite values")
        if x0 is None:
            x0 = x
        check(len(x) == len(x0) and np.allclose(x, x0), f"{tag}: same frequency axis as set 0")
    df = float(x0[1] - x0[0])
    tol = args.bin if args.bin is not None else df
    lower = args.lower if args.lower is not None else 0.5 * min(expected)
    upper = args.upper if args.upper is not None else 1.4 * max(expected)

    model = EMA.Model(lower=lower, upper=upper, pol_order_high=args.order,
                      frf_form="accelerance")
    model.read_uff(args.uff)
    check(model.frf_form == "accelerance", f"sdypy-EMA reads the FRFs as {model.frf_form}")
    model.get_poles(method="lscf", show_progress=False)
    # (the stabilisation divides by zero-valued poles; sdypy-EMA silences that itself)
    warnings.filterwarnings("ignore", category=RuntimeWarning)
    model.select_closest_poles(expected, f_window=args.window)
    for f_exp, f_fit, xi in zip(expected, model.nat_freq, model.nat_xi):
        check(abs(f_fit - f_exp) <= tol,
              f"sdypy-EMA LSCF: {f_fit:.4f} Hz (damping {xi:.5f}), expected {f_exp} Hz "
              f"+/- {tol:g} Hz")

    print(f"{len(failures)} failed" if failures else "all checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

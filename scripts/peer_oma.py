#!/usr/bin/env python3
"""Our output-only modal analysis (`host-harness modal`) beside pyOMA-2's on the same
displacement file: frequencies, damping and shapes per method (FDD, EFDD, SSI-cov, SSI-dat), the
differences, and the wall time of each side. Run on demand; the figures go to
docs/performance.md and docs/method.md §3.12.

    host-harness simulate-field --minutes 30 --out FIELD
    python3 scripts/peer_oma.py FIELD --harness target/release/host-harness [--nperseg 2048]

FIELD/displacement.csv is a wide file (`t_s,1,...,K`; `simulate-field` writes one); with
FIELD/truth.csv the true modes are printed beside. Both sides get the same Welch segments (Hann,
half overlap), 30 block rows and orders up to 40 for SSI-cov and SSI-dat (ours: `modal --ssi
dat`, a second run); pyOMA-2's modal parameters are extracted at our SSI frequencies (its `mpe`
with `sel_freq`; `order_in` 'find_min' for SSI). Runs in a virtual environment with pinned
pyOMA-2: $PEER_OMA_VENV, else .venv-peer-oma at the repository root (created with pip when
missing). Writes FIELD/peer-oma.md (an existing one is replaced only with --force). Exit status
1 when a check of --check fails (SSI-cov's and SSI-dat's frequencies within one line and damping
within 10 %, MAC >= 0.99 for every method but pLSCF; FDD and EFDD frequencies, EFDD damping and
pLSCF are compared, not checked: see docs/method.md §3.12). pLSCF: ours (`modal --plscf`, the
poly-reference LSCF on half-spectra) beside pyOMA-2's matrix-fraction pLSCF on half-spectra
(`method_SD="cor"`, order 20), its parameters at our frequencies from its order 19.
"""
import argparse
import csv
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from pinned_venv import rerun_in_venv

PINS = ["pyOMA-2==1.4.3"]
MARK = "PEER_OMA_IN_VENV"


def ensure_venv(script=__file__, env=None):
    """Re-runs `script` (this one, or another peer script that imports this function) in the
    virtual environment with pinned pyOMA-2, with `env` added to its environment (set before
    numpy is imported there); returns at once when already in it."""
    rerun_in_venv(script, MARK, "PEER_OMA_VENV", ".venv-peer-oma", "pyoma2", PINS, env)


def read_wide(path):
    """A wide displacement file (`t_s,1,...,K`) as (samples x K array, sample rate in Hz)."""
    import numpy as np
    d = np.genfromtxt(path, delimiter=",", names=True)
    names = d.dtype.names
    t = d[names[0]]
    return np.column_stack([d[n] for n in names[1:]]), (len(t) - 1) / (t[-1] - t[0])


def simulate_field(harness, case, minutes, noise, seed, rec):
    """`host-harness simulate-field` into `rec`; returns its truth, {mode: (f_hz, damping)}."""
    import csv
    subprocess.run([harness, "simulate-field", "--case", case, "--minutes", str(minutes),
                    "--noise", str(noise), "--seed", str(seed), "--out", str(rec), "--force"],
                   check=True, capture_output=True)
    truth = {}
    for r in csv.DictReader(open(Path(rec) / "truth.csv")):
        truth.setdefault(int(r["mode"]), (float(r["f_hz"]), float(r["damping"])))
    return truth


def ensemble_parser(doc, records=20):
    """The flags of a study over simulated records: the harness, how many records, how long,
    how noisy (the callers add their own)."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--records", type=int, default=records)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--noise", type=float, default=0.03)
    return ap


def mac(a, b):
    import numpy as np
    a, b = np.asarray(a, complex), np.asarray(b, complex)
    return abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("field", help="directory with displacement.csv (and truth.csv)")
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--nperseg", type=int, default=2048)
    ap.add_argument("--check", action="store_true", help="exit 1 when a check fails")
    ap.add_argument("--force", action="store_true")
    args = ap.parse_args()
    harness = str(Path(args.harness).resolve())
    ensure_venv()
    import logging
    import warnings
    import numpy as np
    logging.disable(logging.CRITICAL)
    warnings.filterwarnings("ignore")
    from pyoma2.algorithms import EFDD, FDD, SSI, pLSCF
    from pyoma2.setup import SingleSetup

    field = Path(args.field)
    out_md = field / "peer-oma.md"
    if out_md.exists() and not args.force:
        sys.exit(f"{out_md} exists: --force to replace it")
    data, fs = read_wide(field / "displacement.csv")
    df = fs / args.nperseg

    # ours: SSI-cov (with FDD and EFDD), then SSI-dat (its SSI modes only)
    ours = {}
    ours_s = {}
    for ssi in ("cov", "dat"):
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            more = ["--plscf"] if ssi == "cov" else []
            subprocess.run([harness, "modal", "--displacement", str(field / "displacement.csv"),
                            "--nperseg", str(args.nperseg), "--ssi", ssi, "--no-plots", "--out",
                            str(Path(tmp) / "m")] + more, check=True, capture_output=True)
            ours_s[ssi] = time.perf_counter() - t0
            modes = list(csv.DictReader(open(Path(tmp) / "m" / "modes.csv")))
            shapes = list(csv.DictReader(open(Path(tmp) / "m" / "shapes.csv")))
        for m in modes:
            if ssi == "dat" and m["method"] != "ssi":
                continue
            shape = [complex(float(r["re"]), float(r["im"])) for r in shapes
                     if r["method"] == m["method"] and r["mode"] == m["mode"]]
            name = "ssi-dat" if ssi == "dat" else m["method"]
            ours.setdefault(name, []).append(
                (float(m["f_hz"]), float(m["damping"]) if m["damping"] else None, shape))
    sel = [f for f, _, _ in ours.get("ssi", [])]
    sel_dat = [f for f, _, _ in ours.get("ssi-dat", [])]
    sel_plscf = [f for f, _, _ in ours.get("plscf", [])]

    # pyOMA-2 on the same records
    t0 = time.perf_counter()
    setup = SingleSetup(data, fs=fs)
    algs = {
        "fdd": FDD(name="FDD", nxseg=args.nperseg, method_SD="per", pov=0.5),
        "efdd": EFDD(name="EFDD", nxseg=args.nperseg, method_SD="per", pov=0.5),
        "ssi": SSI(name="SSI", br=30, ordmax=40, method="cov"),
        "ssi-dat": SSI(name="SSIdat", br=30, ordmax=40, method="dat"),
        # its matrix-fraction form, order 20 of 5x5 blocks; half-spectra ("cor")
        "plscf": pLSCF(name="pLSCF", ordmax=20, nxseg=args.nperseg, method_SD="cor"),
    }
    setup.add_algorithms(*algs.values())
    setup.run_all()
    setup.mpe("FDD", sel_freq=sel)
    setup.mpe("EFDD", sel_freq=sel)
    setup.mpe("SSI", sel_freq=sel, order_in="find_min")
    setup.mpe("SSIdat", sel_freq=sel_dat, order_in="find_min")
    if sel_plscf:
        setup.mpe("pLSCF", sel_freq=sel_plscf, order=19)
    peer_s = time.perf_counter() - t0

    truth = {}
    if (field / "truth.csv").exists():
        for r in csv.DictReader(open(field / "truth.csv")):
            truth.setdefault(int(r["mode"]), (float(r["f_hz"]), float(r["damping"])))

    lines = [f"Same file: {len(data)} samples at {fs:g} Hz, {data.shape[1]} targets; segments of "
             f"{args.nperseg} (lines {df:.4f} Hz). Wall time: ours {ours_s['cov']:.2f} s (the "
             f"`modal` process with SSI-cov and pLSCF, no figures; {ours_s['dat']:.2f} s with "
             f"SSI-dat), pyOMA-2 {peer_s:.2f} s (setup, run, mpe of its five methods).", "",
             "| method | mode | truth f, damping | ours f | pyOMA-2 f | diff, lines | ours damping "
             "| pyOMA-2 damping | ratio | MAC ours/pyOMA-2 |",
             "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    failures = []
    for method, alg in algs.items():
        r = alg.result
        if r is None or r.Fn is None:
            continue
        fn = np.atleast_1d(r.Fn)
        xi = np.atleast_1d(getattr(r, "Xi", None)) if getattr(r, "Xi", None) is not None else None
        phi = np.asarray(r.Phi)
        for i, f_peer in enumerate(fn):
            mine = min(ours.get(method, []), key=lambda m: abs(m[0] - f_peer), default=None)
            if mine is None:
                failures.append(f"{method}: no mode of ours near {f_peer:.4f} Hz")
                continue
            f, z, shape = mine
            dl = abs(f - f_peer) / df
            mc = mac(shape, phi[:, i])
            zp = float(xi[i]) if xi is not None else None
            ratio = z / zp if (z and zp) else None
            tr = min(truth.values(), key=lambda v: abs(v[0] - f_peer), default=None)
            lines.append(
                f"| {method} | {i + 1} | {'' if tr is None else f'{tr[0]:.4f}, {tr[1]:.4f}'} "
                f"| {f:.4f} | {f_peer:.4f} | {dl:.2f} | {'' if z is None else f'{z:.4f}'} "
                f"| {'' if zp is None else f'{zp:.4f}'} | {'' if ratio is None else f'{ratio:.3f}'} "
                f"| {mc:.5f} |")
            # FDD's and EFDD's frequencies are compared, not checked: FDD picks a line on the
            # flat top of a damped bell, pyOMA-2's EFDD is biased (docs/method.md §3.12)
            if method.startswith("ssi") and dl > 1.0:
                failures.append(f"{method} mode {i + 1}: {dl:.2f} lines apart")
            if mc < 0.99 and method != "plscf":
                failures.append(f"{method} mode {i + 1}: MAC {mc:.4f}")
            if method.startswith("ssi") and ratio is not None and abs(ratio - 1) > 0.10:
                failures.append(f"{method} mode {i + 1}: damping ratio {ratio:.3f}")
    finish(lines, failures, out_md, args.check)


def finish(lines, failures, md, check):
    """Prints the table `lines` and each failure, writes the table to `md`; exit status 1 when
    `check` and anything failed."""
    text = "\n".join(lines)
    print(text)
    for f in failures:
        print("FAIL:", f)
    md.write_text(text + "\n")
    if check and failures:
        sys.exit(1)


if __name__ == "__main__":
    main()

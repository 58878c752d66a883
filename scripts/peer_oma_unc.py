#!/usr/bin/env python3
"""The standard uncertainties of SSI-cov's frequencies and damping ratios: ours (the jackknife
over ten groups of the record, `modal`'s `f_hz_u` and `damping_u`) beside pyOMA-2's
first-order propagation (`SSI(calc_unc=True)`, Doehler & Mevel 2013), both beside the real
spread of the estimates over records whose truth is known. Run on demand; the figures go to
docs/validation.md §3.

    python3 scripts/peer_oma_unc.py --harness target/release/host-harness \\
        [--records 20] [--minutes 10] [--noise 0.03] [--case shear-frame] [--out DIR]

Per seed `host-harness simulate-field` writes a record; `modal` (no bands) gives our SSI modes
and their uncertainties; pyOMA-2 1.4.3 runs SSI-cov on the same displacement (30 block rows,
orders 2 to 40 in steps of 2, `calc_unc=True` with its default 50 blocks) and `mpe` at our SSI
frequencies (`order_in="find_min"`), giving `Fn_std` and `Xi_std`. Per true mode: the standard
deviation of each side's estimates over the records (what a standard uncertainty should be),
the mean of our `u` and of pyOMA-2's std. Runs in the virtual environment of
scripts/peer_oma.py ($PEER_OMA_VENV, else .venv-peer-oma). Writes DIR/peer-oma-unc.md.
"""
import csv
import subprocess
from pathlib import Path

from peer_oma import ensemble_parser, ensure_venv, read_wide, simulate_field

def main():
    ap = ensemble_parser(__doc__)
    ap.add_argument("--case", default="shear-frame")
    ap.add_argument("--out", default="target/peer-oma-unc")
    args = ap.parse_args()
    harness = str(Path(args.harness).resolve())
    ensure_venv(__file__)
    import logging
    import warnings
    import numpy as np
    logging.disable(logging.CRITICAL)
    warnings.filterwarnings("ignore")
    from pyoma2.algorithms.ssi import SSI
    from pyoma2.setup.single import SingleSetup

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    per_mode = {}
    for seed in range(args.records):
        rec = out / f"{args.case}-{seed}"
        truth = simulate_field(harness, args.case, args.minutes, args.noise, 7000 + seed, rec)
        subprocess.run([harness, "modal", "--displacement", str(rec / "displacement.csv"),
                        "--no-plots", "--out", str(rec / "m"), "--force"], check=True,
                       capture_output=True)
        ours = [m for m in csv.DictReader(open(rec / "m" / "modes.csv")) if m["method"] == "ssi"]
        data, fs = read_wide(rec / "displacement.csv")
        setup = SingleSetup(data, fs=fs)
        ssi = SSI(name="SSI", br=30, ordmin=2, ordmax=40, step=2, method="cov", calc_unc=True)
        setup.add_algorithms(ssi)
        setup.run_all()
        setup.mpe("SSI", sel_freq=[float(m["f_hz"]) for m in ours], order_in="find_min")
        res = ssi.result
        fn, xi = np.atleast_1d(res.Fn), np.atleast_1d(res.Xi)
        fn_std, xi_std = np.atleast_1d(res.Fn_std), np.atleast_1d(res.Xi_std)
        for k, (f_true, z_true) in truth.items():
            o = min(ours, key=lambda m: abs(float(m["f_hz"]) - f_true))
            i = int(np.argmin(abs(fn - f_true)))
            if abs(float(o["f_hz"]) - f_true) > 3 * z_true * f_true or o["f_hz_u"] == "":
                continue
            per_mode.setdefault(k, []).append((
                float(o["f_hz"]), float(o["f_hz_u"]), float(o["damping"]), float(o["damping_u"]),
                float(fn[i]), float(fn_std[i]), float(xi[i]), float(xi_std[i])))
        print(f"seed {seed}: {len(ours)} modes", flush=True)
    lines = [f"{args.records} records of {args.case}, {args.minutes:g} minutes at 60 Hz, noise "
             f"{args.noise:g}", "",
             "| mode | f: sd of ours | f: our u (mean) | f: sd of pyOMA-2's | f: pyOMA-2 std (mean) "
             "| damping: sd of ours | our u | sd of pyOMA-2's | pyOMA-2 std |",
             "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for k in sorted(per_mode):
        a = np.array(per_mode[k])
        sd = lambda c: float(np.std(a[:, c], ddof=1)) if len(a) > 1 else float("nan")
        mean = lambda c: float(np.mean(a[:, c]))
        lines.append(f"| {k} | {sd(0):.2e} | {mean(1):.2e} | {sd(4):.2e} | {mean(5):.2e} | "
                     f"{sd(2):.2e} | {mean(3):.2e} | {sd(6):.2e} | {mean(7):.2e} |")
    text = "\n".join(lines)
    (out / "peer-oma-unc.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()

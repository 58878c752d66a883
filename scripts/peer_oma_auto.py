#!/usr/bin/env python3
"""Output-only analysis without bands beside pyOMA-2's automatic clustering, on the same files:
how often each side reports exactly the structure's modes, and the wall time of both. Run on
demand; the figures go to docs/method.md §3.12 and docs/performance.md.

    python3 scripts/peer_oma_auto.py --harness target/release/host-harness \\
        [--records 20] [--minutes 10] [--noise 0.03] [--cases shear-frame,weak-high-mode] \\
        [--threads 1|default] [--out DIR]

Per field case and seed, `host-harness simulate-field` writes a record and its truth; `modal`
without `--bands` analyses it (ours: SSI-cov's clusters and EFDD, the process timed); pyOMA-2
1.4.3 runs SSI-cov on the same displacement (30 block rows, orders 2 to 40 in steps of 2, as
ours) and its automatic clustering `Clustering(quick="hier_avg")` (hierarchical, average
linkage, with its post-processing), timed from the array in memory (setup, SSI, clustering).
pyOMA-2's FDD and EFDD need the frequencies given (`sel_freq`): they have no automatic mode,
so only SSI is compared. A method reports "exactly the true modes" when it gives as many modes
as the truth and each true mode is matched by one within max(3 lines, 3 zeta f) and nearer than
half the distance to another true mode (as examples/oma_auto.rs counts).

`--threads 1` sets OMP/OPENBLAS/MKL/RAYON threads to 1 on both sides (the fair comparison of
the algorithms); `--threads default` leaves numpy's BLAS its default threads. Runs in a
virtual environment of scripts/peer_oma.py (pinned pyOMA-2: $PEER_OMA_VENV, else .venv-peer-oma
at the repository root, created with pip when missing). Writes DIR/peer-oma-auto.md (default
target/peer-oma-auto).
"""
import csv
import subprocess
import time
from pathlib import Path

from peer_oma import ensemble_parser, ensure_venv, read_wide, simulate_field

THREADS = ["OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "RAYON_NUM_THREADS"]


def exact(truth, found, df):
    """(exact, extra, missing) of the frequencies `found` against `truth` [(f, zeta)]."""
    used = [False] * len(found)
    missing = []
    for f, z in truth:
        gap = min([abs(o - f) / 2 for o, _ in truth if o != f] + [float("inf")])
        tol = min(max(3 * df, 3 * z * f), gap)
        best = None
        for i, g in enumerate(found):
            if not used[i] and abs(g - f) <= tol and (best is None or abs(g - f) < abs(found[best] - f)):
                best = i
        if best is None:
            missing.append(f)
        else:
            used[best] = True
    extra = [g for g, u in zip(found, used) if not u]
    return (not extra and not missing), extra, missing


def main():
    ap = ensemble_parser(__doc__)
    ap.add_argument("--cases", default="shear-frame,close-modes,weak-high-mode")
    ap.add_argument("--threads", choices=["1", "default"], default="1")
    ap.add_argument("--out", default="target/peer-oma-auto")
    args = ap.parse_args()
    harness = str(Path(args.harness).resolve())
    # the thread count must be set before numpy is imported: in the re-run's environment
    ensure_venv(__file__, {name: "1" for name in THREADS} if args.threads == "1" else None)
    import logging
    import warnings
    import numpy as np
    logging.disable(logging.CRITICAL)
    warnings.filterwarnings("ignore")
    from pyoma2.algorithms.data.run_params import Clustering
    from pyoma2.algorithms.ssi import SSI
    from pyoma2.setup.single import SingleSetup

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    lines = [
        f"{args.records} records per case, {args.minutes:g} minutes at 60 Hz, noise "
        f"{args.noise:g}; threads: {args.threads} (BLAS and ours)", "",
        "| case | ours SSI exact | ours EFDD exact | pyOMA-2 hier_avg exact | ours s/record "
        "| pyOMA-2 s/record | ratio |", "|---|---:|---:|---:|---:|---:|---:|"]
    details = []
    for case in args.cases.split(","):
        counts = {"ssi": 0, "efdd": 0, "peer": 0}
        t_ours = t_peer = 0.0
        for seed in range(args.records):
            rec = out / f"{case}-{seed}"
            truth = simulate_field(harness, case, args.minutes, args.noise, 5000 + seed, rec)
            truth = [truth[k] for k in sorted(truth)]
            data, fs = read_wide(rec / "displacement.csv")
            t0 = time.perf_counter()
            subprocess.run([harness, "modal", "--displacement", str(rec / "displacement.csv"),
                            "--no-plots", "--out", str(rec / "m"), "--force"], check=True,
                           capture_output=True)
            t_ours += time.perf_counter() - t0
            ours = {"ssi": [], "efdd": []}
            for m in csv.DictReader(open(rec / "m" / "modes.csv")):
                if m["method"] in ours:
                    ours[m["method"]].append(float(m["f_hz"]))
            report = (rec / "m" / "report.txt").read_text()
            df = float(report.split("line spacing ")[1].split(" Hz")[0])
            t0 = time.perf_counter()
            setup = SingleSetup(data, fs=fs)
            ssi = SSI(name="SSI", br=30, ordmin=2, ordmax=40, step=2, method="cov")
            ssi.add_clustering(Clustering(name="hier_avg", quick="hier_avg"))
            setup.add_algorithms(ssi)
            setup.run_all()
            ssi.run_all_clustering()
            peer = sorted(np.atleast_1d(ssi.result.clustering_results["hier_avg"].Fn).tolist())
            t_peer += time.perf_counter() - t0
            for key, found in [("ssi", ours["ssi"]), ("efdd", ours["efdd"]), ("peer", peer)]:
                ok, extra, missing = exact(truth, found, df)
                counts[key] += ok
                if not ok:
                    details.append(f"- {case} seed {5000 + seed}, {key}: extra "
                                   f"{[round(x, 3) for x in extra]}, missing "
                                   f"{[round(x, 3) for x in missing]}")
            print(f"{case} {seed}: ours ssi {len(ours['ssi'])} efdd {len(ours['efdd'])}, "
                  f"pyOMA-2 {len(peer)}", flush=True)
        n = args.records
        lines.append(f"| {case} | {counts['ssi']}/{n} | {counts['efdd']}/{n} | "
                     f"{counts['peer']}/{n} | {t_ours / n:.2f} | {t_peer / n:.2f} | "
                     f"{t_peer / t_ours:.1f} |")
    text = "\n".join(lines + [""] + (details or ["(no record missed a mode or had one extra)"]))
    (out / "peer-oma-auto.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Several setups merged by PoSER and by PreGER: ours (`host-harness modal --references
--setup --merge poser|preger`) beside pyOMA-2's `MultiSetup_PoSER` and `MultiSetup_PreGER`
on the same files, and both beside the truth. Run on demand (and in CI with --check); the
tables go to docs/validation.md §10.

    python3 scripts/peer_multisetup.py OUT --harness target/release/host-harness [--check]

Three `simulate-field` records of the five-storey shear frame (seeds 11, 12, 13; 10 minutes;
3 % noise) play three setups of one structure: each keeps storeys 1 and 2 (the references)
and one other (setup 1 storey 3, setup 2 storey 4 in the first column, setup 3 storey 5 in the
last), so that each setup's reference columns are elsewhere in its file. Both sides run
SSI-cov with 30 block rows and orders up to 40, merged by PoSER or identified together by
PreGER (`SSI_MS`); with PreGER also FDD and EFDD of the global spectra (pyOMA-2's `FDD_MS`
and `EFDD_MS`: segments of 2048, periodograms, half overlap) and pLSCF (ours `--plscf`,
pyOMA-2's `pLSCF_MS(ordmax=20, method_SD="cor")` read at its order 19). pyOMA-2's
parameters are taken at our merged frequencies of each method (`mpe` with `sel_freq`; SSI
`order_in="find_min"`).
The global points of both are the references, then each setup's other point (storeys 1 to
5). Writes OUT/s1.csv, s2.csv, s3.csv, truth.csv and peer-multisetup.md (replaced only with
--force). Exit status 1 with --check when a merged mode of ours is more than one line from the
truth's (SSI also from pyOMA-2's), a method misses a mode, or a global shape's MAC with the
truth is under 0.99.
"""
import argparse
import csv
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from peer_oma import ensure_venv, finish, mac, read_wide

ONE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                "RAYON_NUM_THREADS")} | {"TQDM_DISABLE": "1"}
# per setup: the storeys kept (1-based), the references (storeys 1 and 2) among them
SETUPS = [[1, 2, 3], [4, 2, 1], [2, 1, 5]]
NPERSEG = 2048


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="directory to write (created)")
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--check", action="store_true", help="exit 1 when a check fails")
    ap.add_argument("--force", action="store_true", help="replace the files of an earlier run")
    args = ap.parse_args()
    out = Path(args.out)
    md = out / "peer-multisetup.md"
    if md.exists() and not args.force:
        sys.exit(f"{md} exists: --force to replace it")
    ensure_venv(__file__, ONE_THREAD)
    import logging
    import warnings
    global np
    import numpy as np
    logging.disable(logging.CRITICAL)
    warnings.filterwarnings("ignore")
    harness = str(Path(args.harness).resolve())
    out.mkdir(parents=True, exist_ok=True)
    files, refs = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for i, keep in enumerate(SETUPS):
            rec = Path(tmp) / f"r{i}"
            subprocess.run([harness, "simulate-field", "--minutes", "10", "--noise", "0.03",
                            "--seed", str(11 + i), "--out", str(rec)], check=True,
                           capture_output=True)
            rows = list(csv.reader(open(rec / "displacement.csv")))
            cols = [0] + keep
            f = out / f"s{i + 1}.csv"
            with open(f, "w") as w:
                w.write("t_s," + ",".join(str(c + 1) for c in range(len(keep))) + "\n")
                for r in rows[1:]:
                    w.write(",".join(r[c] for c in cols) + "\n")
            files.append(f)
            refs.append([keep.index(1), keep.index(2)])
            if i == 0:
                (out / "truth.csv").write_text((rec / "truth.csv").read_text())
    truth = {}
    for r in csv.DictReader(open(out / "truth.csv")):
        m = truth.setdefault(int(r["mode"]), [float(r["f_hz"]), float(r["damping"]), []])
        m[2].append(float(r["shape"]))

    lines, failures = [], []
    for merge in ("poser", "preger"):
        ours, ours_s = run_ours(harness, files, refs, merge)
        peer, peer_s = run_peer(files, refs, merge, ours)
        fs = read_wide(files[0])[1]
        df = fs / NPERSEG
        what = {"poser": "three setups' SSI-cov, mpe and PoSER",
                "preger": "PreGER's SSI-cov of the three setups together, FDD_MS, EFDD_MS "
                          "and pLSCF_MS of its global spectra, and mpe"}[merge]
        lines += [f"**{merge}**: three setups of {len(read_wide(files[0])[0])} samples at "
                  f"{fs:g} Hz (lines of {df:.4f} Hz); references storeys 1 and 2. Wall time: "
                  f"ours {ours_s:.2f} s (the `modal` process, three setups, no figures), "
                  f"pyOMA-2 {peer_s:.2f} s ({what}).", "",
                  "| method | mode | truth f, damping | ours f | pyOMA-2 f | diff, lines | "
                  "ours damping | pyOMA-2 damping | MAC ours/pyOMA-2 | MAC ours/truth | "
                  "MAC pyOMA-2/truth |",
                  "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for method, (fn, xi, phi) in peer.items():
            for i, (f, z, shape) in enumerate(ours[method]):
                k = int(np.argmin(np.abs(fn - f)))
                t = min(truth.values(), key=lambda v: abs(v[0] - f))
                m_peer, m_true = mac(shape, phi[:, k]), mac(shape, t[2])
                m_peer_true = mac(phi[:, k], t[2])
                zs = "" if z is None else f"{z:.4f}"
                zp = "" if xi is None else f"{xi[k]:.4f}"
                lines.append(f"| {method} | {i + 1} | {t[0]:.4f}, {t[1]:.4f} | {f:.4f} | "
                             f"{fn[k]:.4f} | {abs(f - fn[k]) / df:.2f} | {zs} | {zp} | "
                             f"{m_peer:.5f} | {m_true:.5f} | {m_peer_true:.5f} |")
                # SSI is checked beside pyOMA-2 and the truth; FDD (a line on a damped bell's
                # flat top) and EFDD (pyOMA-2's is biased, docs/method.md §3.12) beside the
                # truth only
                off_peer = method == "ssi" and abs(f - fn[k]) > df
                if off_peer or abs(f - t[0]) > df:
                    failures.append(f"{merge} {method} mode {i + 1}: {f:.4f} Hz, pyOMA-2 "
                                    f"{fn[k]:.4f}, truth {t[0]:.4f}")
                if m_true < 0.99:
                    failures.append(f"{merge} {method} mode {i + 1}: MAC with the truth "
                                    f"{m_true:.4f}")
            if len(ours[method]) != len(truth):
                failures.append(f"{merge}: {len(ours[method])} merged {method} modes, the truth "
                                f"has {len(truth)}")
        lines.append("")
    finish(lines, failures, md, args.check)


def run_ours(harness, files, refs, merge):
    """Our merged modes per method, `{method: [(f, damping or None, shape)]}`, and the `modal`
    process's wall time."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [harness, "modal", "--displacement", str(files[0]), "--references",
               ",".join(str(c + 1) for c in refs[0]), "--nperseg", str(NPERSEG), "--no-plots",
               "--merge", merge, "--out", str(Path(tmp) / "m")]
        if merge == "preger":
            cmd.append("--plscf")
        for f, r in zip(files[1:], refs[1:]):
            cmd += ["--setup", f"{f}:{','.join(str(c + 1) for c in r)}"]
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        took = time.perf_counter() - t0
        modes = list(csv.DictReader(open(Path(tmp) / "m" / "modes.csv")))
        shapes = list(csv.DictReader(open(Path(tmp) / "m" / "shapes.csv")))
    ours = {}
    for m in modes:
        shape = [complex(float(r["re"]), float(r["im"])) for r in shapes
                 if r["mode"] == m["mode"] and r["method"] == m["method"]]
        z = float(m["damping"]) if m["damping"] else None
        ours.setdefault(m["method"], []).append((float(m["f_hz"]), z, shape))
    return ours, took


def run_peer(files, refs, merge, ours):
    """pyOMA-2's merged modes at our frequencies: SSI-cov (30 block rows, orders to 40) by
    PoSER or PreGER, and with PreGER FDD_MS and EFDD_MS of its global spectra (our segments,
    periodograms, half overlap); `{method: (frequencies, damping or None, global shapes as
    columns)}` and its wall time."""
    from pyoma2.algorithms import EFDD_MS, FDD_MS, SSI, SSI_MS, pLSCF_MS
    from pyoma2.setup import MultiSetup_PoSER, MultiSetup_PreGER, SingleSetup
    sel = {m: [f for f, _, _ in ours.get(m, [])] for m in ("ssi", "fdd", "efdd", "plscf")}
    t0 = time.perf_counter()
    if merge == "poser":
        singles = []
        for f in files:
            data, fs = read_wide(f)
            ss = SingleSetup(data, fs=fs)
            ss.add_algorithms(SSI(name="SSI", br=30, ordmax=40, method="cov"))
            ss.run_all()
            ss.mpe("SSI", sel_freq=sel["ssi"], order_in="find_min")
            singles.append(ss)
        msp = MultiSetup_PoSER(ref_ind=refs, single_setups=singles, names=["SSI"])
        results = {"ssi": msp.merge_results()["SSI"]}
    else:
        data = [read_wide(f)[0] for f in files]
        msp = MultiSetup_PreGER(fs=read_wide(files[0])[1], ref_ind=refs, datasets=data)
        msp.add_algorithms(SSI_MS(name="SSI", br=30, ordmax=40, method="cov"),
                           FDD_MS(name="FDD", nxseg=NPERSEG, method_SD="per", pov=0.5),
                           EFDD_MS(name="EFDD", nxseg=NPERSEG, method_SD="per", pov=0.5),
                           pLSCF_MS(name="PLSCF", ordmax=20, nxseg=NPERSEG, method_SD="cor"))
        msp.run_all()
        msp.mpe("SSI", sel_freq=sel["ssi"], order_in="find_min")
        msp.mpe("FDD", sel_freq=sel["fdd"])
        msp.mpe("EFDD", sel_freq=sel["efdd"])
        msp.mpe("PLSCF", sel_freq=sel["plscf"], order=19)
        results = {m: msp.algorithms[m.upper()].result for m in ("ssi", "fdd", "efdd", "plscf")}
    took = time.perf_counter() - t0
    out = {}
    for m, r in results.items():
        xi = getattr(r, "Xi", None)
        out[m] = (np.atleast_1d(r.Fn), None if xi is None else np.atleast_1d(xi),
                  np.asarray(r.Phi))
    return out, took


if __name__ == "__main__":
    main()

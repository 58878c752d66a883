#!/usr/bin/env python3
"""Output-only intervals checked on records that `simulate-field` did not make: a damped chain of
six masses in state space, sampled exactly, through `modal`; per method and mode, how often the
95 % intervals of frequency and damping hold the truth and how wide they are against the spread
of the estimates. Run on demand; the figures go to docs/validation.md §3.

    python3 scripts/chain_ensemble.py --harness target/release/host-harness \\
        [--records 40] [--minutes 10] [--fs 50] [--noise 0.05] [--quantity displacement] \\
        [--out DIR] [--force]

The model (independent of `vibcam-model`'s modal superposition): six masses on springs in a row,
the first tied to the ground, stiffnesses found so that the first four natural frequencies are
2.3, 5.9, 9.4 and 13.1 Hz; modal damping 0.8, 1.2, 2.5 and 1.6 % (2 % for the two upper modes);
every mass driven by its own white force. The state `[x, v]` is sampled exactly at `fs` (Van
Loan's matrix exponential gives the transition and the covariance of the sampled noise, so there
is neither integration error nor aliasing of the model), started from its stationary covariance.
The six outputs are the masses' displacements (or velocities, `--quantity`; accelerations are
those of forces held over each sample, the force's own share included), each with white
measurement noise of `--noise` times its own RMS. Per record a wide CSV
(`t_s,1..6`) goes through `modal --no-plots`; each reported mode is matched to the nearest true
mode within 3 %. "covered" counts `x +- 1.96 u`; the last column the reported intervals' own
ends (Student's t of the jackknife). Writes DIR/chain-ensemble.md (and keeps DIR/records/ with each record's
`modal` output).
"""
import argparse
import csv
import shutil
import subprocess
import sys
from pathlib import Path

TARGET_HZ = [2.3, 5.9, 9.4, 13.1]
DAMPING = [0.008, 0.012, 0.025, 0.016, 0.02, 0.02]


def chain(np, least_squares):
    """Masses, stiffnesses and the undamped modes of the chain (frequencies in Hz, mass-normalised
    shapes)."""
    n = 6
    m = np.array([1.0, 1.0, 0.9, 0.8, 0.8, 0.7])

    def stiffness(logk):
        k = np.exp(logk)
        kk = np.zeros((n, n))
        for i in range(n):
            kk[i, i] += k[i]
            if i > 0:
                kk[i - 1, i - 1] += k[i]
                kk[i - 1, i] -= k[i]
                kk[i, i - 1] -= k[i]
        return kk

    def modes(logk):
        from scipy.linalg import eigh
        w2, phi = eigh(stiffness(logk), np.diag(m))
        return np.sqrt(w2) / (2 * np.pi), phi

    def residual(logk):
        f, _ = modes(logk)
        return np.log(f[:4] / np.array(TARGET_HZ))

    k0 = np.log(np.full(n, (2 * np.pi * 8.0) ** 2))
    fit = least_squares(residual, k0)
    f, phi = modes(fit.x)
    return m, stiffness(fit.x), f, phi


def sampled_system(np, expm, m, k, f_hz, phi, fs):
    """The exact discrete transition `Ad` and the Cholesky factor of the sampled noise's
    covariance, for unit white forces on every mass."""
    n = len(m)
    w = 2 * np.pi * f_hz
    mm = np.diag(m)
    c = mm @ phi @ np.diag(2 * np.array(DAMPING) * w) @ phi.T @ mm
    minv = np.diag(1 / m)
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ c]])
    b = np.vstack([np.zeros((n, n)), minv])
    dt = 1.0 / fs
    big = np.block([[-a, b @ b.T], [np.zeros((2 * n, 2 * n)), a.T]]) * dt
    e = expm(big)
    ad = e[2 * n:, 2 * n:].T
    qd = ad @ e[:2 * n, 2 * n:]
    qd = 0.5 * (qd + qd.T)
    return a, ad, np.linalg.cholesky(qd + 1e-18 * np.eye(2 * n) * np.trace(qd))


def record(np, a, ad, lq, m, k, samples, quantity, noise, rng):
    """One record of the six outputs, `samples` long, from the stationary state."""
    from scipy.linalg import solve_discrete_lyapunov
    n = len(m)
    p = solve_discrete_lyapunov(ad, lq @ lq.T)
    x = np.linalg.cholesky(0.5 * (p + p.T)) @ rng.standard_normal(2 * n)
    noise_in = rng.standard_normal((samples, 2 * n)) @ lq.T
    states = np.empty((samples, 2 * n))
    for i in range(samples):
        states[i] = x
        x = ad @ x + noise_in[i]
    if quantity == "displacement":
        y = states[:, :n]
    elif quantity == "velocity":
        y = states[:, n:]
    else:
        raise ValueError(quantity)
    y = y + noise * y.std(axis=0) * rng.standard_normal(y.shape)
    return y


def accelerations(np, expm, a, m, fs, samples, rng):
    """The masses' accelerations under white forces held over each sample (zero-order hold,
    sampled exactly): `x[k+1] = Ad x[k] + Bd u[k]`, `y[k] = Ca x[k] + M^-1 u[k]`, so the spectrum
    is the accelerance's, force term included (white forces in continuous time have no sampled
    acceleration)."""
    from scipy.linalg import solve_discrete_lyapunov
    n = len(m)
    b = np.vstack([np.zeros((n, n)), np.diag(1 / m)])
    big = np.zeros((3 * n, 3 * n))
    big[:2 * n, :2 * n] = a
    big[:2 * n, 2 * n:] = b
    e = expm(big / fs)
    ad, bd = e[:2 * n, :2 * n], e[:2 * n, 2 * n:]
    p = solve_discrete_lyapunov(ad, bd @ bd.T)
    x = np.linalg.cholesky(0.5 * (p + p.T) + 1e-15 * np.trace(p) * np.eye(2 * n)) @ \
        rng.standard_normal(2 * n)
    u = rng.standard_normal((samples, n))
    drive = u @ bd.T
    states = np.empty((samples, 2 * n))
    for i in range(samples):
        states[i] = x
        x = ad @ x + drive[i]
    return states @ a[n:, :].T + u @ np.diag(1 / m)



def read_modes(path):
    rows = []
    with open(path) as fh:
        for r in csv.DictReader(fh):
            rows.append(r)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--harness", default="target/release/host-harness")
    ap.add_argument("--records", type=int, default=40)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--fs", type=float, default=50.0)
    ap.add_argument("--noise", type=float, default=0.05)
    ap.add_argument("--quantity", choices=["displacement", "velocity", "acceleration"],
                    default="displacement")
    ap.add_argument("--modal-args", default="", help="extra flags for `modal`, one string")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default="target/chain-ensemble")
    ap.add_argument("--force", action="store_true", help="replace an earlier DIR")
    args = ap.parse_args()
    import numpy as np
    from scipy.linalg import expm
    from scipy.optimize import least_squares

    out = Path(args.out)
    if out.exists():
        if not args.force:
            sys.exit(f"{out} exists: pass --force to replace it")
        shutil.rmtree(out)
    (out / "records").mkdir(parents=True)
    harness = str(Path(args.harness).resolve())
    m, k, f_true, phi = chain(np, least_squares)
    a, ad, lq = sampled_system(np, expm, m, k, f_true, phi, args.fs)
    samples = int(round(args.minutes * 60 * args.fs))
    rng = np.random.default_rng(args.seed)
    found = {}  # (method, mode) -> list of (f, f_u, d, d_u)
    for rec in range(args.records):
        if args.quantity == "acceleration":
            y = accelerations(np, expm, a, m, args.fs, samples, rng)
            y = y + args.noise * y.std(axis=0) * rng.standard_normal(y.shape)
        else:
            y = record(np, a, ad, lq, m, k, samples, args.quantity, args.noise, rng)
        d = out / "records" / f"{rec:03}"
        d.mkdir()
        t = np.arange(samples) / args.fs
        np.savetxt(d / "record.csv", np.column_stack([t, y]), delimiter=",", fmt="%.9g",
                   header="t_s," + ",".join(str(i + 1) for i in range(y.shape[1])), comments="")
        subprocess.run([harness, "modal", "--displacement", str(d / "record.csv"), "--out",
                        str(d / "modal"), "--no-plots"] + args.modal_args.split(),
                       check=True, capture_output=True)
        (d / "record.csv").unlink()
        for r in read_modes(d / "modal" / "modes.csv"):
            if r["method"] not in ("efdd", "ssi", "plscf") or not r.get("f_hz_u"):
                continue
            f = float(r["f_hz"])
            j = int(np.argmin(abs(f_true - f) / f_true))
            if abs(f - f_true[j]) > 0.03 * f_true[j]:
                continue
            dmp = float(r["damping"]) if r["damping"] else float("nan")
            du = float(r["damping_u"]) if r.get("damping_u") else float("nan")
            num = lambda k: float(r[k]) if r.get(k) else float("nan")  # noqa: E731
            # whether the reported 95 % interval's own ends (Student's t) hold the truth
            f_in = num("f_hz_lo") <= f_true[j] <= num("f_hz_hi")
            d_in = num("damping_lo") <= DAMPING[j] <= num("damping_hi")
            found.setdefault((r["method"], j), []).append(
                (f, float(r["f_hz_u"]), dmp, du, f_in, d_in))
        print(f"record {rec + 1}/{args.records}", file=sys.stderr)
    lines = [f"# Chain ensemble: {args.records} records of {args.minutes} min at {args.fs} Hz, "
             f"{args.quantity}, noise {args.noise}", "",
             "| method | mode | truth f, damping | found | f bias % (sd) | f covered | "
             "f width/spread | damping bias % | damping covered | damping width/spread | "
             "held within the reported ends: f, damping |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for (method, j), rows in sorted(found.items()):
        v = np.array(rows)
        f0, z0 = f_true[j], DAMPING[j]
        fb = (v[:, 0].mean() / f0 - 1) * 100
        fsd = v[:, 0].std(ddof=1) / f0 * 100 if len(v) > 1 else float("nan")
        fcov = np.mean(abs(v[:, 0] - f0) <= 1.96 * v[:, 1]) * 100
        fw = v[:, 1].mean() / (v[:, 0].std(ddof=1)) if len(v) > 1 else float("nan")
        ok = ~np.isnan(v[:, 2]) & ~np.isnan(v[:, 3])
        dv = v[ok]
        db = (dv[:, 2].mean() / z0 - 1) * 100 if len(dv) else float("nan")
        dcov = np.mean(abs(dv[:, 2] - z0) <= 1.96 * dv[:, 3]) * 100 if len(dv) else float("nan")
        dw = dv[:, 3].mean() / dv[:, 2].std(ddof=1) if len(dv) > 1 else float("nan")
        f_ends = np.mean(v[:, 4]) * 100
        d_ends = np.mean(dv[:, 5]) * 100 if len(dv) else float("nan")
        lines.append(f"| {method} | {j + 1} | {f0:.4f}, {z0:.3f} | {len(v)} | {fb:+.3f} "
                     f"({fsd:.3f}) | {fcov:.0f} % | {fw:.2f} | {db:+.1f} | {dcov:.0f} % | "
                     f"{dw:.2f} | {f_ends:.0f} %, {d_ends:.0f} % |")
    text = "\n".join(lines) + "\n"
    (out / "chain-ensemble.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()

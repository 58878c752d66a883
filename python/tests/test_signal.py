"""vibcam.frf and vibcam.upsample against scipy: the committed fixtures that firmware-core's
own tests read (scripts/gen_welch_fixtures.py, scripts/gen_resample_fixtures.py), with those
tests' tolerances, and scipy run here on a record of its own."""

import csv

import numpy as np
import pytest
import scipy.signal as sig

import vibcam
from conftest import ROOT

WELCH = ROOT / "firmware-core" / "tests" / "fixtures" / "welch"
RESAMPLE = ROOT / "firmware-core" / "tests" / "fixtures" / "resample"


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return rows


def welch_cases():
    return read_csv(WELCH / "cases.csv")


def check_h1(f, h, c, ref_f, ref_h, ref_coh, ref_pxx, name):
    """firmware-core/tests/welch_scipy.rs's criterion: bins equal, H1 and coherence within
    1e-4 (relative) where the coherence exceeds 0.1 and x has energy."""
    assert len(f) == len(ref_f), name
    np.testing.assert_allclose(f, ref_f, rtol=1e-6, atol=1e-9, err_msg=name)
    keep = (ref_coh > 0.1) & (ref_pxx > 1e-10 * ref_pxx.max())
    assert keep.sum() > 0, name
    e_h = np.abs(h[keep] - ref_h[keep]) / np.abs(ref_h[keep])
    e_c = np.abs(c[keep] - ref_coh[keep]) / ref_coh[keep]
    assert e_h.max() < 1e-4, f"{name}: H1 relative error {e_h.max():.2e}"
    assert e_c.max() < 1e-4, f"{name}: coherence relative error {e_c.max():.2e}"


@pytest.mark.parametrize("case", welch_cases(), ids=lambda c: c["name"])
def test_frf_equals_the_scipy_fixtures(case):
    data = read_csv(WELCH / "input.csv")
    n = int(case["n"])
    x = np.array([float(r["x"]) for r in data[:n]])
    y = np.array([float(r["y"]) for r in data[:n]])
    window = {"boxcar": "rect"}.get(case["window"], case["window"])
    f, h, c = vibcam.frf(
        x, y, float(case["fs_hz"]), window=window, nperseg=int(case["nperseg"]),
        noverlap=int(case["noverlap"]), nfft=int(case["nfft"]), detrend=case["detrend"],
    )
    ref = read_csv(WELCH / f"{case['name']}.csv")
    col = lambda k: np.array([float(r[k]) for r in ref])  # noqa: E731
    check_h1(
        f, h, c, col("freq_hz"), col("h1_re") + 1j * col("h1_im"), col("coherence"),
        col("pxx"), case["name"],
    )


@pytest.mark.parametrize(
    "window,nperseg,noverlap,nfft,detrend",
    [("hann", 512, None, None, "constant"), ("hamming", 300, 100, 600, "none"),
     ("rect", 1000, 500, 1024, "constant")],
)
def test_frf_equals_scipy_run_here(window, nperseg, noverlap, nfft, detrend):
    rng = np.random.default_rng(7)
    fs = 2048.0
    # f32-exact input, so that the f32 estimator and scipy's f64 see the same numbers
    x = rng.standard_normal(20000).astype(np.float32).astype(np.float64) + 0.3
    b, a = sig.iirpeak(150.0, 8.0, fs)
    y = (sig.lfilter(b, a, x) + 0.05 * rng.standard_normal(x.size)).astype(np.float32)
    y = y.astype(np.float64)
    f, h, c = vibcam.frf(x, y, fs, window=window, nperseg=nperseg, noverlap=noverlap,
                         nfft=nfft, detrend=detrend)
    sw = {"rect": "boxcar"}.get(window, window)
    kw = dict(fs=fs, window=sw, nperseg=nperseg, noverlap=noverlap, nfft=nfft,
              detrend=False if detrend == "none" else detrend)
    ff, pxy = sig.csd(x, y, **kw)
    _, pxx = sig.welch(x, **kw)
    _, pyy = sig.welch(y, **kw)
    check_h1(f, h, c, ff, pxy / pxx, np.abs(pxy) ** 2 / (pxx * pyy), pxx, window)


def test_frf_defaults_are_scipys():
    rng = np.random.default_rng(3)
    x = rng.standard_normal(3000).astype(np.float32).astype(np.float64)
    y = np.roll(x, 2)
    f, h, c = vibcam.frf(x, y, 100.0)
    ff, pxy = sig.csd(x, y, fs=100.0)
    _, pxx = sig.welch(x, fs=100.0)
    assert len(f) == len(ff) == 129
    check_h1(f, h, c, ff, pxy / pxx, np.abs(pxy) ** 2 / (pxx * sig.welch(y, fs=100.0)[1]),
             pxx, "defaults")


@pytest.mark.parametrize("case", read_csv(RESAMPLE / "cases.csv"), ids=lambda c: c["name"])
def test_upsample_equals_the_scipy_fixtures(case):
    """firmware-core/tests/resample_scipy.rs's criterion: max |error| / RMS < 1e-4."""
    name, n, m = case["name"], int(case["n"]), int(case["m"])
    x = np.loadtxt(RESAMPLE / f"{name}_x.csv")
    want = np.loadtxt(RESAMPLE / f"{name}_y.csv")
    got = vibcam.upsample(x, float(n), float(m))
    assert got.shape == (m,)
    err = np.abs(got - want).max() / np.sqrt(np.mean(want ** 2))
    assert err < 1e-4, f"{name}: {err:.2e}"


def test_upsample_equals_scipy_run_here():
    rng = np.random.default_rng(11)
    x = rng.standard_normal(120) * 1e3
    got = vibcam.upsample(x, 120, 2048)
    want = sig.resample(x, 2048)
    err = np.abs(got - want).max() / np.sqrt(np.mean(want ** 2))
    assert err < 1e-4, err


def test_signal_errors_are_input_errors():
    x = np.zeros(100)
    with pytest.raises(vibcam.InputError, match="one length"):
        vibcam.frf(x, x[:50], 10.0)
    with pytest.raises(vibcam.InputError, match="window `tukey`"):
        vibcam.frf(x, x, 10.0, window="tukey")
    x[3] = np.nan
    with pytest.raises(vibcam.InputError, match=r"x\[3\] is NaN"):
        vibcam.frf(x, np.ones(100), 10.0)
    with pytest.raises(vibcam.InputError, match="integer number of samples"):
        vibcam.upsample(np.ones(10), 3.0, 7.0)
    with pytest.raises(ValueError):  # InputError is a ValueError
        vibcam.upsample(np.ones(10), -1.0, 7.0)

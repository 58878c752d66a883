//! The streaming Welch H1 estimator against `scipy.signal.csd` / `scipy.signal.welch`.
//!
//! Fixtures: `tests/fixtures/welch/`, written by `scripts/gen_welch_fixtures.py` (see its header
//! for how to regenerate them). Every window (Hann, Hamming, rectangular), both detrend modes,
//! overlaps from 0 to 94 %, `nfft > nperseg`, and non-power-of-two `nperseg` / `nfft` (the
//! grandstand's 1111/555/5000, 4800, 97, 1000) are covered.
//!
//! Acceptance: H1 within 1e-4 relative on every bin whose coherence is above
//! 0.1, and the coherence within 1e-4 relative there. Bins where scipy's own Pxx is below 1e-10
//! of its maximum are skipped: they are mathematically empty (the DC bin of a rectangular window
//! after mean removal) and both implementations only return rounding noise there. The Pxx and
//! Pyy shapes are also checked against scipy's density scaling, `2 sum|X|^2 / (K fs sum w^2)`.

use firmware_core::spectrum::{scratch_capacity, Detrend, WelchConfig, WelchH1, Window};
use firmware_core::Complex32;
use std::path::{Path, PathBuf};

/// One instantiation large enough for every case (largest nperseg 4800, nfft 5000; the
/// Bluestein length 5000 needs the most scratch).
type Welch = WelchH1<4800, 5000, { scratch_capacity(5000) }>;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/welch")
}

/// Header and rows of a small numeric-or-text CSV file.
fn read_csv(name: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(dir().join(name))
        .unwrap_or_else(|e| panic!("{name}: {e} (run scripts/gen_welch_fixtures.py)"));
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

fn col(header: &[String], name: &str) -> usize {
    header.iter().position(|h| h == name).expect(name)
}

struct Case {
    name: String,
    config: WelchConfig,
    n: usize,
}

fn cases() -> Vec<Case> {
    let (h, rows) = read_csv("cases.csv");
    rows.iter()
        .map(|r| {
            let get = |c: &str| r[col(&h, c)].as_str();
            let window = match get("window") {
                "hann" => Window::Hann,
                "hamming" => Window::Hamming,
                "boxcar" => Window::Rect,
                w => panic!("unknown window {w}"),
            };
            let detrend = match get("detrend") {
                "constant" => Detrend::Constant,
                "none" => Detrend::None,
                d => panic!("unknown detrend {d}"),
            };
            Case {
                name: get("name").to_string(),
                config: WelchConfig {
                    fs_hz: get("fs_hz").parse().unwrap(),
                    nperseg: get("nperseg").parse().unwrap(),
                    noverlap: get("noverlap").parse().unwrap(),
                    nfft: get("nfft").parse().unwrap(),
                    window,
                    detrend,
                },
                n: get("n").parse().unwrap(),
            }
        })
        .collect()
}

fn input() -> (Vec<f32>, Vec<f32>) {
    let (h, rows) = read_csv("input.csv");
    let (cx, cy) = (col(&h, "x"), col(&h, "y"));
    // 9 significant digits round-trip f32: these are exactly the values scipy used
    rows.iter()
        .map(|r| (r[cx].parse::<f32>().unwrap(), r[cy].parse::<f32>().unwrap()))
        .unzip()
}

struct Reference {
    freq: Vec<f64>,
    pxx: Vec<f64>,
    pyy: Vec<f64>,
    h1: Vec<(f64, f64)>,
    coherence: Vec<f64>,
}

fn reference(name: &str) -> Reference {
    let (h, rows) = read_csv(&format!("{name}.csv"));
    let get = |c: &str| -> Vec<f64> {
        let i = col(&h, c);
        rows.iter().map(|r| r[i].parse().unwrap()).collect()
    };
    let (re, im) = (get("h1_re"), get("h1_im"));
    Reference {
        freq: get("freq_hz"),
        pxx: get("pxx"),
        pyy: get("pyy"),
        h1: re.into_iter().zip(im).collect(),
        coherence: get("coherence"),
    }
}

fn window_power(c: &WelchConfig) -> f64 {
    (0..c.nperseg)
        .map(|j| {
            let ph = 2.0 * std::f64::consts::PI * j as f64 / c.nperseg as f64;
            match c.window {
                Window::Hann => 0.5 - 0.5 * ph.cos(),
                Window::Hamming => 0.54 - 0.46 * ph.cos(),
                _ => 1.0,
            }
        })
        .map(|w| w * w)
        .sum()
}

#[test]
fn fixtures_cover_what_the_issue_asks() {
    let cases = cases();
    for w in [Window::Hann, Window::Hamming, Window::Rect] {
        assert!(cases.iter().any(|c| c.config.window == w), "{w:?}");
    }
    for d in [Detrend::Constant, Detrend::None] {
        assert!(cases.iter().any(|c| c.config.detrend == d), "{d:?}");
    }
    assert!(cases.iter().any(|c| c.config.nfft > c.config.nperseg));
    assert!(cases
        .iter()
        .any(|c| (c.config.nperseg, c.config.noverlap, c.config.nfft) == (1111, 555, 5000)));
    assert!(cases.iter().any(|c| !c.config.nfft.is_power_of_two()));
}

#[test]
fn h1_and_coherence_match_scipy() {
    let (x, y) = input();
    let mut report = Vec::new();
    for case in cases() {
        let c = case.config;
        let r = reference(&case.name);
        let (x, y) = (&x[..case.n], &y[..case.n]);
        let mut w = Box::new(Welch::try_new(c).unwrap_or_else(|e| panic!("{}: {e}", case.name)));
        // odd-sized chunks, to exercise the streaming path on real data too
        for (a, b) in x.chunks(777).zip(y.chunks(777)) {
            w.push(a, b).unwrap();
        }
        let step = c.nperseg - c.noverlap;
        let segments = (case.n - c.nperseg) / step + 1;
        assert_eq!(
            w.accumulator().segments() as usize,
            segments,
            "{}",
            case.name
        );
        assert_eq!(w.accumulator().bins(), r.freq.len(), "{}", case.name);

        let pxx_max = r.pxx.iter().cloned().fold(0.0, f64::max);
        let pyy_max = r.pyy.iter().cloned().fold(0.0, f64::max);
        let density = 1.0 / (segments as f64 * c.fs_hz as f64 * window_power(&c));
        let (mut worst_h1, mut worst_coh, mut worst_p, mut checked) = (0.0f64, 0.0f64, 0.0f64, 0);
        for k in 0..w.accumulator().bins() {
            assert!(
                (w.accumulator().freq(k) as f64 - r.freq[k]).abs() <= 1e-6 * r.freq[k].max(1.0),
                "{} bin {k}: {} Hz vs {}",
                case.name,
                w.accumulator().freq(k),
                r.freq[k]
            );
            // density scaling, one-sided doubling except DC and (even nfft) Nyquist
            let s = w.accumulator().sums(k).unwrap();
            let one_sided = if k == 0 || 2 * k == c.nfft { 1.0 } else { 2.0 };
            for (ours, theirs, max) in [(s.pxx, r.pxx[k], pxx_max), (s.pyy, r.pyy[k], pyy_max)] {
                if theirs > 1e-4 * max {
                    let e = (ours as f64 * density * one_sided - theirs).abs() / theirs;
                    worst_p = worst_p.max(e);
                    assert!(e < 1e-4, "{} bin {k}: P {ours} vs {theirs}", case.name);
                }
            }
            let coh_ref = r.coherence[k];
            if !(coh_ref > 0.1 && r.pxx[k] > 1e-10 * pxx_max) {
                continue;
            }
            checked += 1;
            let h: Complex32 = w.accumulator().h1(k).unwrap();
            let (hr, hi) = r.h1[k];
            let mag = (hr * hr + hi * hi).sqrt();
            let e = ((h.re as f64 - hr).powi(2) + (h.im as f64 - hi).powi(2)).sqrt() / mag;
            worst_h1 = worst_h1.max(e);
            assert!(
                e < 1e-4,
                "{} bin {k}: H1 {h} vs ({hr}, {hi}): relative error {e:e}",
                case.name
            );
            let coh = w.accumulator().coherence(k).unwrap() as f64;
            let e = (coh - coh_ref).abs() / coh_ref;
            worst_coh = worst_coh.max(e);
            assert!(
                e < 1e-4,
                "{} bin {k}: coherence {coh} vs {coh_ref}: relative error {e:e}",
                case.name
            );
        }
        assert!(checked > 0, "{}: no bin with coherence > 0.1", case.name);
        report.push(format!(
            "{:32} segments {segments:5} bins checked {checked:5}/{:5}  max rel err H1 {worst_h1:.1e} coherence {worst_coh:.1e} Pxx/Pyy {worst_p:.1e}",
            case.name,
            w.accumulator().bins()
        ));
    }
    // visible with --nocapture; the figures quoted in the README come from here
    println!("{}", report.join("\n"));
}

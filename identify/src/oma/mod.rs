//! Output-only (operational) modal analysis of K displacement records (docs/method.md §3.12):
//! frequencies, damping and shapes without a measured input, by FDD, EFDD and SSI-cov. Pure
//! functions on in-memory records; `analyze` without `--accel` and `modal` write their results.
//!
//! ```text
//! K records ──> Welch cross-spectral matrix per line ([csd]) ──> singular values and first
//!   singular vector per line ([fdd]) ──> peaks (bands, or prominence over the floor)
//!   ──> FDD: the peak's line and vector; EFDD: the bell back to a correlation function
//! K records ──> correlations, block Toeplitz, SVD, models of orders 2..n ([ssi])
//!   ──> poles stable in frequency, damping and shape ──> clustered into modes
//! ```

pub mod bell;
pub mod cluster;
pub mod csd;
pub mod decay;
pub mod fdd;
pub mod lscf;
pub mod many;
pub mod modes;
pub mod plscf;
pub mod preger;
pub mod preger_spectral;
pub mod setups;
pub mod ssi;
pub mod ssi_dat;
#[cfg(test)]
pub(crate) mod test_records;
pub mod uncertainty;

use cluster::{ClusterRule, SsiMode};
use csd::{Csd, CsdConfig};
use fdd::{EfddRule, PeakRule, Svd};
use num_complex::Complex64;
use ssi::{Pole, SsiRule};

/// The method a mode was identified by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Method {
    /// Frequency domain decomposition: the peak's line and first singular vector.
    Fdd,
    /// Enhanced FDD: frequency and damping from the peak's bell.
    Efdd,
    /// Covariance-driven stochastic subspace identification.
    Ssi,
    /// The record's free decays identified together in the time domain ([`decay`]).
    Decay,
    /// LSCF on the half-spectra of a few reference channels ([`plscf`]).
    Plscf,
}

impl Method {
    /// The name in `modes.csv` and `shapes.csv`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Fdd => "fdd",
            Method::Efdd => "efdd",
            Method::Ssi => "ssi",
            Method::Decay => "decay",
            Method::Plscf => "plscf",
        }
    }
}

/// What measured the records, for the notes on modes that may be a tracker's harmonics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RecordSource {
    /// A displacement file: how it was measured is not known.
    #[default]
    File,
    /// The binary centroid (blob): its pixel locking is a staircase in the motion, which makes
    /// odd harmonics and intermodulation products of strong modes.
    Blob,
    /// A tracker linear in the motion (the weighted centroid, Lucas-Kanade), named.
    Linear(&'static str),
}

/// Settings of an output-only analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct OmaSettings {
    /// Sample rate of the records, Hz.
    pub fs_hz: f64,
    /// The cross-spectral matrix's Welch settings.
    pub csd: CsdConfig,
    /// Bands, Hz: one mode per band and method; empty: peaks picked by `peaks`.
    pub bands: Vec<(f64, f64)>,
    /// The automatic peak rule (without bands).
    pub peaks: PeakRule,
    /// EFDD settings.
    pub efdd: EfddRule,
    /// SSI-cov settings.
    pub ssi: SsiRule,
    /// The rules that make clusters of SSI-cov's stable poles modes.
    pub cluster: ClusterRule,
    /// LSCF on half-spectra, when asked ([`plscf`]; its clusters by `cluster`).
    pub plscf: Option<lscf::LscfRule>,
    /// Groups of the jackknife that gives each estimate its uncertainty (0: none).
    pub groups: usize,
    /// What measured the records (the notes on harmonics).
    pub source: RecordSource,
    /// `$poles`: SSI's modes exactly these (frequency and damping as given), each one's shape
    /// the diagram's stable pole nearest it ([`modes::ssi_modes`]); `None`: the clusters.
    pub poles: Option<Vec<crate::modal::Pole>>,
}

impl OmaSettings {
    /// Defaults for records at `fs_hz` of `samples` samples: Welch with Hann segments of
    /// `nperseg` (default: the largest power of two with at least 8 half-overlapping segments,
    /// at most 4096), peaks from `max(0.5 Hz, 2 lines)` to the Nyquist frequency at 6 dB of
    /// prominence (then checked: [`modes`]); SSI-cov with 30 block rows (fewer for short
    /// records), orders up to 40, stable at 1 % in frequency, 5 % in damping, MAC 0.98, damping
    /// below 20 %, clustered by [`ClusterRule::default`].
    pub fn new(fs_hz: f64, samples: usize, nperseg: Option<usize>) -> OmaSettings {
        let nperseg = nperseg.unwrap_or_else(|| {
            let mut n = 4096usize;
            while n > 16 && 9 * n / 2 > samples {
                n /= 2;
            }
            n.min(samples.max(1))
        });
        let df = fs_hz / nperseg as f64;
        let block_rows = 30usize.min(samples / 8).max(2);
        OmaSettings {
            fs_hz,
            csd: CsdConfig {
                window: firmware_core::spectrum::Window::Hann,
                nperseg,
                noverlap: nperseg / 2,
                nfft: nperseg,
                detrend: firmware_core::spectrum::Detrend::Constant,
            },
            bands: Vec::new(),
            peaks: PeakRule {
                f_min_hz: (0.5f64).max(2.0 * df),
                f_max_hz: fs_hz / 2.0,
                prominence_db: 6.0,
                over_floor_db: None,
            },
            efdd: EfddRule::default(),
            ssi: SsiRule {
                block_rows,
                max_order: 40,
                df_max: 0.01,
                dz_max: 0.05,
                mac_min: 0.98,
                zeta_max: 0.2,
                f_range_hz: ((0.5f64).max(2.0 * df), fs_hz / 2.0),
                kind: ssi::SsiKind::Cov,
            },
            cluster: ClusterRule::default(),
            plscf: None,
            groups: uncertainty::GROUPS,
            source: RecordSource::File,
            poles: None,
        }
    }
}

impl OmaSettings {
    /// [`OmaSettings::new`] with the Welch flags applied (window, detrend, segment, overlap,
    /// transform length; half overlap and no padding when not given), the lowest frequency
    /// from the resulting line spacing. Not checked against the record: the callers name
    /// their own flags in the errors.
    pub fn with_welch(fs_hz: f64, samples: usize, w: &vibcam_chain::frf::WelchSettings) -> Self {
        let mut s = OmaSettings::new(fs_hz, samples, w.nperseg);
        s.csd.window = w.window;
        s.csd.detrend = w.detrend;
        s.csd.noverlap = w.noverlap.unwrap_or(s.csd.nperseg / 2);
        s.csd.nfft = w.nfft.unwrap_or(s.csd.nperseg);
        let df = fs_hz / s.csd.nfft as f64;
        s.peaks.f_min_hz = (0.5f64).max(2.0 * df);
        s.ssi.f_range_hz.0 = s.peaks.f_min_hz;
        s
    }
}

/// One identified mode.
#[derive(Debug, Clone, PartialEq)]
pub struct OmaMode {
    /// How it was identified.
    pub method: Method,
    /// Mode number, 1-based, per method in order of frequency (or the band's number).
    pub mode: usize,
    /// The band, Hz (with bands).
    pub band_hz: Option<(f64, f64)>,
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// First singular value at the peak (FDD and EFDD).
    pub amplitude: Option<f64>,
    /// Damping ratio (EFDD and SSI).
    pub damping: Option<f64>,
    /// Shape at the K channels, normalised (largest component 1).
    pub shape: Vec<Complex64>,
    /// How it was found (a peak's prominence and bell, a cluster's size and spread), for the
    /// report.
    pub evidence: String,
    /// Its statistical uncertainty from the record (the jackknife, [`uncertainty`]).
    pub uncertainty: uncertainty::Uncertainty,
}

/// Everything an output-only analysis found.
#[derive(Debug, Clone)]
pub struct OmaResult {
    /// The record's free decays (none for a stationary response).
    pub decays: Vec<decay::Decay>,
    /// The cross-spectral matrix.
    pub csd: Csd,
    /// Its singular values per line.
    pub svd: Svd,
    /// The lines of the FDD peaks.
    pub peaks: Vec<usize>,
    /// The modes, by method then frequency.
    pub modes: Vec<OmaMode>,
    /// SSI-cov's poles of every order (the stabilisation diagram).
    pub poles: Vec<Pole>,
    /// SSI-cov's clusters of stable poles: reported as a mode (true) or rejected.
    pub clusters: Vec<(SsiMode, bool)>,
    /// Peaks and clusters not taken for modes (without bands), each with its reason.
    pub rejected: Vec<String>,
    /// Notes for the report (a band without a mode, an EFDD that failed).
    pub notes: Vec<String>,
    /// The quantity EFDD's bells were fitted as, and how it was chosen.
    pub quantity: modes::QuantityChoice,
    /// pLSCF's reference channels, 0-based (empty when it did not run).
    pub plscf_references: Vec<usize>,
}

impl OmaResult {
    /// The mode of `method` nearest `f_hz`, if one lies within `within` Hz of it (how a
    /// study matches what was found to a true mode).
    pub fn nearest(&self, method: Method, f_hz: f64, within: f64) -> Option<&OmaMode> {
        self.modes
            .iter()
            .filter(|m| m.method == method && (m.f_hz - f_hz).abs() <= within)
            .min_by(|a, b| (a.f_hz - f_hz).abs().total_cmp(&(b.f_hz - f_hz).abs()))
    }
}

/// The shortest segment (`--nperseg`) an output-only analysis takes, samples.
pub const MIN_SEGMENT: usize = 64;

/// The analysis settings of `channels` at `fs_hz` with the Welch settings as given: the one
/// place the segment rules live (`modal` and `analyze` without an accelerometer). A record
/// shorter than [`MIN_SEGMENT`] without a free decay, a segment given shorter than it or longer than the
/// record, an overlap not below the segment, a transform shorter than it: refused, naming the
/// setting (`record`: how the message names the record).
pub fn segment_settings(
    fs_hz: f64,
    channels: &[Vec<f64>],
    welch: &vibcam_chain::frf::WelchSettings,
    record: &str,
) -> anyhow::Result<OmaSettings> {
    use vibcam_common::setting::SpecError;
    let refuse = |t: String| Err(SpecError::setting(t).into_anyhow());
    let n = channels.first().map_or(0, Vec::len);
    // a record of free decays is identified in the time domain ([`decay`]): one decay is
    // enough, however short the record; the spectra then have few lines
    if n < MIN_SEGMENT && decay::find_decays(channels).is_empty() {
        return refuse(format!(
            "{record} has {n} samples, fewer than one segment of {MIN_SEGMENT} (the shortest \
             analysed), and no free decay (a decay alone, of {} samples or more, is analysed \
             however short)",
            decay::MIN_DECAY_SAMPLES
        ));
    }
    if let Some(given) = welch.nperseg.filter(|g| *g < MIN_SEGMENT) {
        return refuse(format!(
            "$nperseg {given}: a segment of at least {MIN_SEGMENT} samples is needed"
        ));
    }
    let s = OmaSettings::with_welch(fs_hz, n, welch);
    if s.csd.nperseg > n {
        return refuse(format!(
            "$nperseg {}: the record has only {n} samples, fewer than one segment",
            s.csd.nperseg
        ));
    }
    if s.csd.noverlap >= s.csd.nperseg {
        return refuse(format!(
            "$noverlap {} must be smaller than $nperseg {}",
            s.csd.noverlap, s.csd.nperseg
        ));
    }
    if s.csd.nfft < s.csd.nperseg {
        return refuse(format!(
            "$nfft {} must be at least $nperseg {}",
            s.csd.nfft, s.csd.nperseg
        ));
    }
    Ok(s)
}

/// The most iterations an eigenvalue or singular value decomposition may take (nalgebra's
/// own default is none: a matrix it cannot reduce, of non-finite or degenerate values, would
/// be iterated for ever).
pub const MAX_ITERATIONS: usize = 100_000;

/// The power of two nearest the RMS of `channels` (means removed): the records are divided by
/// it before any numerics (exactly: a power of two), so that the analysis of a record in
/// metres, micrometres or pixels is the same. A record without motion, or whose spectra (its
/// square) would not be finite, is an error.
pub(crate) fn record_scale(channels: &[Vec<f64>]) -> anyhow::Result<f64> {
    let (mut sum, mut count) = (0.0f64, 0usize);
    for c in channels {
        let m = c.iter().sum::<f64>() / c.len().max(1) as f64;
        // squares that overflow (or vanish) are the refusal below: the spectra would too
        sum += c.iter().map(|v| (v - m).powi(2)).sum::<f64>();
        count += c.len();
    }
    let rms = (sum / count.max(1) as f64).sqrt();
    let scale = 2f64.powi(rms.log2().round() as i32);
    if !(rms > 0.0 && rms.is_finite() && (scale * scale).is_finite() && scale * scale > 0.0) {
        return Err(vibcam_readers::bad_input(format!(
            "the records' RMS is {rms:e}: an output-only analysis needs records that move, \
             with values whose squares are finite (between about 1e-150 and 1e150; rescale \
             the record)"
        )));
    }
    Ok(scale)
}

/// Output-only analysis of `channels` (one record per target, equal lengths). The records are
/// scaled by a power of two before the numerics (the power of two nearest their RMS) and the spectra and
/// amplitudes scaled back: the same modes whatever the record's unit. More than
/// [`many::MAX_FULL_CHANNELS`] channels are analysed on references ([`many`]).
pub fn analyze(channels: &[Vec<f64>], s: &OmaSettings) -> anyhow::Result<OmaResult> {
    if channels.len() > many::MAX_FULL_CHANNELS {
        return many::analyze(channels, s);
    }
    let (scaled, scale) = scaled_record(channels)?;
    // found on the records as given (the decays' amplitudes in their unit; the rule is one
    // of ratios)
    let decays = decay::find_decays(channels);
    let mut r = analyze_scaled(&scaled, &decays, s)?;
    scale_back((&mut r.csd, &mut r.svd, &mut r.modes), scale * scale);
    Ok(r)
}

/// `channels` divided by their power of two ([`record_scale`]), and that scale.
pub(crate) fn scaled_record(channels: &[Vec<f64>]) -> anyhow::Result<(Vec<Vec<f64>>, f64)> {
    let scale = record_scale(channels)?;
    let scaled = channels
        .iter()
        .map(|c| c.iter().map(|v| v / scale).collect())
        .collect();
    Ok((scaled, scale))
}

/// The spectra, singular values and amplitudes found on scaled records ([`scaled_record`])
/// back in the records' unit: times `power`, the scale squared.
pub(crate) fn scale_back((csd, svd, modes): (&mut Csd, &mut fdd::Svd, &mut [OmaMode]), power: f64) {
    for line in &mut csd.g {
        for v in line.iter_mut() {
            *v *= power;
        }
    }
    for line in &mut svd.s {
        for v in line.iter_mut() {
            *v *= power;
        }
    }
    for m in modes {
        m.amplitude = m.amplitude.map(|a| a * power);
        m.uncertainty.amplitude = m.uncertainty.amplitude.map(|i| i.scaled(power));
    }
}

/// [`analyze`] of records of RMS near 1: SSI-cov first (its modes support the peaks that
/// stand less than 10 dB), then the peaks, FDD and EFDD.
fn analyze_scaled(
    channels: &[Vec<f64>],
    decays: &[decay::Decay],
    s: &OmaSettings,
) -> anyhow::Result<OmaResult> {
    let csd = csd::csd_matrix(channels, s.fs_hz, s.csd)?;
    let svd = fdd::decompose(&csd)?;
    let (mut notes, mut rejected) = (Vec::new(), Vec::new());
    let ssi = modes::ssi_modes((channels, &svd), s, &mut notes, &mut rejected)?;
    let decay_modes = match decays.is_empty() {
        true => Vec::new(),
        false => decay::decay_modes(channels, decays, s, &mut notes, &mut rejected)?,
    };
    let peaks = if s.bands.is_empty() {
        modes::automatic_peaks(&svd, s, &ssi.modes, &mut rejected)
    } else {
        modes::banded_peaks(&svd, csd.df_hz(), s, &mut notes)
    };
    let quantity = modes::choose_quantity(&svd, &peaks, s);
    let resolved = OmaSettings {
        efdd: EfddRule {
            quantity: Some(quantity.quantity),
            ..s.efdd
        },
        ..s.clone()
    };
    let s = &resolved;
    let mut found = modes::fdd_modes(&svd, &peaks, s, &mut notes);
    found.extend(ssi.modes);
    found.sort_by(|a, b| a.method.cmp(&b.method).then(a.f_hz.total_cmp(&b.f_hz)));
    let intervals = uncertainty::of_modes(
        (channels, &csd),
        s,
        (&found, &ssi.lone),
        &peaks,
        s.groups,
        &mut notes,
    )?;
    for (m, u) in found.iter_mut().zip(intervals) {
        m.uncertainty = u;
    }
    // the decays' and pLSCF's own intervals (the jackknife over the decays, over segments)
    found.extend(decay_modes);
    let (plscf, plscf_references) =
        plscf::plscf_modes((channels, &csd), s, &found, &mut notes, &mut rejected)?;
    found.extend(plscf);
    found.sort_by(|a, b| a.method.cmp(&b.method).then(a.f_hz.total_cmp(&b.f_hz)));
    notes.extend(harmonic_notes(&found, csd.df_hz(), s.source));
    notes.extend(common_motion_notes(&found, &svd, s));
    Ok(OmaResult {
        decays: decays.to_vec(),
        csd,
        svd,
        peaks: peaks.iter().map(|p| p.line).collect(),
        modes: found,
        poles: ssi.poles,
        clusters: ssi.clusters,
        rejected,
        notes,
        quantity,
        plscf_references,
    })
}

/// A mode's shape this alike at every target (MAC with all targets moving as one) is named as
/// a common motion.
pub const COMMON_MOTION_MAC: f64 = 0.95;

/// MAC of `shape` with every target moving as one.
fn mac_with_all(shape: &[Complex64]) -> f64 {
    let n = shape.len() as f64;
    let sum: Complex64 = shape.iter().sum();
    let norm: f64 = shape.iter().map(|c| c.norm_sqr()).sum();
    if norm > 0.0 {
        sum.norm_sqr() / (n * norm)
    } else {
        0.0
    }
}

/// Warnings on modes, and on peaks of the first singular value not taken as modes, whose
/// shape is the same at every target (three or more targets, MAC >= [`COMMON_MOTION_MAC`]
/// with a rigid shift of all of them): the camera's own motion (a tripod in the wind, traffic)
/// moves every target alike, and so does a structure moving as one; the references
/// (`--reference`) take the camera's out. Such a peak inside a mode's bell biases that
/// mode's damping.
pub fn common_motion_notes(modes: &[OmaMode], svd: &fdd::Svd, s: &OmaSettings) -> Vec<String> {
    const FIX: &str = "the camera's own motion (a tripod in the wind, traffic), not the \
        structure's, unless the whole structure moves as one; give $reference (windows on \
        parts of the scene that do not move) to take the camera's motion out";
    let mut out = Vec::new();
    let mut warned: Vec<f64> = Vec::new();
    for m in modes.iter().filter(|m| m.shape.len() >= 3) {
        let mac = mac_with_all(&m.shape);
        if mac >= COMMON_MOTION_MAC {
            out.push(format!(
                "warning: {} mode {} at {:.4} Hz moves every target alike (MAC {mac:.3} with \
                 all of them moving as one): {FIX}",
                m.method.name(),
                m.mode,
                m.f_hz
            ));
            warned.push(m.f_hz);
        }
    }
    if svd.u1.first().map_or(0, Vec::len) < 3 {
        return out;
    }
    let df = svd.freq_hz.get(1).copied().unwrap_or(0.0);
    for (l, prominence) in fdd::pick_peaks(svd, s.peaks) {
        let f = svd.freq_hz[l];
        if warned.iter().any(|w| (w - f).abs() <= 3.0 * df) {
            continue;
        }
        let mac = mac_with_all(&svd.u1[l]);
        if mac >= COMMON_MOTION_MAC {
            out.push(format!(
                "warning: the peak of the first singular value at {f:.4} Hz ({prominence:.1} \
                 dB; not a mode above) moves every target alike (MAC {mac:.3} with all of them \
                 moving as one), and biases any mode whose bell it lies in: {FIX}"
            ));
            warned.push(f);
        }
    }
    out
}

/// The nearest intermodulation product `a fa + b fb` of two lower modes (odd order up to 5)
/// to `hi` within its tolerance `tol`: the two modes, `a`, `b` and its frequency.
#[allow(clippy::type_complexity)]
fn nearest_product<'a>(
    hi: &OmaMode,
    lower: &[&'a OmaMode],
    tol: &dyn Fn(f64, &OmaMode) -> f64,
) -> Option<(&'a OmaMode, &'a OmaMode, i32, i32, f64)> {
    let mut product: Option<(&OmaMode, &OmaMode, i32, i32, f64)> = None;
    for (i, fa) in lower.iter().enumerate() {
        for fb in &lower[i + 1..] {
            for (a, b) in (-5i32..=5).flat_map(|a| (-5i32..=5).map(move |b| (a, b))) {
                let order = a.abs() + b.abs();
                if a == 0 || b == 0 || order % 2 == 0 || order > 5 {
                    continue;
                }
                let f = f64::from(a) * fa.f_hz + f64::from(b) * fb.f_hz;
                let t = tol(f64::from(a.abs()), fa).max(tol(f64::from(b.abs()), fb));
                let nearer = product.is_none_or(|p| (hi.f_hz - f).abs() < (hi.f_hz - p.4).abs());
                if f > 0.0 && (hi.f_hz - f).abs() <= t && nearer {
                    product = Some((fa, fb, a, b, f));
                }
            }
        }
    }
    product
}

/// Notes on modes that may be harmonics of a lower mode of the same method: a frequency within
/// `max(1.5 lines, n zeta f)` of `n = 2..=7` times the lower mode's (`zeta` its damping, 1 %
/// where the method gives none) and, with three or more targets, a shape with MAC >= 0.5 to
/// the lower mode's. A tracker that is not linear in the motion (the binary centroid's pixel
/// locking) turns a strong narrow-band mode into odd harmonics that SSI and FDD take for modes
/// (docs/method.md §3.12); such modes are kept but named. With the binary centroid
/// (`source`), its intermodulation products are named too: a frequency at `|a fa + b fb|` of
/// two lower modes, `|a| + |b|` odd and at most 5 (`2 f1 + f2`, `2 f2 - f1`, ...), whatever
/// the shape (a staircase applied to the sum of the modes makes them at every target).
pub fn harmonic_notes(modes: &[OmaMode], df_hz: f64, source: RecordSource) -> Vec<String> {
    let mut notes = Vec::new();
    let why = match source {
        RecordSource::Blob => {
            "made by the binary centroid's pixel locking (a staircase in the motion), not a \
             mode: $tracker weighted or lk makes none"
                .to_string()
        }
        RecordSource::Linear(name) => format!(
            "made by a non-linearity (of the structure, or of the {name} tracker on a target \
             that is not rigid or uniformly lit), or a mode of its own: check it against a \
             model or a second measurement"
        ),
        RecordSource::File => "made by a tracker or a structure that is not linear in the \
             motion (the binary centroid's pixel locking makes them; $tracker weighted or lk \
             makes none), not a mode"
            .to_string(),
    };
    for (j, hi) in modes.iter().enumerate() {
        let targets = hi.shape.len();
        let lower: Vec<&OmaMode> = modes[..j]
            .iter()
            .filter(|lo| lo.method == hi.method && lo.f_hz < hi.f_hz)
            .collect();
        let tol =
            |n: f64, lo: &OmaMode| (1.5 * df_hz).max(n * lo.damping.unwrap_or(0.01) * lo.f_hz);
        let harmonic = lower.iter().find_map(|lo| {
            let n = (hi.f_hz / lo.f_hz).round();
            if !(2.0..=7.0).contains(&n) || (hi.f_hz - n * lo.f_hz).abs() > tol(n, lo) {
                return None;
            }
            let m = crate::modal::mac(&lo.shape, &hi.shape);
            (targets < 3 || m >= 0.5).then_some((*lo, n as usize, m))
        });
        if let Some((lo, n, m)) = harmonic {
            let shape = if targets < 3 {
                "too few targets to compare the shapes".to_string()
            } else {
                format!("its shape has MAC {m:.2} with mode {}'s", lo.mode)
            };
            notes.push(format!(
                "{} mode {} ({:.4} Hz) is {n} x mode {} ({:.4} Hz) and {shape}: possibly a \
                 harmonic {why}",
                hi.method.name(),
                hi.mode,
                hi.f_hz,
                lo.mode,
                lo.f_hz
            ));
            continue;
        }
        if source != RecordSource::Blob {
            continue;
        }
        let product = nearest_product(hi, &lower, &tol);
        if let Some((fa, fb, a, b, f)) = product {
            let term = |c: i32, m: &OmaMode| match c {
                1 => format!("f{}", m.mode),
                -1 => format!("- f{}", m.mode),
                c if c < 0 => format!("- {} f{}", -c, m.mode),
                c => format!("{c} f{}", m.mode),
            };
            let (first, second) = (term(a, fa), term(b, fb));
            let second = if b > 0 { format!("+ {second}") } else { second };
            notes.push(format!(
                "{} mode {} ({:.4} Hz) is at {first} {second} = {f:.4} Hz of modes {} and {} \
                 ({:.4} and {:.4} Hz): possibly an intermodulation product {why}",
                hi.method.name(),
                hi.mode,
                hi.f_hz,
                fa.mode,
                fb.mode,
                fa.f_hz,
                fb.f_hz
            ));
        }
    }
    notes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modal::mac;
    use vibcam_model::field::{simulate, FieldCase};

    /// A struck tuning fork filmed by a slow-motion camera: 32 Hz at 250 fps, damping 0.001,
    /// struck before the record starts (it rings all through, losing half its amplitude), a
    /// hand-held camera's drift at 0.4-2.7 Hz and 0.03 px of tracking noise; one tine point,
    /// or two. With one or two channels the shape matches nearly every line, and EFDD's bell
    /// ran to the fences: 31.95 Hz and, with two strikes, 31.80 Hz (0.6 % low). Now the bell
    /// ends at its valley: EFDD and SSI within 0.1 % of the fork; EFDD's damping, whose band
    /// (0.06 Hz) is far under a line (1.95 Hz), is not given (it came out 0.00003).
    #[test]
    fn a_struck_fork_seen_at_one_or_two_points_gives_its_frequency() {
        let (fs, n, f, z) = (250.0, 1000, 32.0, 0.001);
        let w = 2.0 * std::f64::consts::PI * f;
        let noise = |seed: u64| vibcam_common::testing::gaussian_noise(seed, n);
        let (e1, e2) = (noise(1), noise(2));
        let ring: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / fs + 0.3;
                let tt = 2.0 * std::f64::consts::PI * t;
                let drift = 0.5 * (0.4 * tt).sin()
                    + 0.3 * (1.3 * tt + 1.0).sin()
                    + 0.2 * (2.7 * tt + 2.0).sin();
                2.0 * (-z * w * t).exp() * (w * t).sin() + drift
            })
            .collect();
        let one = vec![ring
            .iter()
            .zip(&e1)
            .map(|(r, e)| r + 0.03 * e)
            .collect::<Vec<f64>>()];
        let mut two = one.clone();
        two.push(
            ring.iter()
                .zip(&e2)
                .map(|(r, e)| 0.3 * r + 0.03 * e)
                .collect(),
        );
        let welch = vibcam_chain::frf::WelchSettings::default();
        for ch in [one, two] {
            let s = segment_settings(fs, &ch, &welch, "the record").unwrap();
            let r = analyze(&ch, &s).unwrap();
            for method in [Method::Efdd, Method::Ssi] {
                let m = r
                    .modes
                    .iter()
                    .find(|m| m.method == method)
                    .unwrap_or_else(|| {
                        panic!("{} channels, no {method:?}: {:#?}", ch.len(), r.notes)
                    });
                assert!(
                    (m.f_hz - f).abs() < 0.001 * f,
                    "{} channels, {method:?}: {} Hz",
                    ch.len(),
                    m.f_hz
                );
            }
            let efdd = r.modes.iter().find(|m| m.method == Method::Efdd).unwrap();
            assert_eq!(efdd.damping, None, "{}", efdd.evidence);
            assert!(efdd.evidence.contains("no damping"), "{}", efdd.evidence);
        }
    }

    /// Lighter and shorter: forks of damping 3e-4 seen for 2 s at two points (eight noise
    /// records). Their damping scatters between model orders by tens of per cent; with a
    /// stability rule relative to the damping alone SSI-cov found the fork within 0.01 % in 2
    /// of them, with the damping floor (docs/method.md §3.12) in 7.
    #[test]
    fn lightly_damped_forks_in_short_records_give_ssi_their_frequency() {
        let (fs, n, f, z) = (250.0, 500, 32.0, 3e-4);
        let w = 2.0 * std::f64::consts::PI * f;
        let ring: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / fs;
                (-z * w * t).exp() * (w * (1.0 - z * z).sqrt() * t + 0.3).sin()
            })
            .collect();
        let found = (0..8u64)
            .filter(|k| {
                let ch: Vec<Vec<f64>> = [1.0, 0.6]
                    .iter()
                    .enumerate()
                    .map(|(j, &a)| {
                        let e = vibcam_common::testing::gaussian_noise(10 * k + j as u64, n);
                        ring.iter().zip(&e).map(|(r, e)| a * r + 0.03 * e).collect()
                    })
                    .collect();
                let r = analyze(&ch, &OmaSettings::new(fs, n, None)).unwrap();
                r.modes
                    .iter()
                    .any(|m| m.method == Method::Ssi && (m.f_hz - f).abs() < 1e-4 * f)
            })
            .count();
        // measured 7 of 8 (2 without the floor); 6 leaves one record of margin
        assert!(found >= 6, "{found} of 8");
    }

    fn truth_shape(v: &[f64]) -> Vec<Complex64> {
        v.iter().map(|&x| Complex64::new(x, 0.0)).collect()
    }

    /// An SSI mode `n` at `f_hz` with `damping` and a real shape.
    fn ssi_mode(n: usize, f_hz: f64, damping: f64, shape: &[f64]) -> OmaMode {
        OmaMode {
            method: Method::Ssi,
            mode: n,
            band_hz: None,
            f_hz,
            amplitude: None,
            damping: Some(damping),
            shape: truth_shape(shape),
            evidence: String::new(),
            uncertainty: Default::default(),
        }
    }

    #[test]
    fn harmonics_are_named_and_modes_at_multiples_with_their_own_shape_are_not() {
        let mode = |n: usize, f_hz: f64, shape: &[f64]| ssi_mode(n, f_hz, 0.01, shape);
        let one = [0.2, 0.5, 0.7, 0.9, 1.0];
        let modes = [
            mode(1, 1.5, &one),
            // 3 x 1.5 within 3 zeta f, a shape like mode 1's: a harmonic
            mode(2, 4.53, &[0.3, 0.5, 0.8, 0.8, 1.0]),
            // 5 x 1.5 with a shape orthogonal to mode 1's: a mode
            mode(3, 7.5, &[1.0, 0.6, -0.2, -0.4, 0.06]),
            // not near a multiple
            mode(4, 5.2, &one),
        ];
        let notes = harmonic_notes(&modes, 0.01, RecordSource::File);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].starts_with("ssi mode 2 (4.5300 Hz) is 3 x mode 1"),
            "{notes:?}"
        );
        // another method's modes are not compared
        let mut other = modes.clone();
        other[0].method = Method::Fdd;
        assert!(harmonic_notes(&other, 0.01, RecordSource::File).is_empty());
    }

    #[test]
    fn the_blob_trackers_intermodulation_products_are_named_and_no_tracker_is_told_to_use_itself() {
        let mode = |n: usize, f_hz: f64, shape: &[f64]| ssi_mode(n, f_hz, 0.012, shape);
        // the shear frame's first two modes and a column of poles at 7.3564 Hz, near
        // 2 f1 + f2 = 7.3785 Hz (within 1.5 lines of a 2048-sample spectrum at 60 fps), as
        // the binary centroid made it on a rendered field record
        let modes = [
            mode(1, 1.5, &[0.28, 0.55, 0.77, 0.92, 1.0]),
            mode(2, 4.3785, &[0.77, 1.0, 0.45, -0.28, -0.87]),
            mode(3, 7.3564, &[0.5, 0.8, 0.7, 0.5, 1.0]),
        ];
        let df = 60.0 / 2048.0;
        let blob = harmonic_notes(&modes, df, RecordSource::Blob);
        assert_eq!(blob.len(), 1, "{blob:?}");
        assert!(
            blob[0].contains("2 f1 + f2 = 7.3785 Hz") && blob[0].contains("intermodulation"),
            "{blob:?}"
        );
        // a linear tracker makes no intermodulation product: nothing is named
        assert!(harmonic_notes(&modes, df, RecordSource::Linear("Lucas-Kanade")).is_empty());
        // a harmonic found on a Lucas-Kanade record does not advise Lucas-Kanade
        let third = [
            mode(1, 1.5, &[0.28, 0.55, 0.77, 0.92, 1.0]),
            mode(2, 4.5, &[0.3, 0.5, 0.8, 0.9, 1.0]),
        ];
        let lk = harmonic_notes(&third, df, RecordSource::Linear("Lucas-Kanade"));
        assert_eq!(lk.len(), 1, "{lk:?}");
        assert!(
            lk[0].contains("3 x mode 1") && !lk[0].contains("$tracker"),
            "{lk:?}"
        );
        let blob = harmonic_notes(&third, df, RecordSource::Blob);
        assert!(blob[0].contains("$tracker weighted or lk"), "{blob:?}");
    }

    #[test]
    fn the_shear_frame_is_identified_by_every_method() {
        let model = FieldCase::ShearFrame.model();
        let fs = 60.0;
        // two hours: the damping's scatter over records of this length is a third of 15 %
        // and less (method.md §3.12: 20 records per length by examples/oma_field.rs)
        let n = (fs * 7200.0) as usize;
        let rec = simulate(&model, fs, n, 0.02, 11);
        let s = OmaSettings::new(fs, n, Some(2048));
        let r = analyze(&rec, &s).unwrap();
        let df = r.csd.df_hz();
        for method in [Method::Fdd, Method::Efdd, Method::Ssi] {
            let found: Vec<&OmaMode> = r.modes.iter().filter(|m| m.method == method).collect();
            for (i, m) in model.modes.iter().enumerate() {
                let got = r
                    .nearest(method, m.f_hz, f64::INFINITY)
                    .unwrap_or_else(|| panic!("{method:?}: no mode"));
                // SSI within a line; EFDD within two (its bell's truncation); FDD's peak line
                // within half the half-power bandwidth (the bell's top is flat over several
                // lines, and the noisy maximum wanders on it)
                let tolerance = match method {
                    Method::Ssi | Method::Decay => df,
                    Method::Efdd | Method::Plscf => 2.0 * df,
                    Method::Fdd => m.damping * m.f_hz,
                };
                assert!(
                    (got.f_hz - m.f_hz).abs() <= tolerance,
                    "{method:?} mode {}: {} against {} Hz (line {df})",
                    i + 1,
                    got.f_hz,
                    m.f_hz
                );
                let mc = mac(&got.shape, &truth_shape(&m.shape));
                assert!(mc >= 0.99, "{method:?} mode {}: MAC {mc}", i + 1);
                // the damping of EFDD (its bell fitted) and SSI-cov within 15 % for all five
                // (their scatter over two-hour records is a third of that, method.md §3.12)
                if let Some(z) = got.damping {
                    assert!(
                        (z / m.damping - 1.0).abs() <= 0.15,
                        "{method:?} mode {}: damping {z} against {}",
                        i + 1,
                        m.damping
                    );
                }
            }
            assert_eq!(found.len(), model.modes.len(), "{method:?}: {found:?}");
        }
    }

    /// The shear frame's displacements and their velocities (central differences): the bells
    /// tell which is which, and EFDD fits each as what it is. Fitted as a displacement's,
    /// the velocity's bells put the modes 0.2-0.6 % high (method.md §3.12).
    #[test]
    fn the_bells_tell_a_velocity_from_a_displacement() {
        let model = FieldCase::ShearFrame.model();
        let (fs, n) = (60.0, 36_000);
        let rec = simulate(&model, fs, n, 0.02, 5);
        let velocity: Vec<Vec<f64>> = rec
            .iter()
            .map(|x| {
                (0..n)
                    .map(|i| (x[(i + 1).min(n - 1)] - x[i.saturating_sub(1)]) * fs / 2.0)
                    .collect()
            })
            .collect();
        let s = OmaSettings::new(fs, n, None);
        for (channels, quantity) in [
            (&rec, bell::Quantity::Displacement),
            (&velocity, bell::Quantity::Velocity),
        ] {
            let r = analyze(channels, &s).unwrap();
            assert_eq!(r.quantity.quantity, quantity, "{:?}", r.quantity);
            assert!(!r.quantity.given);
            for m in &model.modes {
                let got = r.nearest(Method::Efdd, m.f_hz, 0.05 * m.f_hz).unwrap();
                let u = got.uncertainty.f_hz.map_or(f64::NAN, |i| i.u);
                assert!(
                    (got.f_hz - m.f_hz).abs() <= 3.0 * u,
                    "{quantity:?}: {} +- {u} against {}",
                    got.f_hz,
                    m.f_hz
                );
            }
        }
    }

    #[test]
    fn without_bands_each_method_reports_the_true_modes_and_names_what_it_rejected() {
        // ten-minute records at 60 Hz with 3 % noise of each case, the weak high mode's
        // included: SSI-cov and EFDD report exactly the true modes (as many, each within
        // max(3 lines, 3 zeta f)); over 60 records per case they do in 60 of 60
        // (examples/oma_auto.rs, docs/method.md §3.12); here two records per case
        let fs = 60.0;
        let n = (fs * 600.0) as usize;
        for case in [
            FieldCase::ShearFrame,
            FieldCase::CloseModes,
            FieldCase::WeakHighMode,
        ] {
            let model = case.model();
            for seed in [5000, 5001] {
                let rec = simulate(&model, fs, n, 0.03, seed);
                let r = analyze(&rec, &OmaSettings::new(fs, n, None)).unwrap();
                let df = r.csd.df_hz();
                for method in [Method::Efdd, Method::Ssi] {
                    let found: Vec<&OmaMode> =
                        r.modes.iter().filter(|m| m.method == method).collect();
                    assert_eq!(
                        found.len(),
                        model.modes.len(),
                        "{case:?} {seed} {method:?}: {found:?}\n{:?}",
                        r.rejected
                    );
                    for (got, want) in found.iter().zip(&model.modes) {
                        let tolerance = (3.0 * df).max(3.0 * want.damping * want.f_hz);
                        assert!(
                            (got.f_hz - want.f_hz).abs() <= tolerance,
                            "{case:?} {seed} {method:?}: {} against {}",
                            got.f_hz,
                            want.f_hz
                        );
                        assert!(!got.evidence.is_empty());
                    }
                }
                // whatever was not taken is named with its reason; a ripple has the shape of
                // the peak it is on (a bell also runs where its mode is the second singular
                // value, under another mode: a peak there is no ripple of it)
                assert!(
                    r.rejected.iter().all(|x| x.contains(": ")),
                    "{:?}",
                    r.rejected
                );
                for x in r.rejected.iter().filter(|x| x.contains("ripple")) {
                    let m: f64 = x
                        .split("(MAC ")
                        .nth(1)
                        .and_then(|t| t.split(')').next())
                        .and_then(|t| t.parse().ok())
                        .unwrap_or(0.0);
                    assert!(m >= 0.85, "{x}");
                }
            }
        }
    }

    #[test]
    fn close_modes_are_separated_by_ssi_and_by_the_bells_of_their_shapes() {
        // 2.00 and 2.04 Hz: 2.7 lines apart with the default segment of 4096 samples, bells
        // overlapping; FDD's first singular value has one peak of 6 dB (the second mode shows
        // in the second singular value), SSI-cov finds both, and its mode with no peak gives
        // FDD and EFDD its bell: the lines whose first or second singular vector has its shape
        // (1.4 lines apart, with segments of 2048, the bells are one: EFDD then finds one mode
        // in about half the records, docs/method.md §3.12)
        let model = FieldCase::CloseModes.model();
        let fs = 60.0;
        let n = (fs * 1800.0) as usize;
        let rec = simulate(&model, fs, n, 0.02, 5);
        let r = analyze(&rec, &OmaSettings::new(fs, n, None)).unwrap();
        let df = r.csd.df_hz();
        let of = |m: Method| -> Vec<&OmaMode> {
            r.modes
                .iter()
                .filter(|x| x.method == m && x.f_hz < 3.0)
                .collect()
        };
        let fdd = of(Method::Fdd);
        assert_eq!(fdd.len(), 2, "{fdd:?}");
        assert!(
            fdd.iter()
                .any(|m| m.evidence.contains("found from SSI-cov")),
            "{fdd:?}"
        );
        for method in [Method::Ssi, Method::Efdd] {
            let found = of(method);
            assert_eq!(found.len(), 2, "{method:?}: {found:?}");
            for (got, want) in found.iter().zip(&model.modes) {
                assert!(
                    (got.f_hz - want.f_hz).abs() <= df,
                    "{method:?}: {} {}",
                    got.f_hz,
                    want.f_hz
                );
                // 0.96 to 1 over 20 half-hour records (examples/oma_field.rs): the two
                // shapes share the bell
                let mc = mac(&got.shape, &truth_shape(&want.shape));
                assert!(mc >= 0.95, "{method:?} {} Hz: MAC {mc}", want.f_hz);
                // the damping's standard deviation over such records is 6-9 % (SSI) and
                // 13-16 % (EFDD, 10-minute records: examples/oma_auto.rs)
                let z = got.damping.unwrap();
                assert!((z / want.damping - 1.0).abs() <= 0.3, "{method:?}: {z}");
            }
        }
    }

    #[test]
    fn the_firmware_cross_spectra_give_the_host_fdd_lines_and_shapes() {
        // firmware-core's streaming matrix (f32, frames pushed one at a time) against the
        // host's FDD on the same record and segments
        use firmware_core::spectrum::cross::{pick_peaks, CrossSpectra};
        let model = FieldCase::ShearFrame.model();
        let fs = 60.0;
        let n = (fs * 600.0) as usize;
        let rec = simulate(&model, fs, n, 0.02, 21);
        let mut s = OmaSettings::new(fs, n, Some(512));
        s.bands.clear();
        let host = analyze(&rec, &s).unwrap();
        let mut fw = Box::new(CrossSpectra::<5, 512, 257, 15, 0>::try_new(fs as f32).unwrap());
        // millimetres, as a camera would hold them (the simulated values are tiny)
        for i in 0..n {
            let frame: [f32; 5] =
                core::array::from_fn(|t| (rec[t].get(i).copied().unwrap_or(0.0) * 1e3) as f32);
            fw.push(&frame);
        }
        assert_eq!(fw.segments() as usize, host.csd.segments);
        let s1: Vec<f32> = (0..257).map(|l| fw.first_singular(l, 50).0).collect();
        let df = fs / 512.0;
        let lo = (s.peaks.f_min_hz / df).ceil() as usize;
        let (mut sorted, mut out) = ([0.0f32; 257], [0usize; 16]);
        let found = pick_peaks(&s1, (lo, 255), (6.0, 10.0), &mut sorted, &mut out);
        assert!(found >= 4, "{found} peaks");
        // the camera's rule: 6 dB of prominence and 10 dB over the median
        let mut rule = s.peaks;
        rule.over_floor_db = Some(10.0);
        let host_peaks: Vec<usize> = fdd::pick_peaks(&host.svd, rule)
            .into_iter()
            .map(|p| p.0)
            .collect();
        assert_eq!(
            &out[..found],
            &host_peaks[..],
            "firmware lines {:?}",
            &out[..found]
        );
        for &l in &out[..found] {
            let v: Vec<Complex64> = fw
                .first_singular(l, 50)
                .1
                .iter()
                .map(|c| Complex64::new(f64::from(c.re), f64::from(c.im)))
                .collect();
            let m = mac(&v, &host.svd.u1[l]);
            assert!(m >= 0.999, "line {l}: MAC {m}");
        }
        // the matrix itself against the host's (scaled alike), relative to the line's trace
        for l in [10usize, 60, 200] {
            let trace: f64 = (0..5).map(|i| host.csd.g[l][i * 5 + i].re).sum::<f64>() * 1e6;
            for i in 0..5 {
                for j in 0..5 {
                    let a = fw.get(l, i, j);
                    let b = host.csd.g[l][i * 5 + j] * 1e6;
                    let d = (Complex64::new(f64::from(a.re), f64::from(a.im)) - b).norm();
                    assert!(d <= 1e-4 * trace, "line {l} ({i},{j}): {a} vs {b}");
                }
            }
        }
    }
}

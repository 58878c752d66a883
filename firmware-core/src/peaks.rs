//! Resonance frequency and amplitude by peak picking of an H1 estimate (method.md §2.5).
//!
//! For each frequency band `[lo, hi]` of a mode the resonance frequency is the frequency of the
//! bin with the largest `|Im H1|` inside the band, and the resonant amplitude is `|H1|` at that
//! bin. This is the paper's method (a receptance's imaginary part peaks sharply at the natural
//! frequency and is little disturbed by neighbouring modes), and it is what [`pick`] does by
//! default.
//!
//! Conventions:
//! * bin `k` has frequency `f_k = k * df_hz`, computed in `f32` exactly like
//!   [`crate::spectrum::WelchAccumulator::freq`];
//! * the band is inclusive at both ends: bin `k` is inside when `lo <= f_k <= hi` (so two bands
//!   that share an edge frequency both contain a bin that falls exactly on it);
//! * bins whose H1 is not finite are ignored; among equal `|Im H1|` the lowest bin wins;
//! * no bin inside the band, an invalid band (`lo > hi`, non-finite) or an invalid `df_hz`
//!   (non-finite, `<= 0`) give `None`, never NaN.
//!
//! Optional sub-bin refinement (`refine = true`, off by default so results stay comparable with
//! the paper) fits a parabola through `|Im H1|` at the picked bin and its two neighbours (taken
//! from the whole spectrum, even when a neighbour lies just outside the band) and moves the
//! frequency to the vertex, at most half a bin. It is applied only when the picked bin is a local
//! maximum of `|Im H1|` with both neighbours present and finite; otherwise the bin frequency is
//! kept. The refinement changes **only the frequency**: the amplitude stays `|H1|` at the picked
//! bin, so amplitudes are identical with and without refinement.
//!
//! ```
//! use firmware_core::{peaks, Complex32};
//! // a receptance-like H1 on 0.5 Hz bins whose |Im H1| peaks at bin 6 (3.0 Hz)
//! let h1: Vec<Complex32> = (0..20)
//!     .map(|k| Complex32::new(0.1, -1.0 / (1.0 + (k as f32 - 6.0).powi(2))))
//!     .collect();
//! let p = peaks::pick(&h1, 0.5, (1.0, 5.0), false).unwrap();
//! assert_eq!((p.bin, p.f_hz), (6, 3.0));
//! assert!((p.amplitude - (0.01f32 + 1.0).sqrt()).abs() < 1e-6);
//! ```

use crate::Complex32;

/// A picked resonance.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Peak {
    /// Index of the bin with the largest `|Im H1|` in the band.
    pub bin: usize,
    /// Resonance frequency in Hz: `bin * df_hz`, or the parabolic vertex with refinement.
    pub f_hz: f32,
    /// `|H1|` at `bin`, in the unit of H1 (output unit per input unit).
    pub amplitude: f32,
}

/// Picks the peak of `|Im H1|` in `band = (lo_hz, hi_hz)` of the spectrum `h1` (bin `k` at
/// `k * df_hz` Hz). See the [module documentation](self) for the conventions; `refine` enables
/// the parabolic sub-bin refinement of the frequency (off in the paper's method).
pub fn pick(h1: &[Complex32], df_hz: f32, band: (f32, f32), refine: bool) -> Option<Peak> {
    pick_with(h1.len(), df_hz, band, refine, |k| h1.get(k).copied())
}

/// Same as [`pick`] over a spectrum of `bins` bins read through `h1(k)` (which may return
/// `None` for a bin that is not available), so no spectrum buffer is needed, e.g.
/// `pick_with(w.bins(), w.df_hz(), band, false, |k| w.h1(k))` on a
/// [`WelchH1`](crate::spectrum::WelchH1).
pub fn pick_with(
    bins: usize,
    df_hz: f32,
    band: (f32, f32),
    refine: bool,
    h1: impl Fn(usize) -> Option<Complex32>,
) -> Option<Peak> {
    let (lo, hi) = band;
    if !(df_hz.is_finite() && df_hz > 0.0 && lo.is_finite() && hi.is_finite() && lo <= hi) {
        return None;
    }
    let freq = |k: usize| k as f32 * df_hz;
    // candidate range a little wider than the band; the exact test is on freq(k)
    // (float-to-int `as` saturates, negatives give 0)
    let first = (libm::floorf(lo / df_hz) as usize).saturating_sub(1);
    let last = (libm::ceilf(hi / df_hz) as usize)
        .saturating_add(1)
        .min(bins.saturating_sub(1));
    let finite = |v: Complex32| v.re.is_finite() && v.im.is_finite();
    let mut best: Option<(usize, f32, Complex32)> = None;
    let mut k = first;
    while k <= last && k < bins {
        let f = freq(k);
        if lo <= f && f <= hi {
            if let Some(v) = h1(k).filter(|v| finite(*v)) {
                let m = libm::fabsf(v.im);
                if best.is_none_or(|(_, bm, _)| m > bm) {
                    best = Some((k, m, v));
                }
            }
        }
        k += 1;
    }
    let (bin, b, v) = best?;
    let mut f_hz = freq(bin);
    if refine && bin > 0 {
        let side = |k: usize| h1(k).filter(|v| finite(*v)).map(|v| libm::fabsf(v.im));
        if let (Some(a), Some(c)) = (side(bin - 1), side(bin + 1)) {
            let denom = a - 2.0 * b + c;
            if b >= a && b >= c && denom < 0.0 {
                let delta = (0.5 * (a - c) / denom).clamp(-0.5, 0.5);
                let f = (bin as f32 + delta) * df_hz;
                if f.is_finite() {
                    f_hz = f;
                }
            }
        }
    }
    Some(Peak {
        bin,
        f_hz,
        amplitude: libm::hypotf(v.re, v.im),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// Closed-form receptance of one mode, H(f) = 1 / (k - m w^2 + i c w), in f64.
    fn receptance(f: f64, m: f64, fn_hz: f64, zeta: f64) -> (f64, f64) {
        let w = 2.0 * std::f64::consts::PI * f;
        let wn = 2.0 * std::f64::consts::PI * fn_hz;
        let (re, im) = (m * (wn * wn - w * w), 2.0 * m * zeta * wn * w);
        let d = re * re + im * im;
        (re / d, -im / d)
    }

    fn grid(n: usize, df: f64, m: f64, fn_hz: f64, zeta: f64) -> Vec<Complex32> {
        (0..n)
            .map(|k| {
                let (re, im) = receptance(k as f64 * df, m, fn_hz, zeta);
                Complex32::new(re as f32, im as f32)
            })
            .collect()
    }

    #[test]
    fn single_mode_on_a_grid() {
        let (m, fn_hz, zeta, df) = (11885.0, 2.0137, 0.06, 0.01);
        let h = grid(2501, df, m, fn_hz, zeta);
        let p = pick(&h, df as f32, (1.5, 2.25), false).unwrap();
        // reference: brute-force argmax of |Im H| in f64 over the same grid and band
        let want = (150..=225)
            .max_by(|&a, &b| {
                let ia = receptance(a as f64 * df, m, fn_hz, zeta).1.abs();
                let ib = receptance(b as f64 * df, m, fn_hz, zeta).1.abs();
                ia.total_cmp(&ib)
            })
            .unwrap();
        assert_eq!(p.bin, want);
        assert_eq!(p.bin, 201);
        assert!((p.f_hz - 2.01).abs() < 1e-6);
        let (re, im) = receptance(want as f64 * df, m, fn_hz, zeta);
        let amp = (re * re + im * im).sqrt();
        assert!(((p.amplitude as f64) - amp).abs() < 1e-6 * amp);
        // the static compliance scale: amplitude near 1 / (2 zeta k)
        let k = m * (2.0 * std::f64::consts::PI * fn_hz).powi(2);
        assert!((p.amplitude as f64 * 2.0 * zeta * k - 1.0).abs() < 0.01);
    }

    #[test]
    fn refinement_moves_toward_the_true_peak_and_keeps_the_amplitude() {
        // continuous maximum of |Im H| by a fine f64 search, against bin and refined estimates
        for (fn_hz, zeta) in [(2.0137, 0.06), (2.5042, 0.03), (7.1033, 0.0115)] {
            let (m, df) = (1.0, 0.01);
            let h = grid(1500, df, m, fn_hz, zeta);
            let band = ((fn_hz - 0.4) as f32, (fn_hz + 0.4) as f32);
            let plain = pick(&h, df as f32, band, false).unwrap();
            let refined = pick(&h, df as f32, band, true).unwrap();
            let truth = (0..200_000)
                .map(|i| fn_hz - 0.05 + i as f64 * 5e-7)
                .max_by(|a, b| {
                    let ia = receptance(*a, m, fn_hz, zeta).1.abs();
                    let ib = receptance(*b, m, fn_hz, zeta).1.abs();
                    ia.total_cmp(&ib)
                })
                .unwrap();
            let e_bin = (plain.f_hz as f64 - truth).abs();
            let e_ref = (refined.f_hz as f64 - truth).abs();
            assert!(e_ref < e_bin, "{fn_hz}: refined {e_ref} vs bin {e_bin}");
            assert!(e_ref < 0.15 * df, "{fn_hz}: refined error {e_ref}");
            assert_eq!(refined.bin, plain.bin);
            assert_eq!(refined.amplitude, plain.amplitude);
        }
    }

    #[test]
    fn band_edges_are_inclusive_and_invalid_bands_give_none() {
        let mut h = vec![Complex32::new(0.0, 0.0); 11];
        h[4].im = -3.0;
        h[6].im = 5.0;
        h[6].re = 4.0;
        // bin 6 is at 0.6 Hz; a band ending exactly there includes it
        let df = 0.1f32;
        let edge = 6.0 * df;
        let p = pick(&h, df, (edge, 1.0), false).unwrap();
        assert_eq!(p.bin, 6);
        assert!((p.amplitude - 41f32.sqrt()).abs() < 1e-6);
        let p = pick(&h, df, (0.0, edge), false).unwrap();
        assert_eq!(p.bin, 6);
        let p = pick(&h, df, (0.0, 5.0 * df), false).unwrap();
        assert_eq!((p.bin, p.amplitude), (4, 3.0));
        // a band between two bins, beyond the spectrum, reversed or non-finite: None
        assert_eq!(pick(&h, df, (0.61, 0.69), false), None);
        assert_eq!(pick(&h, df, (2.0, 3.0), false), None);
        assert_eq!(pick(&h, df, (0.5, 0.4), false), None);
        assert_eq!(pick(&h, df, (f32::NAN, 0.4), false), None);
        assert_eq!(pick(&h, f32::NAN, (0.0, 0.4), false), None);
        assert_eq!(pick(&h, 0.0, (0.0, 0.4), false), None);
        assert_eq!(pick(&[], df, (0.0, 1.0), true), None);
        // a band reaching below 0 Hz or above the last bin is cut to the spectrum
        assert_eq!(pick(&h, df, (-5.0, 50.0), false).unwrap().bin, 6);
    }

    #[test]
    fn ties_nan_and_refinement_edge_cases() {
        let mut h = vec![Complex32::new(0.0, 1.0); 8];
        // ties: lowest bin wins
        assert_eq!(pick(&h, 1.0, (2.0, 6.0), false).unwrap().bin, 2);
        // non-finite bins are skipped
        h[3] = Complex32::new(f32::NAN, 9.0);
        h[5] = Complex32::new(0.0, 2.0);
        let p = pick(&h, 1.0, (0.0, 7.0), true).unwrap();
        assert_eq!(p.bin, 5);
        assert!(p.f_hz.is_finite() && p.amplitude.is_finite());
        // symmetric neighbours: the vertex is the bin itself
        assert_eq!(p.f_hz, 5.0);
        // picked bin at the band edge but not a local maximum of the spectrum: no refinement
        h[6] = Complex32::new(0.0, 4.0);
        let p = pick(&h, 1.0, (0.0, 5.0), true).unwrap();
        assert_eq!((p.bin, p.f_hz), (5, 5.0));
        // last bin has no right neighbour: no refinement
        h[7] = Complex32::new(0.0, 8.0);
        let p = pick(&h, 1.0, (0.0, 7.0), true).unwrap();
        assert_eq!((p.bin, p.f_hz), (7, 7.0));
        // all non-finite: None
        let bad = [Complex32::new(f32::INFINITY, 0.0); 4];
        assert_eq!(pick(&bad, 1.0, (0.0, 3.0), false), None);
        // pick_with with unavailable bins
        assert_eq!(pick_with(10, 1.0, (0.0, 9.0), false, |_| None), None);
    }
}

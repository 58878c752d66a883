//! What a Welch estimate does to an FRF: it smooths it with the window's spectral kernel.
//!
//! For a stationary input whose spectrum is flat over a few lines, the expected cross-spectrum
//! of a windowed segment is `E[G_xy](f) = S_xx int K(f - nu) T(nu) dnu` and the auto-spectrum
//! `E[G_xx] = S_xx`, with `K(nu) = |W(nu)|^2 / (fs sum w_n^2)` the normalised power of the
//! window's transform (`int K = 1`, Parseval). So the H1 of many segments tends to `K * T`,
//! not `T`: a mode narrower than a few lines comes out lower and wider than it is (the
//! resolution bias, Bendat & Piersol, *Random Data*, 4th ed., 8.5.1 and 9.3.2). A modal fit of
//! the smoothed model `K * T` to the estimate removes that bias from the fitted pole and
//! residue ([`super::fit_mode_smoothed`]).
//!
//! The kernel is tabulated on a grid of 1/16 of a segment line (`fs / nperseg`) out to 4 lines
//! either side (16 for the rectangular window, whose kernel falls only as `1 / nu^2`); the
//! convolution is that quadrature. A Lorentzian peak of half-power half-width `g` is summed on
//! such a grid with a relative error of about `exp(-2 pi g / step)`: below 1e-5 for a mode as
//! wide as a quarter of a line.

use firmware_core::spectrum::Window;
use num_complex::Complex64;

/// Steps of the kernel's grid per segment line.
const STEPS_PER_LINE: usize = 16;

/// The spectral kernel of a Welch estimate's window ([`Smoothing::welch`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Smoothing {
    /// Frequency offsets of the grid, Hz (symmetric about 0).
    pub offsets_hz: Vec<f64>,
    /// The kernel's weight at each offset (summing to 1 over the grid).
    pub weights: Vec<f64>,
}

impl Smoothing {
    /// The kernel of segments of `nperseg` samples at `fs_hz` under `window` (periodic, as
    /// the estimator applies it).
    pub fn welch(window: Window, nperseg: usize, fs_hz: f64) -> Smoothing {
        let (lines, mut weights) = table(window, nperseg);
        let total: f64 = weights.iter().sum();
        if total > 0.0 {
            for k in &mut weights {
                *k /= total;
            }
        }
        let line_hz = fs_hz / nperseg as f64;
        Smoothing {
            offsets_hz: lines.iter().map(|q| q * line_hz).collect(),
            weights,
        }
    }

    /// `(K * f)(f_hz)`: the function `f` of frequency (Hz) smoothed by the kernel.
    pub fn apply(&self, f: impl Fn(f64) -> Complex64, f_hz: f64) -> Complex64 {
        self.offsets_hz
            .iter()
            .zip(&self.weights)
            .map(|(o, k)| f(f_hz - o) * k)
            .sum()
    }
}

/// The kernel's grid (offsets in segment lines) and its weights `K(nu) dnu` before
/// normalisation (Parseval: they sum to nearly 1 when the span holds nearly all the kernel).
fn table(window: Window, nperseg: usize) -> (Vec<f64>, Vec<f64>) {
    let span = match window {
        Window::Rect => 16,
        Window::Hann | Window::Hamming => 4,
    };
    let w: Vec<f64> = (0..nperseg)
        .map(|n| f64::from(window.value(n, nperseg)))
        .collect();
    let energy: f64 = w.iter().map(|v| v * v).sum();
    let half = (span * STEPS_PER_LINE) as i64;
    let step = 1.0 / STEPS_PER_LINE as f64;
    (-half..=half)
        .map(|q| {
            let nu = q as f64 * step;
            // W(nu) = sum_n w_n exp(-2 pi i nu n / L), nu in segment lines
            let theta = -2.0 * std::f64::consts::PI * nu / nperseg as f64;
            let (mut re, mut im) = (0.0, 0.0);
            for (n, wn) in w.iter().enumerate() {
                let (s, c) = (theta * n as f64).sin_cos();
                re += wn * c;
                im += wn * s;
            }
            // |W|^2 / (fs sum w^2) times the step in Hz = |W|^2 step / (L sum w^2)
            (nu, (re * re + im * im) * step / (nperseg as f64 * energy))
        })
        .unzip()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernels_grid_holds_nearly_all_of_its_weight() {
        // Parseval: the kernel integrates to 1 over all frequencies; the grid's span must hold
        // nearly all of it, else normalising over the span would distort the smoothing.
        let held = |w| table(w, 256).1.iter().sum::<f64>();
        let (hann, hamming, rect) = (
            held(Window::Hann),
            held(Window::Hamming),
            held(Window::Rect),
        );
        assert!((hann - 1.0).abs() < 1e-4, "Hann {hann}");
        assert!((hamming - 1.0).abs() < 2e-3, "Hamming {hamming}");
        assert!((rect - 1.0).abs() < 0.015, "rect {rect}");
    }

    #[test]
    fn a_hann_segment_spreads_a_line_over_its_neighbours_as_its_transform_says() {
        // The periodic Hann window's transform at whole lines is 1/2, -1/4, -1/4 (times L):
        // its power at 0 and +-1 line is 1/4 and 1/16 of L^2, and sum w^2 = 3L/8.
        let l = 64;
        let (offsets, weights) = table(Window::Hann, l);
        let at = |line: f64| {
            let q = offsets
                .iter()
                .position(|o| (o - line).abs() < 1e-9)
                .unwrap();
            weights[q]
        };
        let step = 1.0 / STEPS_PER_LINE as f64;
        let scale = step / (l as f64 * 3.0 * l as f64 / 8.0) * (l * l) as f64;
        assert!((at(0.0) - 0.25 * scale).abs() < 1e-6 * scale);
        assert!((at(1.0) - scale / 16.0).abs() < 1e-6 * scale);
        assert!((at(-1.0) - scale / 16.0).abs() < 1e-6 * scale);
        assert!(at(2.0).abs() < 1e-9);
    }
}

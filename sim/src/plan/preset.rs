//! The planner's inputs taken from a study preset's model (`plan --preset grandstand`): the
//! modes' frequencies, the target and threshold the study renders, the camera rate, and one
//! motion amplitude per mode.
//!
//! **The amplitude.** The binary centroid's transfer depends on how far the target moves
//! during an exposure against its edge width (`imaging::compensation`), so the planner needs
//! the size of each mode's motion. The grandstand's motion has two parts: the free decay after
//! the smoothed impulse, and the response to the held process noise. The planner uses the
//! *peak displacement of the mode's response to the mean decay pulse* (`F0` = 1000 N, the mean
//! of U(950, 1050); `alpha` = 5.6 1/s; the mode at its mean frequency and damping), integrated
//! exactly as the study integrates it ([`Zoh`] at 1 kHz) and scaled to pixels as the study's
//! camera sees it ([`grandstand::PX_PER_MM`]). The decay is where the target moves far within
//! one exposure and where the binary centroid departs from the sinc. The process-noise
//! response of one mode is small against the 1.5 px edge (mode 2: about 0.5 px RMS); rendered
//! alone, such a sub-pixel sinusoid shows the sharp image's pixel locking, which the other
//! modes' larger motion dithers away in the study. Over the whole record that response carries
//! more of the mode's energy than the decay, and it is blurred nearly as by the sinc, so the
//! study's binary ratio falls between this curve and the sinc (method.md §3.4, README).
//!
//! So the transfer itself comes from the whole record, as H1 weighs it: the preset also
//! gives the target's motion in the Welch segments of a nominal record
//! ([`grandstand::nominal_motion_segments`]), and the planner averages the transfers at the
//! segments' amplitudes with their input-energy weights, the same table the study's
//! `vision_compensated` rows divide by. The per-mode decay peak is kept for the lost-frame
//! risk.

use super::{PlanInput, PlanMode};
use firmware_core::centroid::Mode as CentroidMode;
use vibcam_model::grandstand::{self, impulse, Mode, Zoh, ALPHA, FINE, FS_HZ, T0_S};

/// Mean peak force of the grandstand's decay pulse, N (U(950, 1050), method.md §3.1).
const MEAN_F0_N: f64 = 1000.0;
/// Length of the simulated decay, s: ten decay time constants of the slowest mode (mode 2:
/// `1 / (zeta w) = 2.1 s`) after the pulse's own rise.
const DECAY_S: f64 = 25.0;

/// Peak displacement (px, as the grandstand's camera sees it) of `mode`'s response to the mean
/// decay pulse, integrated by the study's exact zero-order hold at its fine rate.
pub fn decay_peak_px(mode: &Mode) -> f64 {
    let fine_hz = FS_HZ * FINE as f64;
    let dt = 1.0 / fine_hz;
    let n = (DECAY_S * fine_hz) as usize;
    // the smoothed impulse sampled at the middle of each fine step, as the study does
    let force: Vec<f64> = (0..n)
        .map(|i| impulse(T0_S + (i as f64 + 0.5) * dt, ALPHA, MEAN_F0_N))
        .collect();
    let mut x = vec![0.0; n];
    Zoh::new(mode, dt).add_response(&force, mode.mass_kg, &mut x);
    let peak_m = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    peak_m * 1000.0 * grandstand::PX_PER_MM
}

/// The grandstand study's plan input (method.md §3.1): the three modes at their mean frequency
/// with their decay-peak amplitudes ([`decay_peak_px`]), the study's target and threshold
/// (`THRESHOLD / level`), 50 fps; `tolerance` and `centroid` as given, each mode evaluated at
/// its longest exposure.
pub fn grandstand_input(tolerance: f64, centroid: CentroidMode) -> PlanInput {
    let modes = Mode::nominal()
        .iter()
        .enumerate()
        .map(|(i, m)| PlanMode {
            mode: i + 1,
            f_hz: m.f_hz,
            amplitude_px: decay_peak_px(m),
        })
        .collect();
    let target = grandstand::TARGET;
    PlanInput {
        modes,
        target,
        threshold_frac: grandstand::THRESHOLD as f64 / target.level,
        fps: FS_HZ,
        tolerance,
        centroid,
        exposure_ms: None,
        motion: Some(grandstand::nominal_motion_segments()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The zero-order-hold peak against the convolution of the pulse with the closed-form
    /// impulse response `h(t) = e^{-zeta w t} sin(w_d t) / (m w_d)` (midpoint rule at the same
    /// 1 ms step, near the peak), and below the impulse bound `I / (m w_d)` (`|h| <= 1 / (m
    /// w_d)`, `I` the pulse's integral `F0 e / alpha`).
    #[test]
    fn decay_peak_is_the_convolution_with_the_impulse_response() {
        let dt = 1.0 / (FS_HZ * FINE as f64);
        let impulse_n_s = MEAN_F0_N * std::f64::consts::E / ALPHA;
        for m in Mode::nominal() {
            let w = std::f64::consts::TAU * m.f_hz;
            let wd = w * (1.0 - m.zeta * m.zeta).sqrt();
            let h = |t: f64| (-m.zeta * w * t).exp() * (wd * t).sin() / (m.mass_kg * wd);
            // the largest excursion is the first peak, within a period of the 0.18 s rise: 2 s
            let n = 2000;
            let f: Vec<f64> = (0..n)
                .map(|j| impulse(T0_S + (j as f64 + 0.5) * dt, ALPHA, MEAN_F0_N))
                .collect();
            let x = |k: usize| -> f64 {
                (0..k.min(n))
                    .map(|j| h((k - j) as f64 * dt - 0.5 * dt) * f[j] * dt)
                    .sum()
            };
            let want = (1..n).map(x).fold(0.0f64, |a, v| a.max(v.abs()));
            let want_px = want * 1000.0 * grandstand::PX_PER_MM;
            let got = decay_peak_px(&m);
            let bound_px = impulse_n_s / (m.mass_kg * wd) * 1000.0 * grandstand::PX_PER_MM;
            eprintln!(
                "mode {} Hz: decay peak {got:.4} px, convolution {want_px:.4}, bound {bound_px:.3}",
                m.f_hz
            );
            // the ZOH is exact for the held force, the convolution's midpoint rule is off by
            // (w dt)^2 / 24 = 2e-5 at most (mode 3)
            assert!((got / want_px - 1.0).abs() < 1e-4, "{got} vs {want_px}");
            assert!(got < bound_px, "{got} vs {bound_px}");
        }
    }

    #[test]
    fn the_grandstand_input_is_the_study_camera() {
        let p = grandstand_input(0.1, CentroidMode::Binary);
        let f: Vec<f64> = p.modes.iter().map(|m| m.f_hz).collect();
        assert_eq!(f, [2.0, 2.5, 3.16]);
        assert_eq!(p.threshold(), grandstand::THRESHOLD);
        assert_eq!(p.target, grandstand::TARGET);
        assert_eq!(p.fps, 50.0);
    }
}

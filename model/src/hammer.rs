//! An impact hammer test in closed form: a structure of a few viscously damped, mass-normalised
//! modes hit at one point by half-sine force pulses, its response at any time exact (no
//! integration step), for testing the experimental modal analysis (`ema`) against known
//! modes.
//!
//! Mode `r` (natural frequency `w_r`, damping `zeta_r`, shape `phi_r`) has the impulse response
//! `h_r(t) = phi_r[o] phi_r[d] exp(-zeta_r w_r t) sin(w_d t) / w_d` between the driven point `d`
//! and the response point `o` (`w_d = w_r sqrt(1 - zeta_r^2)`). A half-sine pulse
//! `F sin(pi v / T)` on `0 <= v <= T` convolved with it is, with `lambda = -zeta w_r + i w_d`
//! and `a = pi / T`,
//!
//! ```text
//! x(t) = F / w_d Im[ exp(lambda t) J(min(t, T)) ],
//! J(u) = [ (exp((ia - lambda) u) - 1) / (ia - lambda) - (exp((-ia - lambda) u) - 1) / (-ia - lambda) ] / 2i
//! ```
//!
//! (`J(u) = integral_0^u sin(a v) exp(-lambda v) dv`). Displacement in metres per newton of
//! the mass-normalised modes; the receptance FRF is `sum_r phi_r[o] phi_r[d] / (w_r^2 - w^2 +
//! 2 i zeta_r w_r w)`.

use num_complex::Complex64;
use std::f64::consts::PI;

/// One mode: natural frequency (Hz), damping ratio, and the (mass-normalised) shape at every
/// point.
#[derive(Debug, Clone, PartialEq)]
pub struct HammerMode {
    /// Undamped natural frequency, Hz.
    pub f_hz: f64,
    /// Viscous damping ratio.
    pub damping: f64,
    /// Shape at each point.
    pub shape: Vec<f64>,
}

/// One hit: a half-sine pulse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Time of the pulse's start, s.
    pub t_s: f64,
    /// Pulse width `T`, s.
    pub width_s: f64,
    /// Peak force, N.
    pub peak_n: f64,
}

/// A structure hit at point `drive`.
#[derive(Debug, Clone, PartialEq)]
pub struct HammerTest {
    /// The modes.
    pub modes: Vec<HammerMode>,
    /// The driven point (an index into the shapes).
    pub drive: usize,
    /// The hits.
    pub hits: Vec<Hit>,
}

/// Points of [`HammerTest::three_modes`].
pub const THREE_MODE_POINTS: usize = 5;

impl Hit {
    /// Hits of these peak forces (N), one every 3 s from 0.2 s, 0.6 ms wide each.
    pub fn every_3_s(peaks_n: &[f64]) -> Vec<Hit> {
        peaks_n
            .iter()
            .enumerate()
            .map(|(i, &p)| Hit {
                t_s: 0.2 + 3.0 * i as f64,
                width_s: 0.0006,
                peak_n: p,
            })
            .collect()
    }
}

impl HammerTest {
    /// A structure of three modes (23 Hz 1.5 %, 61.5 Hz 1.0 %, 118 Hz 0.8 %) seen at five
    /// points (the shapes of a beam's first three bending modes, `sin(r pi (o + 0.7) / 6)`),
    /// hit at point 2 (index 1) by `hits`.
    pub fn three_modes(hits: Vec<Hit>) -> HammerTest {
        let shape = |r: usize| -> Vec<f64> {
            (0..THREE_MODE_POINTS)
                .map(|o| ((r + 1) as f64 * PI * (o as f64 + 0.7) / 6.0).sin())
                .collect()
        };
        let mode = |r: usize, f_hz: f64, damping: f64| HammerMode {
            f_hz,
            damping,
            shape: shape(r),
        };
        HammerTest {
            modes: vec![
                mode(0, 23.0, 0.015),
                mode(1, 61.5, 0.010),
                mode(2, 118.0, 0.008),
            ],
            drive: 1,
            hits,
        }
    }

    /// The force at `t`, N.
    pub fn force(&self, t: f64) -> f64 {
        self.hits
            .iter()
            .map(|h| {
                let v = t - h.t_s;
                if (0.0..=h.width_s).contains(&v) {
                    h.peak_n * (PI * v / h.width_s).sin()
                } else {
                    0.0
                }
            })
            .sum()
    }

    /// The displacement of point `o` at `t`, m.
    pub fn displacement(&self, o: usize, t: f64) -> f64 {
        let mut x = 0.0;
        for h in &self.hits {
            let tau = t - h.t_s;
            if tau <= 0.0 {
                continue;
            }
            let a = PI / h.width_s;
            let u = tau.min(h.width_s);
            for m in &self.modes {
                let wr = 2.0 * PI * m.f_hz;
                let wd = wr * (1.0 - m.damping * m.damping).sqrt();
                let lambda = Complex64::new(-m.damping * wr, wd);
                let ia = Complex64::new(0.0, a);
                let p = ia - lambda;
                let q = -ia - lambda;
                let j = ((p * u).exp() - 1.0) / p - ((q * u).exp() - 1.0) / q;
                let j = j / Complex64::new(0.0, 2.0);
                let g = m.shape[o] * m.shape[self.drive];
                x += g * h.peak_n / wd * ((lambda * tau).exp() * j).im;
            }
        }
        x
    }

    /// The receptance FRF from the drive to point `o` at `f_hz`, m/N.
    pub fn receptance(&self, o: usize, f_hz: f64) -> Complex64 {
        let w = 2.0 * PI * f_hz;
        self.modes
            .iter()
            .map(|m| {
                let wr = 2.0 * PI * m.f_hz;
                m.shape[o] * m.shape[self.drive]
                    / Complex64::new(wr * wr - w * w, 2.0 * m.damping * wr * w)
            })
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closed_form_matches_a_numerical_convolution() {
        let test = HammerTest {
            modes: vec![
                HammerMode {
                    f_hz: 40.0,
                    damping: 0.02,
                    shape: vec![1.0, 0.5],
                },
                HammerMode {
                    f_hz: 150.0,
                    damping: 0.01,
                    shape: vec![0.6, -0.8],
                },
            ],
            drive: 0,
            hits: vec![Hit {
                t_s: 0.01,
                width_s: 0.002,
                peak_n: 100.0,
            }],
        };
        // trapezoidal convolution of the force with the impulse response, 1 us steps
        let dt = 1e-6;
        for t in [0.0105f64, 0.0115, 0.02, 0.05] {
            let steps = ((t - 0.01) / dt).round() as usize;
            let mut x = 0.0;
            for k in 0..=steps {
                let v = 0.01 + k as f64 * dt;
                let tau = t - v;
                let h: f64 = test
                    .modes
                    .iter()
                    .map(|m| {
                        let wr = 2.0 * PI * m.f_hz;
                        let wd = wr * (1.0 - m.damping * m.damping).sqrt();
                        m.shape[1] * m.shape[0] * (-m.damping * wr * tau).exp() * (wd * tau).sin()
                            / wd
                    })
                    .sum();
                let w = if k == 0 || k == steps { 0.5 } else { 1.0 };
                x += w * test.force(v) * h * dt;
            }
            let got = test.displacement(1, t);
            assert!(
                (got - x).abs() < 1e-5 * x.abs().max(1e-9),
                "t {t}: {got} vs {x}"
            );
        }
    }
}

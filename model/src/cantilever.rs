//! The cantilever rig (method.md §3.2, the paper's laboratory validation): an aluminium
//! cantilever on a shaker, base (encastre) acceleration in, tip acceleration out, two modes,
//! band-limited random base excitation, accelerometers at 2048 Hz and a 120 fps camera looking
//! at a white disk on the tip. The only place the rig's constants live.
//!
//! Base-excited modal model: `q_i'' + 2 h_i w_i q_i' + w_i^2 q_i = -G_i xb''`,
//! `tip = xb + sum phi_i q_i`, so the transmissibility from base to tip acceleration is
//! `T(w) = 1 + sum G_i phi_i w^2 / (w_i^2 - w^2 + 2 i h_i w_i w)`.

use super::DiskTarget;
use firmware_core::spectrum::{Detrend, WelchConfig, Window};
use num_complex::Complex64;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Frames per test (10 s at 120 fps).
pub const FRAMES: usize = 1200;
/// Accelerometer samples per test (10 s at 2048 Hz).
pub const SAMPLES: usize = 20480;
/// Camera frame rate, fps.
pub const FPS: f64 = 120.0;
/// Accelerometer rate, Hz.
pub const FS_HZ: f64 = 2048.0;
/// Fine steps per accelerometer sample: the fine time base is 30 720 Hz, the common clock of
/// the camera and the ADC (method.md §2.7).
pub const FINE_PER_SAMPLE: usize = 15;
/// Camera scale, mm/px.
pub const MM_PER_PX: f64 = 0.1266;
/// The white disk of radius 10 px (level 255), its edge smoothed by a Gaussian of 0.5 px. Not
/// quite band-limited (the edge's Gaussian factor is 0.29 at the Nyquist frequency), so the EPSA
/// phase shift interpolates the sampled disk: its intensity centroid moves by up to ~2e-3 px
/// (tested in `recording`).
pub const TARGET: DiskTarget = DiskTarget {
    radius_px: 10.0,
    level: 255.0,
    edge_sigma_px: 0.5,
    texture: crate::Texture::Plain,
};
/// Binary centroid threshold: half the target level.
pub const THRESHOLD: u16 = 127;
/// Mode bands, Hz: mode 1 in [5, 15], mode 2 in [25, 45].
pub const BANDS: [(f64, f64); 2] = [(5.0, 15.0), (25.0, 45.0)];
/// The rig's estimator: one periodic Hann segment over the whole 10 s test (0.1 Hz bins).
pub const WELCH: WelchConfig = WelchConfig {
    fs_hz: FS_HZ as f32,
    nperseg: SAMPLES,
    noverlap: 0,
    nfft: SAMPLES,
    window: Window::Hann,
    detrend: Detrend::Constant,
};
/// Band of the random base acceleration, Hz.
pub const EXCITATION_BAND_HZ: (f64, f64) = (5.0, 50.0);
/// Tip motion peak to peak, mm (the excitation is scaled to it).
pub const TIP_PP_MM: f64 = 4.5;
/// Accelerometer noise, g RMS.
pub const ACCEL_NOISE_G: f64 = 0.00015;
/// Run-to-run scatter of the natural frequencies: Normal(f, 0.3 % of f).
pub const F_SCATTER: f64 = 0.003;
/// Run-to-run scatter of the damping ratios: Uniform(h +/- 5 %).
pub const ZETA_SCATTER: f64 = 0.05;

/// One mode of the base-excited model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseExcitedMode {
    /// Natural frequency, Hz.
    pub f_hz: f64,
    /// Damping ratio.
    pub zeta: f64,
    /// Participation times tip mode shape, `G_i phi_i`.
    pub g_phi: f64,
}

/// The structure, its excitation and its accelerometers.
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    /// Modes.
    pub modes: Vec<BaseExcitedMode>,
    /// Band of the random base acceleration, Hz.
    pub band_hz: (f64, f64),
    /// Tip motion peak to peak, mm (the excitation is scaled to it).
    pub tip_pp_mm: f64,
    /// Accelerometer noise, g RMS.
    pub accel_noise_g: f64,
    /// What the tip accelerometer reads of gravity as it tilts with the beam, per unit of the
    /// tip's slope, m/s^2 ([`Tilt::gain`]: `+g` for an upright beam, `-g` hanging, 0 for a
    /// horizontal beam moving vertically). 0 in the nominal rig.
    pub accel_tilt_gain: f64,
    /// Beam length, m (turns the mode shapes' slopes per beam length into radians per metre of
    /// tip motion; only used with a tilt gain).
    pub beam_length_m: f64,
}

impl Rig {
    /// Nominal parameters: 7.1 Hz (h 0.0115, G phi 1.566) and 32.4 Hz (h 0.011, G phi -0.867).
    pub fn nominal() -> Self {
        Rig {
            modes: vec![
                BaseExcitedMode {
                    f_hz: 7.1,
                    zeta: 0.0115,
                    g_phi: 1.566,
                },
                BaseExcitedMode {
                    f_hz: 32.4,
                    zeta: 0.011,
                    g_phi: -0.867,
                },
            ],
            band_hz: EXCITATION_BAND_HZ,
            tip_pp_mm: TIP_PP_MM,
            accel_noise_g: ACCEL_NOISE_G,
            accel_tilt_gain: 0.0,
            beam_length_m: 1.0,
        }
    }

    /// Draws the run-to-run scatter from `rng` ([`F_SCATTER`], [`ZETA_SCATTER`]). The draws are
    /// made even when `fixed` (the method-uncertainty variant keeps the nominal values), so both
    /// variants consume the run's stream alike.
    pub fn scatter(&mut self, rng: &mut ChaCha8Rng, fixed: bool) {
        for m in self.modes.iter_mut() {
            let z: f64 = StandardNormal.sample(rng);
            let u: f64 = rng.random();
            if !fixed {
                m.f_hz *= 1.0 + F_SCATTER * z;
                m.zeta *= 1.0 + ZETA_SCATTER * (2.0 * u - 1.0);
            }
        }
    }

    /// Transmissibility from base to tip acceleration at `f_hz` (closed form, see the module
    /// documentation).
    pub fn transmissibility(&self, f_hz: f64) -> Complex64 {
        self.transmissibility_at(f_hz, 1.0)
    }

    /// Transmissibility from base to the absolute acceleration at `xi = x / L` along the beam:
    /// each mode's term scaled by its shape there relative to the tip,
    /// `mode_shape(i, xi) / mode_shape(i, 1)` (exactly 1 at the tip).
    pub fn transmissibility_at(&self, f_hz: f64, xi: f64) -> Complex64 {
        self.transmissibility_seen(f_hz, View { xi, lever: 0.0 })
    }

    /// Transmissibility from base to what `view` sees (its position plus the projected
    /// rotation, [`View`]): each mode's term scaled by [`View::factor`].
    pub fn transmissibility_seen(&self, f_hz: f64, view: View) -> Complex64 {
        self.sum_of_modes(f_hz, |i, _| view.factor(i))
    }

    /// [`Rig::transmissibility_seen`] with each mode's factor given (`factors[i]`, e.g. a
    /// view's [`View::factor`]s computed once for a whole spectrum).
    pub fn transmissibility_scaled(&self, f_hz: f64, factors: &[f64]) -> Complex64 {
        self.sum_of_modes(f_hz, |i, _| factors[i])
    }

    /// Transmissibility from base to what the tip accelerometer reads: the tip's acceleration
    /// plus gravity projected on its sensing axis as it tilts with the beam
    /// (`accel_tilt_gain` times the tip slope, [`Tilt`]). The slope of mode `i` is
    /// `phi_i'(L) / (phi_i(L) L)` times its tip displacement, and the displacement is the
    /// acceleration over `-w^2`, so each mode's term is scaled by
    /// `1 + gain phi_i'/(phi_i L w^2)` (the term carries `w^2`, so it stays finite as `w`
    /// falls: a quasi-static tilt). Exactly [`Rig::transmissibility`] without a tilt gain.
    pub fn accelerometer_transmissibility(&self, f_hz: f64) -> Complex64 {
        let per_slope = self.accel_tilt_gain / self.beam_length_m;
        self.sum_of_modes(f_hz, |i, w2| 1.0 + per_slope * tip_slope_ratio(i) / w2)
    }

    /// `1 + sum_i scale(i, w^2) G_i phi_i w^2 / (w_i^2 - w^2 + 2 i h_i w_i w)`.
    fn sum_of_modes(&self, f_hz: f64, scale: impl Fn(usize, f64) -> f64) -> Complex64 {
        let w = 2.0 * std::f64::consts::PI * f_hz;
        let mut h = Complex64::new(1.0, 0.0);
        for (i, m) in self.modes.iter().enumerate() {
            let wn = 2.0 * std::f64::consts::PI * m.f_hz;
            let at = scale(i, w * w);
            h += at * m.g_phi * w * w / Complex64::new(wn * wn - w * w, 2.0 * m.zeta * wn * w);
        }
        h
    }
}

/// Standard gravity, m/s^2.
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// How the beam stands in gravity (`[rig] beam_orientation`), which decides what the tip
/// accelerometer reads of its own tilt. The accelerometer turns with the tip; its sensing axis,
/// perpendicular to the beam, tilts by the tip's slope `theta`. An accelerometer reads specific
/// force (acceleration minus gravity), so on a beam standing **upright** (clamped below, moving
/// horizontally) it reads `a - g theta`: gravity's projection adds to the motion (the tip tilts
/// the way it moves, `theta` in phase with the displacement, and the acceleration is
/// `-w^2` times it), and the accelerometer over-reads each mode by `1 + g phi'/(phi L w^2)`,
/// far more for a low mode than for a high one (`1/w^2`). **Hanging** (clamped above) it
/// under-reads by the same amount. A **horizontal** beam moving vertically tilts its axis about
/// the vertical: the projection changes by `1 - cos theta`, second order, none here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tilt {
    /// Horizontal beam, vertical motion: no first-order tilt reading (the default).
    #[default]
    Horizontal,
    /// Clamped below, free end up, horizontal motion: the accelerometer over-reads.
    Upright,
    /// Clamped above, free end down, horizontal motion: the accelerometer under-reads.
    Hanging,
}

impl Tilt {
    /// The tilt gain, m/s^2 per radian of tip slope: `+g`, `-g` or 0.
    pub fn gain(self) -> f64 {
        match self {
            Tilt::Horizontal => 0.0,
            Tilt::Upright => STANDARD_GRAVITY,
            Tilt::Hanging => -STANDARD_GRAVITY,
        }
    }
}

/// `phi_i'(L) / phi_i(L)` at the tip, per beam length: 1.3765 for mode 1, 4.7808 for mode 2
/// (computed once: a spectrum asks for it at every bin).
pub fn tip_slope_ratio(mode: usize) -> f64 {
    static RATIOS: std::sync::OnceLock<[f64; 2]> = std::sync::OnceLock::new();
    RATIOS.get_or_init(|| [0, 1].map(|m| mode_slope(m, 1.0) / mode_shape(m, 1.0)))[mode]
}

/// Where a camera sees the beam's motion: the displacement at `xi = x / L` along it, plus
/// `lever` (in beam lengths) times the beam's slope there. The lever term is the beam's rotation
/// projected on the image plane: a target standing off the beam, or seen in perspective off the
/// optical axis, moves in the image by the rotation times a lever arm as well as by the
/// deflection (the paper's explanation of its mode-1 chi_mu of 95 %: out-of-plane rotation of
/// the tip). Linear in the beam's motion, so per mode a constant factor (`factor`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Position along the beam, `x / L` (1 = the tip).
    pub xi: f64,
    /// Lever of the projected rotation, in beam lengths (0 = none; negative moves the image
    /// against the deflection).
    pub lever: f64,
}

impl View {
    /// What this view sees of mode `i`, relative to the tip's deflection:
    /// `(phi_i(xi) + lever phi_i'(xi)) / phi_i(1)` (exactly 1 at the tip without a lever).
    pub fn factor(&self, i: usize) -> f64 {
        if self.xi == 1.0 && self.lever == 0.0 {
            return 1.0;
        }
        (mode_shape(i, self.xi) + self.lever * mode_slope(i, self.xi)) / mode_shape(i, 1.0)
    }
}

/// `d mode_shape(mode, xi) / d xi`: the slope of the mode shape along the beam (per beam
/// length). At the tip `slope / shape` is 1.3765 for mode 1 and 4.7808 for mode 2.
pub fn mode_slope(mode: usize, xi: f64) -> f64 {
    let (bl, sigma) = MODE_CONSTANTS[mode];
    let b = bl * xi;
    bl * (b.sinh() + b.sin() - sigma * (b.cosh() - b.cos()))
}

/// `(beta_i L, sigma_i)` of the first two cantilever modes.
const MODE_CONSTANTS: [(f64, f64); 2] = [
    (1.875_104_068_7, 0.734_095_514_1),
    (4.694_091_132_9, 1.018_467_318_5),
];

/// Euler-Bernoulli cantilever mode shape of mode `mode` (0 or 1) at `xi = x / L` along the beam,
/// clamped at `xi = 0`: `cosh(b) - cos(b) - sigma (sinh(b) - sin(b))` with `b = beta_i L xi`
/// (`beta_1 L = 1.8751`, `beta_2 L = 4.6941`); the free tip takes the value +-2. The shape of the
/// targets along the beam for multi-target recordings and the modal tests.
pub fn mode_shape(mode: usize, xi: f64) -> f64 {
    let (bl, sigma) = MODE_CONSTANTS[mode];
    let b = bl * xi;
    b.cosh() - b.cos() - sigma * (b.sinh() - b.sin())
}

/// The tip's motion as the H1 estimator of the study weighs it: the nominal rig's test of seed 0
/// with acquisition `acq` is stationary, so one segment with the equivalent sinusoidal
/// amplitude (`sqrt(2)` RMS, px) of the whole record
/// (`imaging::exposure::ExposureCorrection::for_segments` of the simulation).
pub fn nominal_motion_segments(
    acq: &crate::Acquisition,
) -> anyhow::Result<Vec<crate::MotionSegment>> {
    let sim = crate::simulate(&crate::Rig::Cantilever(Rig::nominal()), acq, 0)?;
    let px: Vec<f64> = sim.tip_mm.iter().map(|mm| mm / MM_PER_PX).collect();
    Ok(vec![crate::MotionSegment {
        weight: 1.0,
        amplitude_px: crate::equivalent_amplitude_px(&px),
    }])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transmissibility_has_the_closed_form_limits_and_resonances() {
        let rig = Rig::nominal();
        // rigid-body limit: the tip follows the base
        assert!((rig.transmissibility(1e-3) - 1.0).norm() < 1e-6);
        // far above both modes: 1 - sum G phi
        let high: f64 = 1.0 - rig.modes.iter().map(|m| m.g_phi).sum::<f64>();
        assert!((rig.transmissibility(1e5) - high).norm() < 1e-3);
        // at a natural frequency that mode's term is -i G phi / (2 h) exactly; the other mode
        // and the 1 are added by their own closed forms
        for (i, m) in rig.modes.iter().enumerate() {
            let o = rig.modes[1 - i];
            let (w, wo) = (
                2.0 * std::f64::consts::PI * m.f_hz,
                2.0 * std::f64::consts::PI * o.f_hz,
            );
            let want = 1.0
                + Complex64::new(0.0, -m.g_phi / (2.0 * m.zeta))
                + o.g_phi * w * w / Complex64::new(wo * wo - w * w, 2.0 * o.zeta * wo * w);
            let got = rig.transmissibility(m.f_hz);
            assert!((got - want).norm() < 1e-9 * want.norm(), "{got} vs {want}");
        }
        // the paper's peaks: about 68 and 39
        assert!((rig.transmissibility(7.1).norm() - 68.0).abs() < 1.0);
        assert!((rig.transmissibility(32.4).norm() - 39.4).abs() < 1.0);
    }

    #[test]
    fn mode_slopes_are_the_derivatives_of_the_shapes() {
        for m in 0..2 {
            for k in 1..20 {
                let xi = k as f64 / 20.0;
                let h = 1e-6;
                let fd = (mode_shape(m, xi + h) - mode_shape(m, xi - h)) / (2.0 * h);
                assert!((mode_slope(m, xi) - fd).abs() < 1e-6, "mode {m} at {xi}");
            }
            // clamped: no slope at the root
            assert!(mode_slope(m, 0.0).abs() < 1e-12);
        }
        let ratio = |m: usize| mode_slope(m, 1.0) / mode_shape(m, 1.0);
        assert!((ratio(0) - 1.376_505).abs() < 1e-5, "{}", ratio(0));
        assert!((ratio(1) - 4.780_778).abs() < 1e-5, "{}", ratio(1));
        // a view with a lever scales each mode by 1 + lever * slope / shape at the tip
        let v = View {
            xi: 1.0,
            lever: -0.0324,
        };
        assert!((v.factor(0) - (1.0 - 0.0324 * ratio(0))).abs() < 1e-12);
        assert!((v.factor(1) - (1.0 - 0.0324 * ratio(1))).abs() < 1e-12);
    }

    #[test]
    fn mode_shapes_are_clamped_and_end_at_plus_minus_two() {
        for m in 0..2 {
            assert!(mode_shape(m, 0.0).abs() < 1e-12);
            // the free-end value of the Euler-Bernoulli shape with this normalisation is 2 (-1)^m
            let tip = mode_shape(m, 1.0);
            assert!((tip.abs() - 2.0).abs() < 1e-6, "mode {m}: {tip}");
        }
        // mode 2 has one node inside the beam (near x / L = 0.783), mode 1 none
        let sign_changes = |m: usize| {
            (1..100)
                .filter(|k| {
                    mode_shape(m, *k as f64 / 100.0) * mode_shape(m, (*k + 1) as f64 / 100.0) < 0.0
                })
                .count()
        };
        assert_eq!((sign_changes(0), sign_changes(1)), (0, 1));
    }
}

//! Modal parameters from complex FRFs (method.md §3.6): natural frequency and damping ratio per
//! resonance by a least-squares fit of a single-mode model with residual terms, residues per FRF
//! for a shared pole, mode shapes from the residues, and the modal assurance criterion (MAC).
//! Pure functions on in-memory arrays.
//!
//! # The model
//!
//! Around one resonance, in a band `[lo, hi]` Hz given by the caller, each FRF is modelled as a
//! complex-conjugate pole pair plus two residual terms standing for the modes outside the band
//! (Ewins, *Modal Testing*, 2nd ed., 4.3):
//!
//! ```text
//! H(w) = r / (iw - p) + conj(r) / (iw - conj(p)) + R_L (iw)^a + R_U (iw)^b
//! p = -zeta w_r + i w_r sqrt(1 - zeta^2)
//! ```
//!
//! with `w = 2 pi f`, `w_r = 2 pi f_hz` the undamped natural frequency and `zeta` the damping
//! ratio (viscous). The pole-pair form is that of any FRF of a real, linear, viscously damped
//! structure: with a complex residue `r` it covers receptance, mobility and accelerance alike
//! (the difference between them moves into `r` and the residuals) and complex (non-proportional,
//! or delayed) modes. The residual exponents follow the FRF's form ([`FrfForm`]): lower residual
//! (modes below the band: mass-like) and upper residual (modes above: stiffness-like) are
//! `(iw)^-2` and `(iw)^0` for receptance, `(iw)^-1` and `(iw)^1` for mobility, `(iw)^0` and
//! `(iw)^2` for accelerance. `R_L` and `R_U` are complex.
//!
//! The FRFs of this workspace (method.md §3.2: tip over base acceleration, vision acceleration over
//! base acceleration) are **accelerance-like** ratios: for the base-excited cantilever
//! `H(w) = 1 + sum_i c_i w^2 / (w_i^2 - w^2 + 2 i zeta_i w_i w)`, in which each mode is exactly a
//! pole pair plus the constant `-c_i` and the rigid-base `1` is a constant: use
//! [`FrfForm::Accelerance`].
//!
//! # The fit
//!
//! Nonlinear least squares, unweighted, over the real and imaginary parts of all bins in the
//! band (and all FRFs, for a shared pole), by **variable projection** (Golub & Pereyra): for a
//! given pole the model is linear in `r`, `R_L`, `R_U`, which are solved for exactly (Householder
//! QR, per FRF); the two pole parameters are then found by Levenberg-Marquardt on the projected
//! residual. The start is the best point of a grid around the band's largest-|H| bin (+/- 2 bins
//! in eighths of a bin, damping 1e-4 to 0.3 log-spaced), so no half-power estimate is needed:
//! with 0.1 Hz bins a mode of 0.16 Hz half-power bandwidth has only two bins above half power,
//! too few for a bandwidth estimate, but all the band's bins constrain the pole through the
//! model. Computation uses frequencies scaled by the band centre, for conditioning.
//!
//! The band should contain one resonance and no other; the fitted natural frequency must lie
//! inside it, else [`ModalError::PoleOutsideBand`].
//!
//! # Mode shapes
//!
//! For a pole shared by several FRFs (targets), the residue of FRF `j` is proportional to the
//! mode shape at that target times the mode's participation at the common input, so the shape is
//! the residue vector normalised ([`normalise_shape`]): divided by its component of largest
//! modulus, which becomes exactly `1` (unit largest modulus, that component's real part
//! positive). For a normal (real) mode the result is real up to noise.

use num_complex::Complex64;
use std::f64::consts::PI;

mod fit;
mod linalg;
mod smoothing;

pub use smoothing::Smoothing;

use fit::Problem;

/// Form of an FRF: which motion quantity over which. It sets the residual terms' exponents (see
/// the module documentation). The workspace's acceleration-over-acceleration FRFs are
/// [`FrfForm::Accelerance`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrfForm {
    /// Displacement over force (or over an input whose FRF has receptance-like residuals):
    /// residuals `R_L (iw)^-2 + R_U`.
    Receptance,
    /// Velocity over force: residuals `R_L (iw)^-1 + R_U (iw)`.
    Mobility,
    /// Acceleration over force, or acceleration over base acceleration:
    /// residuals `R_L + R_U (iw)^2`.
    #[default]
    Accelerance,
}

impl FrfForm {
    /// Exponents `(a, b)` of `(iw)` in the lower and upper residual terms.
    pub fn residual_exponents(self) -> (i32, i32) {
        match self {
            FrfForm::Receptance => (-2, 0),
            FrfForm::Mobility => (-1, 1),
            FrfForm::Accelerance => (0, 2),
        }
    }
}

/// A mode's pole: undamped natural frequency and viscous damping ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pole {
    /// Undamped natural frequency `|p| / (2 pi)`, Hz.
    pub f_hz: f64,
    /// Damping ratio `-Re(p) / |p|`, dimensionless, in (0, 1).
    pub damping: f64,
}

impl Pole {
    /// The pole in the upper half plane, rad/s: `-zeta w_r + i w_r sqrt(1 - zeta^2)`.
    pub fn s(&self) -> Complex64 {
        let wr = 2.0 * PI * self.f_hz;
        Complex64::new(
            -self.damping * wr,
            wr * (1.0 - self.damping * self.damping).sqrt(),
        )
    }

    fn from_s(p: Complex64) -> Pole {
        let wr = p.norm();
        Pole {
            f_hz: wr / (2.0 * PI),
            damping: -p.re / wr,
        }
    }
}

/// The linear part of one FRF's fit for a given pole: residue and residual terms, in the FRF's
/// units with `w` in rad/s (see the module documentation for the model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResidueFit {
    /// Residue `r` of the pole `p` (that of `conj(p)` is `conj(r)`).
    pub residue: Complex64,
    /// Lower residual `R_L`, the coefficient of `(iw)^a` ([`FrfForm::residual_exponents`]).
    pub lower_residual: Complex64,
    /// Upper residual `R_U`, the coefficient of `(iw)^b`.
    pub upper_residual: Complex64,
    /// Relative misfit over the band, `||model - data|| / ||data||` (0 for a perfect fit).
    pub misfit: f64,
}

impl ResidueFit {
    /// The fitted model at `f_hz`, for the pole it was fitted with and the FRF's form.
    pub fn evaluate(&self, pole: &Pole, form: FrfForm, f_hz: f64) -> Complex64 {
        let s = Complex64::new(0.0, 2.0 * PI * f_hz);
        let p = pole.s();
        let (a, b) = form.residual_exponents();
        self.residue / (s - p)
            + self.residue.conj() / (s - p.conj())
            + self.lower_residual * s.powi(a)
            + self.upper_residual * s.powi(b)
    }
}

/// One resonance fitted on one FRF ([`fit_mode`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeFit {
    /// Band fitted, Hz.
    pub band_hz: (f64, f64),
    /// Natural frequency and damping ratio.
    pub pole: Pole,
    /// Residue and residuals of the FRF.
    pub fit: ResidueFit,
    /// Number of bins in the band.
    pub bins: usize,
    /// Levenberg-Marquardt iterations after the grid start.
    pub iterations: usize,
}

impl ModeFit {
    /// Natural frequency, Hz.
    pub fn f_hz(&self) -> f64 {
        self.pole.f_hz
    }

    /// Damping ratio.
    pub fn damping(&self) -> f64 {
        self.pole.damping
    }
}

/// A mode shape across several FRFs (targets): the pole used, each FRF's residue fit, and the
/// normalised shape ([`fit_shape`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ShapeFit {
    /// Band fitted, Hz.
    pub band_hz: (f64, f64),
    /// The pole shared by all FRFs (fitted jointly, or given).
    pub pole: Pole,
    /// Residue fit per FRF, in the order given.
    pub fits: Vec<ResidueFit>,
    /// The residues normalised by [`normalise_shape`], one per FRF.
    pub shape: Vec<Complex64>,
}

/// What can go wrong in a modal fit. Each names the band.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ModalError {
    /// The band is not `0 <= lo < hi` with finite ends.
    #[error("band {lo}-{hi} Hz is not a frequency band (need 0 <= lo < hi)")]
    InvalidBand {
        /// Lower end, Hz.
        lo: f64,
        /// Upper end, Hz.
        hi: f64,
    },
    /// No FRF was given.
    #[error("band {lo}-{hi} Hz: no FRF to fit")]
    NoFrf {
        /// Lower end, Hz.
        lo: f64,
        /// Upper end, Hz.
        hi: f64,
    },
    /// An FRF's length differs from the frequency axis.
    #[error("FRF {frf} has {len} values but the frequency axis has {freqs}")]
    LengthMismatch {
        /// Index of the FRF (0-based, in the order given).
        frf: usize,
        /// Its length.
        len: usize,
        /// Length of the frequency axis.
        freqs: usize,
    },
    /// Too few bins in the band for the model's 8 real parameters.
    #[error("band {lo}-{hi} Hz holds {bins} bins; a modal fit needs at least {needed}")]
    TooFewBins {
        /// Lower end, Hz.
        lo: f64,
        /// Upper end, Hz.
        hi: f64,
        /// Bins found in the band.
        bins: usize,
        /// Bins needed.
        needed: usize,
    },
    /// A frequency or FRF value in the band is not finite, or the frequencies do not increase.
    #[error("band {lo}-{hi} Hz: FRF {frf} at {f_hz} Hz is not finite, or the frequencies do not increase there")]
    NotFinite {
        /// Lower end, Hz.
        lo: f64,
        /// Upper end, Hz.
        hi: f64,
        /// Index of the FRF (0-based).
        frf: usize,
        /// Frequency of the bad bin, Hz.
        f_hz: f64,
    },
    /// The given pole is not a damped oscillation (`f_hz > 0`, `0 < damping < 1`).
    #[error(
        "band {lo}-{hi} Hz: the pole {f_hz} Hz, damping {damping} is not a damped oscillation"
    )]
    InvalidPole {
        /// Lower end, Hz.
        lo: f64,
        /// Upper end, Hz.
        hi: f64,
        /// Natural frequency given, Hz.
        f_hz: f64,
        /// Damping given.
        damping: f64,
    },
    /// The least-squares problem for the residues is singular (e.g. all-zero FRF).
    #[error("band {lo}-{hi} Hz: the residue least-squares problem is singular")]
    Singular {
        /// Lower end, Hz.
        lo: f64,
        /// Upper end, Hz.
        hi: f64,
    },
    /// The best-fitting pole lies outside the band: no resonance in it, or the band cuts one.
    #[error("band {lo}-{hi} Hz: the best-fitting pole ({f_hz:.4} Hz, damping {damping:.4}) lies outside the band; is there one resonance inside it?")]
    PoleOutsideBand {
        /// Lower end, Hz.
        lo: f64,
        /// Upper end, Hz.
        hi: f64,
        /// The pole's natural frequency, Hz.
        f_hz: f64,
        /// Its damping ratio.
        damping: f64,
    },
}

/// Real unknowns per FRF in the linear part (Re/Im of r, R_L, R_U).
const LINEAR: usize = 6;
/// Fewest bins a fit accepts: 2 real equations per bin must exceed the 8 real parameters with
/// some redundancy.
const MIN_BINS: usize = 6;

/// Fits one resonance in `band_hz` to one FRF: natural frequency, damping ratio, residue and
/// residuals (see the module documentation for the model and method).
///
/// `freq_hz` are the bin frequencies (increasing inside the band), `h` the complex FRF per bin.
pub fn fit_mode(
    freq_hz: &[f64],
    h: &[Complex64],
    band_hz: (f64, f64),
    form: FrfForm,
) -> Result<ModeFit, ModalError> {
    let problem = Problem::new(freq_hz, &[h], band_hz, form, None)?;
    let (theta, iterations) = problem.fit_pole();
    mode_fit(&problem, theta, iterations)
}

/// The [`ModeFit`] of one FRF's `problem` at its fitted scaled pole `theta`.
fn mode_fit(problem: &Problem, theta: [f64; 2], iterations: usize) -> Result<ModeFit, ModalError> {
    let eval = problem.solve(theta).ok_or(problem.singular())?;
    let pole = problem.check_pole(theta)?;
    Ok(ModeFit {
        band_hz: problem.band,
        pole,
        fit: problem.unscale(&eval, 0),
        bins: problem.s.len(),
        iterations,
    })
}

/// [`fit_mode`] for an FRF estimated by Welch's method with the kernel `smoothing`
/// ([`Smoothing::welch`]): the model smoothed by the kernel is fitted, so the pole and the
/// residue are those of the FRF itself, without the window's resolution bias (a mode a few
/// lines wide comes out of the estimate lower and wider). Levenberg-Marquardt starts from the
/// unsmoothed fit's pole. [`ResidueFit::evaluate`] gives the FRF, [`Smoothing::apply`] over it the
/// estimate's expectation.
pub fn fit_mode_smoothed(
    freq_hz: &[f64],
    h: &[Complex64],
    band_hz: (f64, f64),
    form: FrfForm,
    smoothing: &Smoothing,
) -> Result<ModeFit, ModalError> {
    let plain = Problem::new(freq_hz, &[h], band_hz, form, None)?;
    let problem = Problem::new(freq_hz, &[h], band_hz, form, Some(smoothing))?;
    let (start, _) = plain.fit_pole();
    let (theta, iterations) = problem.refine(start, problem.cost(start));
    mode_fit(&problem, theta, iterations)
}

/// Fits one resonance shared by several FRFs (e.g. the targets along a structure, and the
/// accelerometer): with `pole` `None` the pole is fitted jointly to all FRFs (one pole, a
/// residue and residuals per FRF, least squares over all of them); with `Some(pole)` (e.g.
/// fitted on the accelerometer's FRF with [`fit_mode`]) only the residues are fitted. The shape
/// is the residues normalised by [`normalise_shape`].
pub fn fit_shape(
    freq_hz: &[f64],
    frfs: &[&[Complex64]],
    band_hz: (f64, f64),
    form: FrfForm,
    pole: Option<Pole>,
) -> Result<ShapeFit, ModalError> {
    let problem = Problem::new(freq_hz, frfs, band_hz, form, None)?;
    let theta = match pole {
        Some(p) => {
            if !(p.f_hz > 0.0 && p.damping > 0.0 && p.damping < 1.0) {
                return Err(ModalError::InvalidPole {
                    lo: band_hz.0,
                    hi: band_hz.1,
                    f_hz: p.f_hz,
                    damping: p.damping,
                });
            }
            let s = p.s() / problem.wc;
            [s.re, s.im]
        }
        None => problem.fit_pole().0,
    };
    let eval = problem.solve(theta).ok_or(problem.singular())?;
    let pole = match pole {
        Some(p) => p,
        None => problem.check_pole(theta)?,
    };
    let fits: Vec<ResidueFit> = (0..frfs.len()).map(|j| problem.unscale(&eval, j)).collect();
    let residues: Vec<Complex64> = fits.iter().map(|f| f.residue).collect();
    Ok(ShapeFit {
        band_hz,
        pole,
        fits,
        shape: normalise_shape(&residues),
    })
}

/// Normalises a mode shape: divides it by its component of largest modulus, so that component
/// becomes `1` (unit largest modulus, real part positive) and the others keep their modulus and
/// phase relative to it. All-zero input is returned unchanged.
pub fn normalise_shape(v: &[Complex64]) -> Vec<Complex64> {
    let largest = v
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap_or_default();
    if largest.norm() == 0.0 {
        return v.to_vec();
    }
    v.iter().map(|c| c / largest).collect()
}

/// Modal assurance criterion between two complex shapes of the same length:
/// `|a^H b|^2 / ((a^H a) (b^H b))`, in [0, 1]; 1 when one is a complex multiple of the other.
/// Returns `NaN` for different lengths or a zero shape (no direction to compare).
pub fn mac(a: &[Complex64], b: &[Complex64]) -> f64 {
    if a.len() != b.len() {
        return f64::NAN;
    }
    let ab: Complex64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let aa: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let bb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if aa == 0.0 || bb == 0.0 {
        return f64::NAN;
    }
    ab.norm_sqr() / (aa * bb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng as _;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution as _, StandardNormal};

    /// The cantilever rig of method.md §3.2: (f Hz, damping, G phi at the tip).
    const RIG: [(f64, f64, f64); 2] = [(7.1, 0.0115, 1.566), (32.4, 0.011, -0.867)];
    /// Bands of method.md §3.2.
    const BANDS: [(f64, f64); 2] = [(5.0, 15.0), (25.0, 45.0)];

    /// Closed-form FRF of the base-excited modal model (method.md §3.2), output over base
    /// acceleration, for a point whose participation-times-shape is `gphi[i]` per mode:
    /// `1 + sum_i gphi_i w^2 / (w_i^2 - w^2 + 2 i h_i w_i w)`.
    fn base_excited(f: f64, gphi: &[f64]) -> Complex64 {
        let w = 2.0 * PI * f;
        let mut h = Complex64::new(1.0, 0.0);
        for (&(fi, zi, _), &g) in RIG.iter().zip(gphi) {
            let wi = 2.0 * PI * fi;
            h += g * w * w / Complex64::new(wi * wi - w * w, 2.0 * zi * wi * w);
        }
        h
    }

    /// One mode of pole `(f_hz, damping)` with `[residue, lower, upper]` residual terms (re, im),
    /// exactly of the model's `form` at the frequencies `f`: the terms and the FRF.
    fn exact_frf(
        f: &[f64],
        (f_hz, damping): (f64, f64),
        [r, l, u]: [(f64, f64); 3],
        form: FrfForm,
    ) -> (ResidueFit, Vec<Complex64>) {
        let p = Pole { f_hz, damping };
        let truth = ResidueFit {
            residue: Complex64::new(r.0, r.1),
            lower_residual: Complex64::new(l.0, l.1),
            upper_residual: Complex64::new(u.0, u.1),
            misfit: 0.0,
        };
        let h = f.iter().map(|&x| truth.evaluate(&p, form, x)).collect();
        (truth, h)
    }

    /// 0.1 Hz bins to 60 Hz, as the rig's H1 (2048 Hz, nfft 20480).
    fn bins() -> Vec<f64> {
        (0..=600).map(|k| k as f64 * 0.1).collect()
    }

    fn tip() -> Vec<f64> {
        RIG.iter().map(|m| m.2).collect()
    }

    #[test]
    fn exact_two_mode_frf_gives_the_model_poles() {
        let f = bins();
        let h: Vec<Complex64> = f.iter().map(|&x| base_excited(x, &tip())).collect();
        for (m, band) in BANDS.iter().enumerate() {
            let fit = fit_mode(&f, &h, *band, FrfForm::Accelerance).unwrap();
            let (f0, z0, _) = RIG[m];
            let ef = (fit.f_hz() - f0) / f0;
            let ez = (fit.damping() - z0) / z0;
            println!(
                "mode {}: f {:.6} Hz ({ef:.2e}), damping {:.6} ({ez:.2e}), misfit {:.2e}, {} it",
                m + 1,
                fit.f_hz(),
                fit.damping(),
                fit.fit.misfit,
                fit.iterations
            );
            // The only model error is the other mode's residual beyond R_L + R_U (iw)^2 (its
            // w^4 / w_2^4 and w_1^2 / w^2 curvature across the band, ~0.1 % of the peak):
            assert!(ef.abs() < 1e-5, "mode {m}: f {}", fit.f_hz());
            assert!(ez.abs() < 1e-3, "mode {m}: damping {}", fit.damping());
        }
    }

    #[test]
    fn single_mode_is_recovered_to_rounding() {
        // One mode, FRF exactly of the model's form: nothing but rounding separates fit and truth.
        let f = bins();
        let residues = [(0.3, -40.0), (1.0, 0.0), (-2e-5, 1e-6)];
        let (truth, h) = exact_frf(&f, (7.1, 0.0115), residues, FrfForm::Accelerance);
        let fit = fit_mode(&f, &h, (5.0, 15.0), FrfForm::Accelerance).unwrap();
        assert!((fit.f_hz() - 7.1).abs() < 1e-9 * 7.1, "{}", fit.f_hz());
        assert!(
            (fit.damping() - 0.0115).abs() < 1e-7 * 0.0115,
            "{}",
            fit.damping()
        );
        assert!((fit.fit.residue - truth.residue).norm() < 1e-7 * truth.residue.norm());
        assert!((fit.fit.lower_residual - truth.lower_residual).norm() < 1e-7);
        assert!(fit.fit.misfit < 1e-10);
    }

    #[test]
    fn receptance_and_mobility_forms_recover_their_pole() {
        // One mode of each form with its own residual terms: the fit must pick the exponents.
        let f = bins();
        for form in [FrfForm::Receptance, FrfForm::Mobility] {
            let residues = [(-1e-4, -2e-2), (-3.0, 0.0), (2e-7, 0.0)];
            let (_, h) = exact_frf(&f, (32.4, 0.011), residues, form);
            let fit = fit_mode(&f, &h, (25.0, 45.0), form).unwrap();
            assert!(
                (fit.f_hz() - 32.4).abs() < 1e-8 * 32.4,
                "{form:?}: {}",
                fit.f_hz()
            );
            assert!(
                (fit.damping() - 0.011).abs() < 1e-6 * 0.011,
                "{form:?}: {}",
                fit.damping()
            );
        }
    }

    /// Adds complex Gaussian noise of `rel` times |H| per bin (the H1 random error is roughly
    /// proportional to |H|: sqrt((1 - coh^2) / (2 coh^2 n_d))).
    fn noisy(h: &[Complex64], rel: f64, rng: &mut ChaCha8Rng) -> Vec<Complex64> {
        h.iter()
            .map(|v| {
                let re: f64 = StandardNormal.sample(rng);
                let im: f64 = StandardNormal.sample(rng);
                v + Complex64::new(re, im) * (rel * v.norm() / 2f64.sqrt())
            })
            .collect()
    }

    #[test]
    fn noisy_frf_within_ten_percent() {
        // 5 % complex noise per bin, 20 realisations: every damping ratio within 10 % of the
        // model's, every frequency within a quarter bin.
        let f = bins();
        let h: Vec<Complex64> = f.iter().map(|&x| base_excited(x, &tip())).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(14);
        let mut worst = [(0.0f64, 0.0f64); 2];
        for _ in 0..20 {
            let hn = noisy(&h, 0.05, &mut rng);
            for (m, band) in BANDS.iter().enumerate() {
                let fit = fit_mode(&f, &hn, *band, FrfForm::Accelerance).unwrap();
                let (f0, z0, _) = RIG[m];
                worst[m].0 = worst[m].0.max((fit.f_hz() - f0).abs());
                worst[m].1 = worst[m].1.max(((fit.damping() - z0) / z0).abs());
            }
        }
        println!("worst |df| Hz, |dzeta|/zeta over 20 noisy FRFs: {worst:?}");
        for (m, (df, dz)) in worst.iter().enumerate() {
            assert!(*df < 0.025, "mode {}: |df| {df}", m + 1);
            assert!(*dz < 0.10, "mode {}: damping error {dz}", m + 1);
        }
    }

    fn five_targets() -> Vec<Vec<Complex64>> {
        let f = bins();
        (1..=5)
            .map(|j| {
                let xi = j as f64 / 5.0;
                let gphi: Vec<f64> = (0..2)
                    .map(|m| {
                        RIG[m].2 * vibcam_model::cantilever::mode_shape(m, xi)
                            / vibcam_model::cantilever::mode_shape(m, 1.0)
                    })
                    .collect();
                f.iter().map(|&x| base_excited(x, &gphi)).collect()
            })
            .collect()
    }

    fn model_shape(mode: usize) -> Vec<Complex64> {
        (1..=5)
            .map(|j| {
                Complex64::new(
                    vibcam_model::cantilever::mode_shape(mode, j as f64 / 5.0),
                    0.0,
                )
            })
            .collect()
    }

    #[test]
    fn five_point_shapes_match_the_model() {
        let f = bins();
        let targets = five_targets();
        let refs: Vec<&[Complex64]> = targets.iter().map(|v| v.as_slice()).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let noisy_targets: Vec<Vec<Complex64>> =
            targets.iter().map(|h| noisy(h, 0.05, &mut rng)).collect();
        let noisy_refs: Vec<&[Complex64]> = noisy_targets.iter().map(|v| v.as_slice()).collect();
        for (m, band) in BANDS.iter().enumerate() {
            let joint = fit_shape(&f, &refs, *band, FrfForm::Accelerance, None).unwrap();
            let truth = model_shape(m);
            let mac_exact = mac(&joint.shape, &truth);
            // The tip has the largest modulus in both modes: it is exactly 1.
            assert_eq!(joint.shape[4], Complex64::new(1.0, 0.0));
            assert!((joint.pole.f_hz - RIG[m].0).abs() < 1e-4);
            // Shared pole from the tip FRF alone, residues for all:
            let tip_fit = fit_mode(&f, refs[4], *band, FrfForm::Accelerance).unwrap();
            let given =
                fit_shape(&f, &refs, *band, FrfForm::Accelerance, Some(tip_fit.pole)).unwrap();
            let noisy = fit_shape(&f, &noisy_refs, *band, FrfForm::Accelerance, None).unwrap();
            let mac_noisy = mac(&noisy.shape, &truth);
            println!(
                "mode {}: MAC exact {:.9}, given pole {:.9}, 5 % noise {:.6}; noisy f {:.4} damping {:.5}",
                m + 1,
                mac_exact,
                mac(&given.shape, &truth),
                mac_noisy,
                noisy.pole.f_hz,
                noisy.pole.damping
            );
            assert!(mac_exact > 1.0 - 1e-6, "mode {m}: {mac_exact}");
            assert!(mac(&given.shape, &truth) > 1.0 - 1e-6);
            assert!(mac_noisy >= 0.999, "mode {m}: {mac_noisy}");
            // The other mode's shape is far from this one (cantilever modes are orthogonal in
            // mass, not in 5 points, so only well below 1):
            assert!(mac(&joint.shape, &model_shape(1 - m)) < 0.5);
        }
    }

    #[test]
    fn mac_properties() {
        let a = model_shape(0);
        let b = model_shape(1);
        assert!((mac(&a, &a) - 1.0).abs() < 1e-15);
        // Invariant to a complex scale of either shape:
        let k = Complex64::new(-0.3, 2.5);
        let ak: Vec<Complex64> = a.iter().map(|x| x * k).collect();
        assert!((mac(&ak, &a) - 1.0).abs() < 1e-14);
        assert!((mac(&ak, &b) - mac(&a, &b)).abs() < 1e-14);
        // Symmetric, within [0, 1], 0 for orthogonal shapes:
        assert!((mac(&a, &b) - mac(&b, &a)).abs() < 1e-15);
        assert!((0.0..=1.0).contains(&mac(&a, &b)));
        let e1 = [Complex64::new(1.0, 0.0), Complex64::new(0.0, 0.0)];
        let e2 = [Complex64::new(0.0, 0.0), Complex64::new(0.0, 1.0)];
        assert_eq!(mac(&e1, &e2), 0.0);
        // Closed form for two real 2-vectors at 45 degrees: cos^2 = 1/2.
        let d = [Complex64::new(1.0, 0.0), Complex64::new(1.0, 0.0)];
        assert!((mac(&e1, &d) - 0.5).abs() < 1e-15);
        assert!(mac(&a, &a[..3]).is_nan());
    }

    #[test]
    fn normalised_shape_has_unit_largest_component() {
        let v = [
            Complex64::new(0.0, 0.5),
            Complex64::new(0.0, -2.0),
            Complex64::new(1.0, 1.0),
        ];
        let n = normalise_shape(&v);
        assert_eq!(n[1], Complex64::new(1.0, 0.0));
        assert!((n[0] - Complex64::new(-0.25, 0.0)).norm() < 1e-15);
        assert!((n[2].norm() - 2f64.sqrt() / 2.0).abs() < 1e-15);
    }

    #[test]
    fn errors_name_the_band() {
        let f = bins();
        let h: Vec<Complex64> = f.iter().map(|&x| base_excited(x, &tip())).collect();
        let e = fit_mode(&f, &h, (5.0, 5.25), FrfForm::Accelerance).unwrap_err();
        assert!(matches!(e, ModalError::TooFewBins { bins: 3, .. }), "{e}");
        assert!(e.to_string().contains("5-5.25 Hz"), "{e}");
        let e = fit_mode(&f, &h[..10], (5.0, 15.0), FrfForm::Accelerance).unwrap_err();
        assert!(matches!(e, ModalError::LengthMismatch { .. }));
        // A band that cuts mode 1 off, holding only its falling flank: the pole is outside.
        let e = fit_mode(&f, &h, (7.6, 20.0), FrfForm::Accelerance).unwrap_err();
        assert!(matches!(e, ModalError::PoleOutsideBand { .. }), "{e}");
        let mut bad = h.clone();
        bad[70].re = f64::NAN;
        let e = fit_mode(&f, &bad, (5.0, 15.0), FrfForm::Accelerance).unwrap_err();
        assert!(e.to_string().contains("FRF 0 at 7"), "{e}");
    }

    /// Welch H1 (Hann segments of `nperseg`, half overlap) of a long record of white input
    /// through the first mode of the rig, exactly (periodic over the record, in the frequency
    /// domain): the estimate whose resolution bias the smoothed fit must remove.
    fn welch_of_one_mode(nperseg: usize, seed: u64) -> vibcam_chain::frf::Frf {
        let (fs, n) = (64.0, 1 << 18);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let x: Vec<f64> = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
        let mut planner = vibcam_fft::RealPlanner::new();
        let (fwd, inv) = (planner.forward(n), planner.inverse(n));
        let mut spec = fwd.make_output_vec();
        fwd.process(&mut x.clone(), &mut spec).unwrap();
        for (k, v) in spec.iter_mut().enumerate() {
            *v *= base_excited(k as f64 * fs / n as f64, &[RIG[0].2, 0.0]) / n as f64;
        }
        spec[n / 2].im = 0.0;
        let mut y = vec![0.0; n];
        inv.process(&mut spec, &mut y).unwrap();
        let settings = vibcam_chain::frf::WelchSettings {
            window: Window::Hann,
            nperseg: Some(nperseg),
            noverlap: None,
            nfft: None,
            detrend: Default::default(),
        };
        let config = settings
            .resolve(n, fs, vibcam_chain::frf::Defaults::Scipy)
            .unwrap();
        vibcam_chain::frf::estimate(&x, &y, config).unwrap()
    }

    use firmware_core::spectrum::Window;

    #[test]
    fn the_smoothed_fit_removes_the_windows_resolution_bias_from_a_welch_estimate() {
        // Segments of 10 s: 0.1 Hz lines, Hann's noise bandwidth 0.15 Hz against the mode's
        // half-power bandwidth 2 h f = 0.163 Hz. The plain fit sees a lower, wider mode.
        let (f1, h1) = (RIG[0].0, RIG[0].1);
        let frf = welch_of_one_mode(640, 7);
        let band = (5.0, 10.0);
        let plain = fit_mode(&frf.freq_hz, &frf.h1, band, FrfForm::Accelerance).unwrap();
        let kernel = Smoothing::welch(Window::Hann, 640, 64.0);
        let fit =
            fit_mode_smoothed(&frf.freq_hz, &frf.h1, band, FrfForm::Accelerance, &kernel).unwrap();
        let err = |z: f64| z / h1 - 1.0;
        assert!(
            err(plain.pole.damping) > 0.15,
            "plain {}",
            plain.pole.damping
        );
        assert!(
            err(fit.pole.damping).abs() < 0.03,
            "smoothed {}",
            fit.pole.damping
        );
        assert!((fit.pole.f_hz / f1 - 1.0).abs() < 1e-3, "{}", fit.pole.f_hz);
        // and the FRF at the line nearest the mode: the estimate is low, the fit's model is not
        let k = frf
            .freq_hz
            .iter()
            .position(|f| (f - f1).abs() < 0.05)
            .unwrap();
        let truth = base_excited(frf.freq_hz[k], &[RIG[0].2, 0.0]).norm();
        let model = fit
            .fit
            .evaluate(&fit.pole, FrfForm::Accelerance, frf.freq_hz[k])
            .norm();
        assert!(
            frf.h1[k].norm() / truth < 0.9,
            "{} {truth}",
            frf.h1[k].norm()
        );
        assert!((model / truth - 1.0).abs() < 0.03, "{model} {truth}");
    }

    #[test]
    fn the_smoothed_fit_recovers_an_exactly_smoothed_mode() {
        // The smoothed model itself as data: the fit must give back the pole it was made of,
        // down to a mode a fifth of a line wide.
        let f: Vec<f64> = (0..=200).map(|k| k as f64 * 0.1).collect();
        let kernel = Smoothing::welch(Window::Hann, 20, 2.0);
        for damping in [0.02, 0.005, 0.0015] {
            let (truth, _) = exact_frf(
                &f,
                (7.13, damping),
                [(3.0, 1.0), (0.5, 0.0), (1e-4, 0.0)],
                FrfForm::Accelerance,
            );
            let pole = Pole {
                f_hz: 7.13,
                damping,
            };
            let h: Vec<Complex64> = f
                .iter()
                .map(|&x| kernel.apply(|v| truth.evaluate(&pole, FrfForm::Accelerance, v), x))
                .collect();
            let fit =
                fit_mode_smoothed(&f, &h, (5.0, 10.0), FrfForm::Accelerance, &kernel).unwrap();
            assert!(
                (fit.pole.damping / damping - 1.0).abs() < 1e-3,
                "{damping}: {:?}",
                fit.pole
            );
            assert!((fit.pole.f_hz / 7.13 - 1.0).abs() < 1e-5, "{:?}", fit.pole);
        }
    }
}

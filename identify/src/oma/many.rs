//! Modes from many channels (a dense field of points: hundreds of records): the modes are
//! identified on a few reference channels, and each mode's shape is then carried to every
//! channel through the cross-spectra between all channels and the references at the mode's
//! line (docs/method.md §3.12, "Many channels").
//!
//! The full cross-spectral matrix of `K` channels holds `K^2` values per line (768 channels of
//! 129 lines: 1.2 GB) and SSI's block Hankel matrix grows as `K`; both are bounded here by the
//! references. They are chosen by pivoted Gram-Schmidt on the records (means removed): first
//! the channel of most variance, then each time the channel with most variance left once the
//! chosen ones are projected out, so that the references span the motion the channels share
//! (every mode one of them sees). The shape of a mode at every channel is the first left
//! singular vector of the `K x R` cross-spectral matrix `G[k, r] = E[X_k conj(X_r)]` at the
//! line nearest the mode's frequency (at a lightly damped, separated mode it is dominated by
//! that mode, as FDD's shape is), turned to the phase of the mode's shape at the references;
//! its magnitudes' intervals are the jackknife over groups of segments left out.

use super::csd::{self, CsdConfig};
use super::uncertainty::{group, jackknife, GROUPS};
use super::{OmaResult, OmaSettings};
use nalgebra::DMatrix;
use num_complex::Complex64;

/// The most channels analysed as they are; a record of more is analysed on references.
pub const MAX_FULL_CHANNELS: usize = 48;

/// References chosen among many channels.
pub const REFERENCES: usize = 12;

/// The `r` channels that span most of the records' motion (pivoted Gram-Schmidt), in the order
/// chosen; channel indices.
pub fn references(channels: &[Vec<f64>], r: usize) -> Vec<usize> {
    let mut rest: Vec<Vec<f64>> = channels
        .iter()
        .map(|c| {
            let m = c.iter().sum::<f64>() / c.len().max(1) as f64;
            c.iter().map(|v| v - m).collect()
        })
        .collect();
    let energy = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
    let mut chosen = Vec::new();
    while chosen.len() < r.min(channels.len()) {
        let (best, e) = rest
            .iter()
            .enumerate()
            .filter(|(i, _)| !chosen.contains(i))
            .map(|(i, v)| (i, energy(v)))
            .fold((usize::MAX, -1.0), |a, b| if b.1 > a.1 { b } else { a });
        if best == usize::MAX || e <= 0.0 {
            break;
        }
        chosen.push(best);
        let q: Vec<f64> = rest[best].iter().map(|v| v / e.sqrt()).collect();
        for v in rest.iter_mut() {
            let p: f64 = v.iter().zip(&q).map(|(a, b)| a * b).sum();
            v.iter_mut().zip(&q).for_each(|(a, b)| *a -= p * b);
        }
    }
    chosen
}

/// Output-only analysis of many channels: [`super::analyze`] of the references, each mode's
/// shape (and its magnitudes' intervals) carried to every channel. The singular values and the
/// cross-spectral matrix in the result are the references'.
pub fn analyze(channels: &[Vec<f64>], s: &OmaSettings) -> anyhow::Result<OmaResult> {
    let refs = references(channels, REFERENCES);
    let chosen: Vec<Vec<f64>> = refs.iter().map(|&i| channels[i].clone()).collect();
    let mut r = super::analyze(&chosen, s)?;
    r.plscf_references = r.plscf_references.iter().map(|&i| refs[i]).collect();
    let lines: Vec<usize> = r
        .modes
        .iter()
        .map(|m| (m.f_hz * s.csd.nfft as f64 / s.fs_hz).round() as usize)
        .collect();
    let parts = cross_spectra(channels, &refs, s.csd, &lines)?;
    for (m, part) in r.modes.iter_mut().zip(parts) {
        let at_refs: Vec<Complex64> = m.shape.clone();
        let Some(whole) = shape_of(&part.whole, &refs, &at_refs) else {
            continue;
        };
        let norm = largest(&whole);
        let shape: Vec<Complex64> = whole.iter().map(|v| v / norm).collect();
        let replicates: Vec<Vec<Complex64>> = part
            .left_out
            .iter()
            .filter_map(|g| shape_of(g, &refs, &at_refs))
            .collect();
        m.uncertainty.shape_abs = (replicates.len() >= 2).then(|| {
            (0..shape.len())
                .map(|j| {
                    let v: Vec<f64> = replicates.iter().map(|s| (s[j] / norm).norm()).collect();
                    jackknife(shape[j].norm(), &v).map_or(f64::NAN, |i| i.u)
                })
                .collect()
        });
        m.shape = shape;
    }
    let names: Vec<String> = refs.iter().map(|i| (i + 1).to_string()).collect();
    r.notes.push(format!(
        "{} channels: the modes were identified on {} reference channels (records {}, chosen \
         to span the motion: the channel of most variance, then of most variance left), and \
         each shape carried to every channel by the cross-spectra with the references at the \
         mode's line; the singular values shown are the references'",
        channels.len(),
        refs.len(),
        names.join(", ")
    ));
    Ok(r)
}

/// The component of largest modulus (the shape's scale; never zero for a shape found).
fn largest(v: &[Complex64]) -> Complex64 {
    v.iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .filter(|c| c.norm() > 0.0)
        .unwrap_or(Complex64::new(1.0, 0.0))
}

/// A mode's `K x R` cross-spectra at its line: of all segments, and of all but each group.
struct Part {
    whole: DMatrix<Complex64>,
    left_out: Vec<DMatrix<Complex64>>,
}

/// Per line of `lines`, the sums `X_k conj(X_r)` over the segments of all channels against the
/// references (unscaled: the shapes need only their direction).
fn cross_spectra(
    channels: &[Vec<f64>],
    refs: &[usize],
    c: CsdConfig,
    lines: &[usize],
) -> anyhow::Result<Vec<Part>> {
    let segments = csd::check(channels, c)?;
    let (k, r) = (channels.len(), refs.len());
    let groups = GROUPS.min(segments);
    let step = c.nperseg - c.noverlap;
    let w: Vec<f64> = (0..c.nperseg)
        .map(|i| f64::from(c.window.value(i, c.nperseg)))
        .collect();
    let mut planner = vibcam_fft::RealPlanner::new();
    let fft = planner.forward(c.nfft);
    let mut input = fft.make_input_vec();
    let mut out = fft.make_output_vec();
    let zero = || DMatrix::<Complex64>::zeros(k, r);
    // per group, per line
    let mut sums: Vec<Vec<DMatrix<Complex64>>> = (0..groups)
        .map(|_| lines.iter().map(|_| zero()).collect())
        .collect();
    let mut x = vec![vec![Complex64::new(0.0, 0.0); lines.len()]; k];
    for (g, sum) in sums.iter_mut().enumerate() {
        for s in group(g, groups, segments) {
            let start = s * step;
            for (ch, xs) in channels.iter().zip(x.iter_mut()) {
                let seg = &ch[start..start + c.nperseg];
                csd::segment_spectrum(seg, (&w, c.detrend), &fft, &mut input, &mut out)?;
                for (v, &l) in xs.iter_mut().zip(lines) {
                    *v = out.get(l).copied().unwrap_or_default();
                }
            }
            for (li, m) in sum.iter_mut().enumerate() {
                for (ri, &rc) in refs.iter().enumerate() {
                    let xr = x[rc][li].conj();
                    for (kc, xs) in x.iter().enumerate() {
                        m[(kc, ri)] += xs[li] * xr;
                    }
                }
            }
        }
    }
    Ok((0..lines.len())
        .map(|li| {
            let mut whole = zero();
            for g in &sums {
                whole += &g[li];
            }
            let left_out = match groups >= 2 {
                true => sums.iter().map(|g| &whole - &g[li]).collect(),
                false => Vec::new(),
            };
            Part { whole, left_out }
        })
        .collect())
}

/// The first left singular vector of `g` (`K x R`), turned to the phase of `at_refs` (the
/// mode's shape at the references) and scaled to it there; `None` for a matrix without motion.
fn shape_of(
    g: &DMatrix<Complex64>,
    refs: &[usize],
    at_refs: &[Complex64],
) -> Option<Vec<Complex64>> {
    let a = g.adjoint() * g;
    let eig = nalgebra::SymmetricEigen::try_new(a, 1e-14, super::MAX_ITERATIONS)?;
    let top = eig
        .eigenvalues
        .iter()
        .enumerate()
        .max_by(|x, y| x.1.total_cmp(y.1))?
        .0;
    let v = eig.eigenvectors.column(top).into_owned();
    let u = g * v;
    // least squares: u at the references times c is nearest the mode's shape there
    let (mut num, mut den) = (Complex64::new(0.0, 0.0), 0.0);
    for (&i, &p) in refs.iter().zip(at_refs) {
        num += u[i].conj() * p;
        den += u[i].norm_sqr();
    }
    if den <= 0.0 || !den.is_finite() || !num.norm().is_finite() {
        return None;
    }
    let c = num / den;
    Some(u.iter().map(|v| v * c).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_span_the_shared_motion_first() {
        // channels 0..6: two sines mixed; channel 3 carries only the second, the loudest is 5
        let n = 400;
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).sin()).collect();
        let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.71).cos()).collect();
        let mix =
            |p: f64, q: f64| -> Vec<f64> { a.iter().zip(&b).map(|(x, y)| p * x + q * y).collect() };
        let ch = vec![
            mix(1.0, 0.0),
            mix(1.0, 0.1),
            mix(0.9, 0.0),
            mix(0.0, 0.5),
            mix(1.1, 0.05),
            mix(3.0, 0.0),
        ];
        let r = references(&ch, 2);
        assert_eq!(r[0], 5);
        // what is left after channel 5 is the second sine: channel 3 carries the most of it
        assert_eq!(r[1], 3);
    }

    #[test]
    fn a_shape_is_carried_to_every_channel() {
        // one mode at 5 Hz, its shape a sine over 60 channels, plus a second mode at 12 Hz
        let (fs, n, k) = (64.0, 4096, 60);
        let t: Vec<f64> = (0..n).map(|i| i as f64 / fs).collect();
        let phi = |j: usize| (std::f64::consts::PI * (j as f64 + 0.5) / k as f64).sin();
        let psi = |j: usize| (2.0 * std::f64::consts::PI * (j as f64 + 0.5) / k as f64).sin();
        let ch: Vec<Vec<f64>> = (0..k)
            .map(|j| {
                t.iter()
                    .enumerate()
                    .map(|(i, t)| {
                        let noise = ((i * 7919 + j * 104_729) % 1000) as f64 / 1000.0 - 0.5;
                        phi(j) * (2.0 * std::f64::consts::PI * 5.0 * t).sin()
                            + 0.5 * psi(j) * (2.0 * std::f64::consts::PI * 12.0 * t + 0.3).sin()
                            + 0.01 * noise
                    })
                    .collect()
            })
            .collect();
        let refs = references(&ch, 4);
        let c = CsdConfig {
            window: firmware_core::spectrum::Window::Hann,
            nperseg: 256,
            noverlap: 128,
            nfft: 256,
            detrend: firmware_core::spectrum::Detrend::Constant,
        };
        let parts = cross_spectra(&ch, &refs, c, &[20, 48]).unwrap();
        for (part, truth) in parts.iter().zip([&phi as &dyn Fn(usize) -> f64, &psi]) {
            let at_refs: Vec<Complex64> = refs
                .iter()
                .map(|&i| Complex64::new(truth(i), 0.0))
                .collect();
            let s = shape_of(&part.whole, &refs, &at_refs).unwrap();
            for (j, v) in s.iter().enumerate() {
                assert!(
                    (v - Complex64::new(truth(j), 0.0)).norm() < 0.01,
                    "{j}: {v}"
                );
            }
            assert_eq!(part.left_out.len(), GROUPS);
        }
    }
}

//! Several forces at once (docs/method.md §3.13, "Several forces"): a continuous test driven by
//! two shakers or more, their forces recorded beside the responses. Per line, the forces'
//! cross-spectral matrix `Gff = sum F F^H` (inputs x inputs) and the responses' cross-spectra
//! with them `Gxf = sum X F^H` (responses x inputs), summed over Hann segments in groups as for
//! one force ([`super::spectra`]); the FRF matrix is the multiple-input H1,
//!
//! ```text
//! H = Gxf Gff^-1,
//! ```
//!
//! exact when the responses' noise is uncorrelated with the forces, and defined where `Gff` is
//! not singular: the forces must not be fully correlated (two shakers fed one signal are one
//! input). A line's conditioning, the ratio of `Gff`'s least to largest singular value, says
//! how well they are separated; a note names a band where the median falls below 0.01. Each
//! response's multiple coherence `gamma_o^2 = (H Gff H^H)_oo / Gxx_o` is its share explained by
//! all forces together (given for each of its FRFs). The FRFs (input-major, [`super::Layout`])
//! are then fitted as a roving hammer's are ([`super::roving`]): one LSCF, LSFD residues per
//! FRF, each mode's residue matrix reduced to its dominant singular vector.

use super::spectra::Frfs;
use super::{identify, EmaResult, EmaSettings, Excitation, Formed, Layout};
use crate::oma::uncertainty::{group, GROUPS};
use nalgebra::DMatrix;
use num_complex::Complex64;
use vibcam_readers::bad_input;

/// One group's sums, per line.
#[derive(Debug, Clone, PartialEq)]
struct Unit {
    /// `Gff` per line, `ff[line][i * inputs + k] = sum F_i conj(F_k)`.
    ff: Vec<Vec<Complex64>>,
    /// `Gxf` per line, `xf[line][o * inputs + i] = sum X_o conj(F_i)`.
    xf: Vec<Vec<Complex64>>,
    /// `Gxx` per line and response.
    xx: Vec<Vec<f64>>,
    /// Segments it holds.
    size: usize,
}

/// The spectra of a test with several forces, kept per group of segments.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectra {
    /// Line frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Forces.
    pub inputs: usize,
    /// Responses.
    pub outputs: usize,
    units: Vec<Unit>,
}

impl Spectra {
    /// Hann segments of `nperseg` overlapping by half, each segment's mean removed, in `groups`
    /// contiguous groups; lines up to `f_top_hz`.
    pub fn of_segments(
        forces: &[Vec<f64>],
        responses: &[Vec<f64>],
        fs_hz: f64,
        nperseg: usize,
        (groups, f_top_hz): (usize, f64),
    ) -> anyhow::Result<Spectra> {
        let (n, step) = (nperseg, nperseg / 2);
        let len = forces.first().map_or(0, Vec::len);
        if len < n || n < 8 {
            anyhow::bail!("{len} samples: fewer than one segment of {n}");
        }
        let segments = (len - n) / step + 1;
        let groups = groups.min(segments).max(1);
        let lines = ((f_top_hz * n as f64 / fs_hz).ceil() as usize + 1).min(n / 2 + 1);
        let fft = vibcam_fft::RealPlanner::new().forward(n);
        let hann: Vec<f64> = (0..n)
            .map(|k| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / n as f64).cos())
            .collect();
        let transform = |x: &[f64]| -> anyhow::Result<Vec<Complex64>> {
            let mean = x.iter().sum::<f64>() / x.len() as f64;
            let mut input: Vec<f64> = x.iter().zip(&hann).map(|(v, w)| (v - mean) * w).collect();
            let mut out = fft.make_output_vec();
            fft.process(&mut input, &mut out)
                .map_err(|e| anyhow::anyhow!("transform of {n} samples: {e}"))?;
            Ok(out)
        };
        let (ni, no) = (forces.len(), responses.len());
        let mut units = Vec::new();
        for g in 0..groups {
            let mut u = Unit {
                ff: vec![vec![Complex64::new(0.0, 0.0); ni * ni]; lines],
                xf: vec![vec![Complex64::new(0.0, 0.0); no * ni]; lines],
                xx: vec![vec![0.0; no]; lines],
                size: 0,
            };
            for seg in group(g, groups, segments) {
                let s = seg * step;
                let f: Vec<Vec<Complex64>> = forces
                    .iter()
                    .map(|x| transform(&x[s..s + n]))
                    .collect::<anyhow::Result<_>>()?;
                let x: Vec<Vec<Complex64>> = responses
                    .iter()
                    .map(|x| transform(&x[s..s + n]))
                    .collect::<anyhow::Result<_>>()?;
                for k in 0..lines {
                    for i in 0..ni {
                        for j in 0..ni {
                            u.ff[k][i * ni + j] += f[i][k] * f[j][k].conj();
                        }
                        for (o, xo) in x.iter().enumerate() {
                            u.xf[k][o * ni + i] += xo[k] * f[i][k].conj();
                        }
                    }
                    for (acc, xo) in u.xx[k].iter_mut().zip(&x) {
                        *acc += xo[k].norm_sqr();
                    }
                }
                u.size += 1;
            }
            units.push(u);
        }
        Ok(Spectra {
            freq_hz: (0..lines).map(|k| k as f64 * fs_hz / n as f64).collect(),
            inputs: ni,
            outputs: no,
            units,
        })
    }

    /// The summed matrices of line `k` over every group but those of `left_out`.
    fn sums(
        &self,
        k: usize,
        left_out: &std::ops::Range<usize>,
    ) -> (DMatrix<Complex64>, DMatrix<Complex64>, Vec<f64>) {
        let (ni, no) = (self.inputs, self.outputs);
        let mut gff = DMatrix::zeros(ni, ni);
        let mut gxf = DMatrix::zeros(no, ni);
        let mut gxx = vec![0.0; no];
        for (g, u) in self.units.iter().enumerate() {
            if left_out.contains(&g) {
                continue;
            }
            gff += DMatrix::from_row_slice(ni, ni, &u.ff[k]);
            gxf += DMatrix::from_row_slice(no, ni, &u.xf[k]);
            for (a, b) in gxx.iter_mut().zip(&u.xx[k]) {
                *a += b;
            }
        }
        (gff, gxf, gxx)
    }

    /// The FRF matrix of every group but `left_out` (input-major, [`Layout`]), each response's
    /// multiple coherence for each of its FRFs; no H2 (it is one force's).
    pub fn frfs_without(&self, left_out: std::ops::Range<usize>) -> Frfs {
        let (ni, no) = (self.inputs, self.outputs);
        let lines = self.freq_hz.len();
        let zero = Complex64::new(0.0, 0.0);
        let mut h1 = vec![vec![zero; lines]; ni * no];
        let mut coherence = vec![vec![0.0; lines]; ni * no];
        for k in 0..lines {
            let (gff, gxf, gxx) = self.sums(k, &left_out);
            let Some(inv) = gff.try_inverse() else {
                continue;
            };
            let h = &gxf * inv;
            for o in 0..no {
                // (H Gff H^H)_oo = h_o gxf_o^H
                let explained: Complex64 = (0..ni).map(|i| h[(o, i)] * gxf[(o, i)].conj()).sum();
                let c = if gxx[o] > 0.0 {
                    (explained.re / gxx[o]).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                for i in 0..ni {
                    h1[i * no + o][k] = h[(o, i)];
                    coherence[i * no + o][k] = c;
                }
            }
        }
        Frfs {
            h1,
            h2: Vec::new(),
            coherence,
        }
    }

    /// Per line, the ratio of `Gff`'s least to largest singular value (1: forces uncorrelated
    /// and equally strong; 0: one force a multiple of the others).
    pub fn conditioning(&self) -> Vec<f64> {
        (0..self.freq_hz.len())
            .map(|k| {
                let s = self.sums(k, &(0..0)).0.singular_values();
                let max = s.max();
                if max > 0.0 {
                    s.min() / max
                } else {
                    0.0
                }
            })
            .collect()
    }
}

/// The analysis of a continuous test with several `forces` (module documentation): `forces`
/// and `responses` at one rate `fs_hz`.
pub fn analyse(
    forces: &[Vec<f64>],
    responses: &[Vec<f64>],
    fs_hz: f64,
    s: &EmaSettings,
) -> anyhow::Result<EmaResult> {
    let Excitation::Continuous { nperseg } = s.excitation else {
        return Err(bad_input(
            "several forces at once are a continuous test (shakers); a roving hammer's hits, \
             one point at a time, are $roving",
        ));
    };
    let sp = Spectra::of_segments(
        forces,
        responses,
        fs_hz,
        nperseg,
        (GROUPS, s.band_hz.1 * 1.05),
    )?;
    let all = sp.frfs_without(0..0);
    let mut notes = Vec::new();
    let band_hz = match s.band_from_data {
        (false, false) => s.band_hz,
        free => {
            let segments = sp.units.iter().map(|u| u.size).sum();
            super::coherent_band((segments, &sp.freq_hz, &all), s.band_hz, free, &mut notes)
        }
    };
    let cond = sp.conditioning();
    let mut in_band: Vec<f64> = sp
        .freq_hz
        .iter()
        .zip(&cond)
        .filter(|(f, _)| **f >= band_hz.0 && **f <= band_hz.1)
        .map(|(_, c)| *c)
        .collect();
    in_band.sort_by(f64::total_cmp);
    if let Some(&median) = in_band.get(in_band.len() / 2).filter(|&&m| m < 1e-9) {
        return Err(bad_input(format!(
            "the forces are one signal: their cross-spectral matrix is singular in the band \
             (median conditioning {median:.1e}): shakers fed one signal are one input; give \
             one force ($excitation_col)"
        )));
    }
    if let Some(&median) = in_band.get(in_band.len() / 2) {
        notes.push(format!(
            "{} forces: the median conditioning of their cross-spectral matrix in the band is \
             {median:.3} (1: uncorrelated and equally strong){}",
            sp.inputs,
            if median < 0.01 {
                "; below 0.01 the forces are nearly one (correlated drives): their FRFs are \
                 poorly separated and doubtful"
            } else {
                ""
            }
        ));
    }
    let formed = Formed {
        freq: sp.freq_hz.clone(),
        frfs: all,
        layout: Layout {
            outputs: responses.len(),
            inputs: forces.len(),
        },
        points: &[],
        exp: None,
        band_hz,
        unit_sizes: sp.units.iter().map(|u| u.size).collect(),
        unit: "segment group",
        without: &|g| sp.frfs_without(g..g + 1).h1,
    };
    identify(formed, s, notes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::modal::{mac, FrfForm};
    use crate::oma::cluster::ClusterRule;
    use crate::oma::lscf::LscfRule;
    use rand::SeedableRng as _;
    use rand_distr::{Distribution as _, Normal};
    use vibcam_model::hammer::HammerTest;

    /// White forces, one per drive, the second `b` times the first plus `1 - b` of its own.
    fn forces(drives: usize, n: usize, b: f64) -> Vec<Vec<f64>> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let unit = Normal::new(0.0, 1.0).unwrap();
        let mut f: Vec<Vec<f64>> = (0..drives)
            .map(|_| (0..n).map(|_| unit.sample(&mut rng)).collect())
            .collect();
        let first = f[0].clone();
        for (v, a) in f[1].iter_mut().zip(&first) {
            *v = b * a + (1.0 - b) * *v;
        }
        f
    }

    /// `forces` at points `drives` (0-based), the five points' exact periodic displacements
    /// through the receptances, 0.1 % noise.
    fn record(forces: Vec<Vec<f64>>, drives: &[usize], fs: f64) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let n = forces[0].len();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        let unit = Normal::new(0.0, 1.0).unwrap();
        let mut planner = vibcam_fft::RealPlanner::new();
        let (fwd, inv) = (planner.forward(n), planner.inverse(n));
        let spectra: Vec<Vec<Complex64>> = forces
            .iter()
            .map(|f| {
                let mut x = f.clone();
                let mut out = fwd.make_output_vec();
                fwd.process(&mut x, &mut out).unwrap();
                out
            })
            .collect();
        let responses = (0..5)
            .map(|o| {
                let mut x: Vec<Complex64> = (0..n / 2 + 1)
                    .map(|k| {
                        let f = k as f64 * fs / n as f64;
                        drives
                            .iter()
                            .zip(&spectra)
                            .map(|(&d, sp)| {
                                let test = HammerTest {
                                    drive: d,
                                    ..HammerTest::three_modes(Vec::new())
                                };
                                sp[k] * test.receptance(o, f) * 1e3 / n as f64
                            })
                            .sum()
                    })
                    .collect();
                x[0].im = 0.0;
                x[n / 2].im = 0.0;
                let mut out = inv.make_output_vec();
                inv.process(&mut x, &mut out).unwrap();
                let rms = (out.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
                out.iter()
                    .map(|v| v + 1e-3 * rms * unit.sample(&mut rng))
                    .collect()
            })
            .collect();
        (forces, responses)
    }

    fn settings(nperseg: usize) -> EmaSettings {
        EmaSettings {
            excitation: Excitation::Continuous { nperseg },
            form: FrfForm::Receptance,
            band_hz: (5.0, 200.0),
            band_from_data: (false, false),
            bands: None,
            lscf: LscfRule::default(),
            cluster: ClusterRule::default(),
            poles: None,
        }
    }

    #[test]
    fn two_shakers_give_the_modes_the_frf_matrix_and_the_shapes() {
        let (fs, n) = (1000.0, 1 << 17);
        let (forces, responses) = record(forces(2, n, 0.0), &[1, 3], fs);
        let r = analyse(&forces, &responses, fs, &settings(16_384)).unwrap();
        assert_eq!(
            r.layout,
            Layout {
                outputs: 5,
                inputs: 2
            }
        );
        assert_eq!(r.frfs.h1.len(), 10);
        let truth = HammerTest::three_modes(Vec::new());
        // the FRF matrix against the closed form at the modes' peaks: response 5 over the
        // force at point 4 (FRF 1 * 5 + 4)
        let at_point_4 = HammerTest {
            drive: 3,
            ..HammerTest::three_modes(Vec::new())
        };
        for m in &truth.modes {
            let k = (m.f_hz * 16_384.0 / fs).round() as usize;
            let (got, want) = (
                r.frfs.h1[9][k],
                at_point_4.receptance(4, r.freq_hz[k]) * 1e3,
            );
            assert!(
                (got - want).norm() < 0.05 * want.norm(),
                "{got} vs {want} at {} Hz",
                r.freq_hz[k]
            );
            // a Hann segment's leakage at a peak costs about 1 % of coherence here
            assert!(
                r.frfs.coherence[9][k] > 0.98,
                "coherence {}",
                r.frfs.coherence[9][k]
            );
        }
        assert_eq!(r.modes.len(), 3, "{:?}", r.notes);
        for (m, t) in r.modes.iter().zip(&truth.modes) {
            assert!(
                (m.pole.f_hz - t.f_hz).abs() < 1e-3 * t.f_hz,
                "{} vs {}",
                m.pole.f_hz,
                t.f_hz
            );
            assert!((m.pole.damping - t.damping).abs() < 0.05 * t.damping);
            let shape: Vec<Complex64> = t.shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
            assert!(mac(&m.shape, &shape) > 0.999, "mode {}", m.mode);
        }
        super::super::assert_noted(&r.notes, "2 forces: the median conditioning");
    }

    #[test]
    fn forces_nearly_one_are_named_one_signal_and_an_impact_refused() {
        let (fs, n) = (1000.0, 1 << 15);
        // the second shaker's drive 98 % the first's
        let (f, x) = record(forces(2, n, 0.98), &[1, 3], fs);
        let r = analyse(&f, &x, fs, &settings(4096)).unwrap();
        super::super::assert_noted(&r.notes, "the forces are nearly one");
        let (f, x) = record(forces(2, n, 1.0), &[1, 3], fs);
        let e = analyse(&f, &x, fs, &settings(4096))
            .unwrap_err()
            .to_string();
        assert!(e.contains("the forces are one signal"), "{e}");
        let mut s = settings(4096);
        s.excitation = Excitation::Impact {
            rule: super::super::impact::ImpactRule::default(),
            exp: super::super::ExpChoice::Off,
        };
        let e = analyse(&f, &x, fs, &s).unwrap_err().to_string();
        assert!(
            e.contains("several forces at once are a continuous test"),
            "{e}"
        );
    }
}

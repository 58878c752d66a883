//! The auto- and cross-spectra of force and responses, kept per unit of averaging (a hit of an
//! impact test, or a group of Welch segments of a continuous one), so that the FRFs can be formed
//! from all units or from all but one (the jackknife of docs/method.md §3.13):
//! `H1 = sum conj(F) X / sum |F|^2`, `H2 = sum |X|^2 / sum conj(X) F`,
//! `coherence = |sum conj(F) X|^2 / (sum |F|^2 sum |X|^2)`.

use super::impact::{force_window, ExpWindow, Hits};
use num_complex::Complex64;

/// One unit's sums, per line.
#[derive(Debug, Clone, PartialEq)]
pub struct Unit {
    /// `sum |F|^2`.
    pub ff: Vec<f64>,
    /// Per response `sum conj(F) X`.
    pub fx: Vec<Vec<Complex64>>,
    /// Per response `sum |X|^2`.
    pub xx: Vec<Vec<f64>>,
    /// Blocks or segments it holds.
    pub size: usize,
}

/// The spectra of a test.
#[derive(Debug, Clone, PartialEq)]
pub struct Spectra {
    /// Line frequencies, Hz (from 0 to the highest kept).
    pub freq_hz: Vec<f64>,
    /// The units.
    pub units: Vec<Unit>,
}

/// FRFs formed from spectra.
#[derive(Debug, Clone, PartialEq)]
pub struct Frfs {
    /// Per response, H1 per line.
    pub h1: Vec<Vec<Complex64>>,
    /// Per response, H2 per line.
    pub h2: Vec<Vec<Complex64>>,
    /// Per response, the ordinary coherence per line.
    pub coherence: Vec<Vec<f64>>,
}

impl Frfs {
    /// `other`'s FRFs after these (the FRFs of several records, one after the other).
    pub fn extend(&mut self, other: Frfs) {
        self.h1.extend(other.h1);
        self.h2.extend(other.h2);
        self.coherence.extend(other.coherence);
    }
}

impl Spectra {
    /// The FRFs of every unit but `left_out`.
    pub fn frfs(&self, left_out: Option<usize>) -> Frfs {
        self.frfs_without(left_out.map_or(0..0, |g| g..g + 1))
    }

    /// The FRFs of every unit but those of `left_out` (a range of units; empty: all of them).
    pub fn frfs_without(&self, left_out: std::ops::Range<usize>) -> Frfs {
        let lines = self.freq_hz.len();
        let outs = self.units.first().map_or(0, |u| u.fx.len());
        let mut ff = vec![0.0; lines];
        let mut fx = vec![vec![Complex64::new(0.0, 0.0); lines]; outs];
        let mut xx = vec![vec![0.0; lines]; outs];
        for (i, u) in self.units.iter().enumerate() {
            if left_out.contains(&i) {
                continue;
            }
            for k in 0..lines {
                ff[k] += u.ff[k];
                for o in 0..outs {
                    fx[o][k] += u.fx[o][k];
                    xx[o][k] += u.xx[o][k];
                }
            }
        }
        let tiny = f64::MIN_POSITIVE;
        let h1 = fx
            .iter()
            .map(|f| f.iter().zip(&ff).map(|(c, a)| c / a.max(tiny)).collect())
            .collect();
        let h2 = fx
            .iter()
            .zip(&xx)
            .map(|(f, x)| {
                f.iter()
                    .zip(x)
                    .map(|(c, b)| {
                        if c.norm() > 0.0 {
                            Complex64::new(*b, 0.0) / c.conj()
                        } else {
                            Complex64::new(0.0, 0.0)
                        }
                    })
                    .collect()
            })
            .collect();
        let coherence = fx
            .iter()
            .zip(&xx)
            .map(|(f, x)| {
                (0..lines)
                    .map(|k| {
                        let den = ff[k] * x[k];
                        if den > 0.0 {
                            (f[k].norm_sqr() / den).min(1.0)
                        } else {
                            0.0
                        }
                    })
                    .collect()
            })
            .collect();
        Frfs { h1, h2, coherence }
    }
}

/// Transforms one block (or segment): force and responses already windowed; the sums of its
/// lines `0..lines` added to `unit`.
fn accumulate(
    fft: &std::sync::Arc<dyn vibcam_fft::RealToComplex<f64>>,
    force: &[f64],
    responses: &[Vec<f64>],
    lines: usize,
    unit: &mut Unit,
) -> anyhow::Result<()> {
    let n = force.len();
    let mut input = force.to_vec();
    let mut f = fft.make_output_vec();
    fft.process(&mut input, &mut f)
        .map_err(|e| anyhow::anyhow!("transform of {n} samples: {e}"))?;
    for (acc, v) in unit.ff.iter_mut().zip(&f) {
        *acc += v.norm_sqr();
    }
    for (o, x) in responses.iter().enumerate() {
        let mut input = x.clone();
        let mut xs = fft.make_output_vec();
        fft.process(&mut input, &mut xs)
            .map_err(|e| anyhow::anyhow!("transform of {n} samples: {e}"))?;
        for k in 0..lines {
            unit.fx[o][k] += f[k].conj() * xs[k];
            unit.xx[o][k] += xs[k].norm_sqr();
        }
    }
    unit.size += 1;
    Ok(())
}

fn empty_unit(lines: usize, outs: usize) -> Unit {
    Unit {
        ff: vec![0.0; lines],
        fx: vec![vec![Complex64::new(0.0, 0.0); lines]; outs],
        xx: vec![vec![0.0; lines]; outs],
        size: 0,
    }
}

/// The number of lines of a transform of `n` samples at `fs_hz` up to `f_top_hz`.
fn lines_to(n: usize, fs_hz: f64, f_top_hz: f64) -> usize {
    ((f_top_hz * n as f64 / fs_hz).floor() as usize + 1).min(n / 2 + 1)
}

/// The spectra of an impact test: one unit per used hit, its block's force windowed
/// ([`force_window`]), each response less its mean before the pulse, both multiplied by `exp`
/// when given; lines up to `f_top_hz`.
pub fn of_hits(
    force: &[f64],
    responses: &[Vec<f64>],
    fs_hz: f64,
    hits: &Hits,
    exp: Option<ExpWindow>,
    f_top_hz: f64,
) -> anyhow::Result<Spectra> {
    let n = hits.block;
    let lines = lines_to(n, fs_hz, f_top_hz);
    let fft = vibcam_fft::RealPlanner::new().forward(n);
    let window: Vec<f64> = (0..n)
        .map(|k| exp.map_or(1.0, |w| w.at(k as f64 / fs_hz)))
        .collect();
    let mut units = Vec::new();
    for hit in hits.used() {
        let s = hits.block_start(hit);
        let p = hit.pulse();
        let mut f = force_window(&force[s..s + n], hits.baseline, (p.start - s, p.end - s));
        for (v, w) in f.iter_mut().zip(&window) {
            *v *= w;
        }
        let xs: Vec<Vec<f64>> = responses
            .iter()
            .map(|x| {
                let block = &x[s..s + n];
                let pre = hits.pre.max(1);
                let mean = block[..pre].iter().sum::<f64>() / pre as f64;
                block
                    .iter()
                    .zip(&window)
                    .map(|(v, w)| (v - mean) * w)
                    .collect()
            })
            .collect();
        let mut unit = empty_unit(lines, responses.len());
        accumulate(&fft, &f, &xs, lines, &mut unit)?;
        units.push(unit);
    }
    Ok(Spectra {
        freq_hz: (0..lines).map(|k| k as f64 * fs_hz / n as f64).collect(),
        units,
    })
}

/// The spectra of a continuous test (a shaker, random force): Hann segments of `nperseg`
/// samples overlapping by half, each segment's mean removed, in `groups` contiguous groups of
/// segments (one unit each); lines up to `f_top_hz`.
pub fn of_segments(
    force: &[f64],
    responses: &[Vec<f64>],
    fs_hz: f64,
    nperseg: usize,
    groups: usize,
    f_top_hz: f64,
) -> anyhow::Result<Spectra> {
    let n = nperseg;
    let step = n / 2;
    if force.len() < n || n < 8 {
        anyhow::bail!("{} samples: fewer than one segment of {n}", force.len());
    }
    let segments = (force.len() - n) / step + 1;
    let groups = groups.min(segments).max(1);
    let lines = lines_to(n, fs_hz, f_top_hz);
    let fft = vibcam_fft::RealPlanner::new().forward(n);
    let hann: Vec<f64> = (0..n)
        .map(|k| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / n as f64).cos())
        .collect();
    let prepare = |x: &[f64]| -> Vec<f64> {
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        x.iter().zip(&hann).map(|(v, w)| (v - mean) * w).collect()
    };
    let mut units = Vec::new();
    for g in 0..groups {
        let mut unit = empty_unit(lines, responses.len());
        for seg in crate::oma::uncertainty::group(g, groups, segments) {
            let s = seg * step;
            let f = prepare(&force[s..s + n]);
            let xs: Vec<Vec<f64>> = responses.iter().map(|x| prepare(&x[s..s + n])).collect();
            accumulate(&fft, &f, &xs, lines, &mut unit)?;
        }
        units.push(unit);
    }
    Ok(Spectra {
        freq_hz: (0..lines).map(|k| k as f64 * fs_hz / n as f64).collect(),
        units,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frf_of_a_known_filter_with_noise_free_blocks() {
        // x = 2 f delayed by one sample: H = 2 exp(-i w / fs), coherence 1
        let fs = 1000.0;
        let n = 4096;
        let force = vibcam_common::testing::uniform_noise(3, n);
        let x: Vec<f64> = (0..n)
            .map(|k| if k > 0 { 2.0 * force[k - 1] } else { 0.0 })
            .collect();
        let s = of_segments(&force, &[x], fs, 512, 4, 400.0).unwrap();
        let h = s.frfs(None);
        for k in 5..200 {
            let w = 2.0 * std::f64::consts::PI * s.freq_hz[k] / fs;
            let want = Complex64::from_polar(2.0, -w);
            // the one-sample delay inside a Hann segment leaks a little: a loose check
            assert!(
                (h.h1[0][k] - want).norm() < 0.05,
                "line {k}: {} vs {want}",
                h.h1[0][k]
            );
            assert!(h.coherence[0][k] > 0.99);
        }
        assert_eq!(s.units.len(), 4);
        assert_eq!(s.units.iter().map(|u| u.size).sum::<usize>(), 15);
    }
}

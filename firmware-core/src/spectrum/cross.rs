//! [`CrossSpectra`]: the streaming Welch cross-spectral matrix of `K` channels (the targets of
//! a camera), its first singular value and vector per line, and peak picking: output-only
//! modal analysis (frequency domain decomposition) on the camera, allocation-free (the host's
//! version and the method: docs/method.md §3.12).
//!
//! Frames arrive one at a time ([`CrossSpectra::push`]: one sample per channel). Every
//! `SEG / 2` frames after the first `SEG` a segment of the last `SEG` samples per channel is
//! taken: its mean removed, a periodic Hann window, a transform of `SEG` points, and the upper
//! triangle of `conj(X_i) X_j` added per line (`LINES = SEG / 2 + 1`; `TRI = K (K + 1) / 2`
//! entries per line, checked by [`CrossSpectra::try_new`]). The first singular value and vector
//! of a line's Hermitian matrix come by power iteration ([`CrossSpectra::first_singular`]);
//! [`pick_peaks`] finds the peaks of the first singular value as the host does (prominence and
//! height over the median floor). Nothing here panics.
//!
//! RAM: `4 K SEG` (segment rings) `+ 8 K LINES` (spectra) `+ 8 TRI LINES` (the matrix) `+ 8 SEG`
//! (transform) `+ 8 SCRATCH` bytes: about 41 KiB for 4 targets and segments of 512, 112 KiB
//! for 8.

use crate::dft::{Dft, Direction};
use crate::spectrum::Window;
use crate::Complex32;

/// Why a [`CrossSpectra`] cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CrossError {
    /// `LINES` is not `SEG / 2 + 1`, `TRI` not `K (K + 1) / 2`, `K` is 0 or `SEG` below 8.
    Capacities,
    /// The transform of `SEG` points is not supported or needs more scratch than `SCRATCH`.
    Transform,
}

impl core::fmt::Display for CrossError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            CrossError::Capacities => write!(
                f,
                "capacities: LINES must be SEG / 2 + 1, TRI K (K + 1) / 2, K >= 1, SEG >= 8"
            ),
            CrossError::Transform => write!(f, "the segment's transform is not supported"),
        }
    }
}

/// The streaming cross-spectral matrix of `K` channels (see the module documentation).
#[derive(Clone)]
pub struct CrossSpectra<
    const K: usize,
    const SEG: usize,
    const LINES: usize,
    const TRI: usize,
    const SCRATCH: usize,
> {
    dft: Dft,
    fs_hz: f32,
    ring: [[f32; SEG]; K],
    /// Samples pushed so far (the ring's write position is `pushed % SEG`).
    pushed: usize,
    spectra: [[Complex32; LINES]; K],
    acc: [[Complex32; TRI]; LINES],
    work: [Complex32; SEG],
    scratch: [Complex32; SCRATCH],
    segments: u32,
    /// `sum w^2` of the window.
    w2: f32,
}

impl<
        const K: usize,
        const SEG: usize,
        const LINES: usize,
        const TRI: usize,
        const SCRATCH: usize,
    > core::fmt::Debug for CrossSpectra<K, SEG, LINES, TRI, SCRATCH>
{
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("CrossSpectra")
            .field("capacities", &(K, SEG, LINES, TRI, SCRATCH))
            .field("fs_hz", &self.fs_hz)
            .field("pushed", &self.pushed)
            .field("segments", &self.segments)
            .finish_non_exhaustive()
    }
}

/// Index of `(i, j)`, `i <= j < k`, in the upper triangle stored row by row.
const fn tri(i: usize, j: usize, k: usize) -> usize {
    i * k - i * (i + 1) / 2 + j
}

impl<
        const K: usize,
        const SEG: usize,
        const LINES: usize,
        const TRI: usize,
        const SCRATCH: usize,
    > CrossSpectra<K, SEG, LINES, TRI, SCRATCH>
{
    /// An empty estimate for frames at `fs_hz`; checks the capacities.
    pub fn try_new(fs_hz: f32) -> Result<Self, CrossError> {
        if K == 0 || SEG < 8 || LINES != SEG / 2 + 1 || TRI != K * (K + 1) / 2 {
            return Err(CrossError::Capacities);
        }
        let dft = Dft::try_new(SEG).map_err(|_| CrossError::Transform)?;
        if dft.scratch_len() > SCRATCH {
            return Err(CrossError::Transform);
        }
        let mut w2 = 0.0f32;
        for n in 0..SEG {
            let w = Window::Hann.value(n, SEG);
            w2 += w * w;
        }
        Ok(CrossSpectra {
            dft,
            fs_hz,
            ring: [[0.0; SEG]; K],
            pushed: 0,
            spectra: [[Complex32::new(0.0, 0.0); LINES]; K],
            acc: [[Complex32::new(0.0, 0.0); TRI]; LINES],
            work: [Complex32::new(0.0, 0.0); SEG],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
            segments: 0,
            w2,
        })
    }

    /// Segments averaged so far.
    pub fn segments(&self) -> u32 {
        self.segments
    }

    /// Frequency of line `l`, Hz.
    pub fn freq(&self, l: usize) -> f32 {
        l as f32 * self.fs_hz / SEG as f32
    }

    /// Pushes one frame: a sample per channel. A non-finite sample is taken as 0 (the
    /// caller's lost frames should be filled before). When a segment completes it is added.
    pub fn push(&mut self, frame: &[f32; K]) {
        let at = self.pushed % SEG;
        for (ring, &v) in self.ring.iter_mut().zip(frame) {
            if let Some(slot) = ring.get_mut(at) {
                *slot = if v.is_finite() { v } else { 0.0 };
            }
        }
        self.pushed = self.pushed.wrapping_add(1);
        if self.pushed >= SEG && (self.pushed - SEG) % (SEG / 2) == 0 {
            self.add_segment();
        }
    }

    /// The last `SEG` samples of every channel, transformed and accumulated.
    fn add_segment(&mut self) {
        // the oldest sample of the ring is at the write position
        let start = self.pushed % SEG;
        for (ring, spectrum) in self.ring.iter().zip(self.spectra.iter_mut()) {
            let mean = ring.iter().sum::<f32>() / SEG as f32;
            for (n, w) in self.work.iter_mut().enumerate() {
                let v = ring.get((start + n) % SEG).copied().unwrap_or(0.0);
                *w = Complex32::new((v - mean) * Window::Hann.value_f32(n, SEG), 0.0);
            }
            if self
                .dft
                .process(&mut self.work, &mut self.scratch, Direction::Forward)
                .is_err()
            {
                return;
            }
            for (s, w) in spectrum.iter_mut().zip(self.work.iter()) {
                *s = *w;
            }
        }
        for (l, acc) in self.acc.iter_mut().enumerate() {
            for i in 0..K {
                let xi = self
                    .spectra
                    .get(i)
                    .and_then(|s| s.get(l))
                    .copied()
                    .unwrap_or_default()
                    .conj();
                for j in i..K {
                    let xj = self
                        .spectra
                        .get(j)
                        .and_then(|s| s.get(l))
                        .copied()
                        .unwrap_or_default();
                    if let Some(a) = acc.get_mut(tri(i, j, K)) {
                        *a += xi * xj;
                    }
                }
            }
        }
        self.segments += 1;
    }

    /// `G_ij` of line `l` (density, one-sided, as the host's and scipy's `csd`); 0 before the
    /// first segment or out of range.
    pub fn get(&self, l: usize, i: usize, j: usize) -> Complex32 {
        if self.segments == 0 || i >= K || j >= K {
            return Complex32::new(0.0, 0.0);
        }
        let (a, b, conj) = if i <= j { (i, j, false) } else { (j, i, true) };
        let Some(v) = self.acc.get(l).and_then(|r| r.get(tri(a, b, K))).copied() else {
            return Complex32::new(0.0, 0.0);
        };
        let one_sided = if l == 0 || (SEG % 2 == 0 && l == LINES - 1) {
            1.0
        } else {
            2.0
        };
        let v = v * (one_sided / (self.fs_hz * self.w2 * self.segments as f32));
        if conj {
            v.conj()
        } else {
            v
        }
    }

    /// The first singular value of line `l` and its unit vector (power iteration from a
    /// vector of ones, up to `iterations`, stopping when the value changes by less than 1e-6
    /// relative); `(0, zeros)` for an empty line.
    pub fn first_singular(&self, l: usize, iterations: u32) -> (f32, [Complex32; K]) {
        let mut v = [Complex32::new(1.0, 0.0); K];
        let mut value = 0.0f32;
        for _ in 0..iterations.max(1) {
            let mut w = [Complex32::new(0.0, 0.0); K];
            for (i, wi) in w.iter_mut().enumerate() {
                for (j, vj) in v.iter().enumerate() {
                    *wi += self.get(l, i, j) * vj;
                }
            }
            let norm = libm::sqrtf(w.iter().map(|c| c.norm_sqr()).sum::<f32>());
            if !(norm.is_finite() && norm > 0.0) {
                return (0.0, [Complex32::new(0.0, 0.0); K]);
            }
            for (vi, wi) in v.iter_mut().zip(&w) {
                *vi = wi / norm;
            }
            let settled = libm::fabsf(norm - value) <= 1e-6 * norm;
            value = norm;
            if settled {
                break;
            }
        }
        (value, v)
    }
}

/// Peaks of a first-singular-value spectrum `s1` (one value per line) between lines `lo` and
/// `hi` (inclusive): local maxima with at least `prominence_db` of prominence (over the higher
/// of the lowest points between the peak and a higher one on either side) and `floor_db` over
/// the median of the range (found with the help of `sorted`, at least as long as the range).
/// Writes the lines into `out`, returns how many (at most `out.len()`).
pub fn pick_peaks(
    s1: &[f32],
    (lo, hi): (usize, usize),
    (prominence_db, floor_db): (f32, f32),
    sorted: &mut [f32],
    out: &mut [usize],
) -> usize {
    let hi = hi.min(s1.len().saturating_sub(1));
    let (Some(range), true) = (s1.get(lo..=hi), lo <= hi) else {
        return 0;
    };
    let Some(sorted) = sorted.get_mut(..range.len()) else {
        return 0;
    };
    for (o, v) in sorted.iter_mut().zip(range) {
        *o = *v;
    }
    // insertion sort: no panic path (the library's sort has one for inconsistent orders)
    for i in 1..sorted.len() {
        let mut j = i;
        while j > 0 {
            let (Some(&a), Some(&b)) = (sorted.get(j - 1), sorted.get(j)) else {
                break;
            };
            if a.total_cmp(&b).is_le() {
                break;
            }
            sorted.swap(j - 1, j);
            j -= 1;
        }
    }
    let floor = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
    let db = |a: f32, b: f32| 10.0 * libm::log10f(a / b.max(f32::MIN_POSITIVE));
    let at = |i: usize| s1.get(i).copied().unwrap_or(f32::NEG_INFINITY);
    let mut n = 0;
    for l in lo..=hi {
        let v = at(l);
        let left = if l > lo { at(l - 1) } else { f32::NEG_INFINITY };
        let right = if l < hi { at(l + 1) } else { f32::NEG_INFINITY };
        if !(v > left && v >= right && v > 0.0) {
            continue;
        }
        // the lowest point on each side before a higher value (or the range's end)
        let mut lb = v;
        for i in (lo..l).rev() {
            if at(i) > v {
                break;
            }
            lb = lb.min(at(i));
        }
        let mut rb = v;
        for i in l + 1..=hi {
            if at(i) > v {
                break;
            }
            rb = rb.min(at(i));
        }
        if db(v, lb.max(rb)) >= prominence_db && db(v, floor) >= floor_db {
            if let Some(o) = out.get_mut(n) {
                *o = l;
                n += 1;
            }
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capacities_are_checked() {
        assert_eq!(
            CrossSpectra::<2, 16, 9, 3, 0>::try_new(10.0).map(|_| ()),
            Ok(())
        );
        for bad in [
            CrossSpectra::<2, 16, 8, 3, 0>::try_new(10.0).map(|_| ()),
            CrossSpectra::<2, 16, 9, 4, 0>::try_new(10.0).map(|_| ()),
        ] {
            assert_eq!(bad, Err(CrossError::Capacities));
        }
    }

    #[test]
    fn one_sinusoid_puts_its_shape_in_the_first_vector_at_its_line() {
        // two channels in antiphase at line 4 of 32: G is rank one there, its vector (1, -2)
        let mut cs = CrossSpectra::<2, 32, 17, 3, 0>::try_new(32.0).unwrap();
        for i in 0..32 * 8 {
            let v = libm::sinf(2.0 * core::f32::consts::PI * 4.0 * i as f32 / 32.0);
            cs.push(&[v, -2.0 * v]);
        }
        assert_eq!(cs.segments(), 15);
        let (s, v) = cs.first_singular(4, 50);
        let ratio = v[1] / v[0];
        assert!(
            (ratio.re + 2.0).abs() < 1e-3 && ratio.im.abs() < 1e-3,
            "{ratio}"
        );
        // the trace is the first singular value (rank one), both PSDs positive
        let trace = cs.get(4, 0, 0).re + cs.get(4, 1, 1).re;
        assert!((s - trace).abs() < 1e-3 * trace, "{s} {trace}");
        // Hermitian
        assert_eq!(cs.get(4, 1, 0), cs.get(4, 0, 1).conj());
        let mut s1 = [0.0f32; 17];
        for (l, o) in s1.iter_mut().enumerate() {
            *o = cs.first_singular(l, 50).0;
        }
        let (mut sorted, mut out) = ([0.0f32; 17], [0usize; 4]);
        assert_eq!(
            pick_peaks(&s1, (1, 15), (6.0, 10.0), &mut sorted, &mut out),
            1
        );
        assert_eq!(out[0], 4);
    }
}

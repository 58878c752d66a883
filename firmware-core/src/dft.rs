//! Exact discrete Fourier transform of any length on top of power-of-two `microfft`.
//!
//! The measurement chain needs DFTs whose lengths are not powers of two: 1200 camera samples
//! (10 s at 120 fps), 20480 upsampled samples, `nfft = 5000` for 0.01 Hz bins at 50 Hz.
//! `microfft` only does powers of two up to [`MAX_POW2`], so a length `n` is split as
//! `n = p * m` with `p` the largest power of two dividing `n` (at most [`MAX_POW2`]) and `m`
//! the rest, and one Cooley-Tukey step combines
//!
//! * `p` DFTs of length `m` (direct O(m^2) sums when `m <=` [`NAIVE_MAX`], Bluestein's chirp-z
//!   algorithm with a power-of-two convolution otherwise),
//! * the twiddle factors `exp(-2 pi i n2 k1 / n)`,
//! * `m` `microfft` FFTs of length `p`.
//!
//! Everything runs in caller-provided buffers: the data (`n` values) and a scratch slice of
//! [`scratch_len`]`(n)` values (zero for powers of two). Nothing allocates, nothing panics.
//!
//! Conventions (same as numpy/scipy): forward `X[k] = sum_j x[j] exp(-2 pi i j k / n)`;
//! [`Direction::Inverse`] computes `sum_k X[k] exp(+2 pi i j k / n)` **without** the `1/n`
//! factor.
//!
//! ```
//! use firmware_core::dft::{scratch_len, Dft, Direction};
//! use firmware_core::Complex32;
//! // an exact 120-point DFT (not a power of two): a unit impulse has a flat spectrum
//! const N: usize = 120;
//! const SCRATCH: usize = match scratch_len(N) { Some(s) => s, None => 0 };
//! let plan = Dft::try_new(N).unwrap();
//! let mut x = [Complex32::new(0.0, 0.0); N];
//! x[0] = Complex32::new(1.0, 0.0);
//! let mut scratch = [Complex32::new(0.0, 0.0); SCRATCH];
//! plan.process(&mut x, &mut scratch, Direction::Forward).unwrap();
//! assert!(x.iter().all(|v| (v.re - 1.0).abs() < 1e-5 && v.im.abs() < 1e-5));
//! ```

use crate::{BufferError, Complex32};

/// Largest power-of-two transform `microfft` provides with the features this crate enables.
pub const MAX_POW2: usize = 32768;

/// Odd (non power-of-two) factors up to this length use direct O(m^2) sums; above it, Bluestein.
pub const NAIVE_MAX: usize = 128;

/// Largest supported transform length: powers of two up to [`MAX_POW2`], and any `p * m` whose
/// remaining factor `m` is either small or fits a Bluestein convolution of at most [`MAX_POW2`].
pub const MAX_LEN: usize = MAX_POW2 * NAIVE_MAX;

/// Transform direction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Direction {
    /// `X[k] = sum_j x[j] exp(-2 pi i j k / n)`.
    Forward,
    /// `x[j] = sum_k X[k] exp(+2 pi i j k / n)` (unnormalised: divide by `n` yourself).
    Inverse,
}

/// Why a transform cannot be planned (a configuration error; running a plan can only fail on
/// a caller buffer of the wrong length, [`BufferError`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum DftError {
    /// Length zero.
    Empty,
    /// The length's non-power-of-two factor is too large for a Bluestein convolution of
    /// [`MAX_POW2`] points.
    Unsupported {
        /// Requested length.
        len: usize,
    },
}

error_display!(DftError, f, {
    DftError::Empty => write!(f, "DFT length must be at least 1"),
    DftError::Unsupported { len } => write!(
        f,
        "DFT length {len} is not supported: its odd part needs a convolution longer than {MAX_POW2}"
    ),
});

/// How the length-`m` factor is transformed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Inner {
    /// `m == 1`: pure power of two.
    None,
    /// Direct sums.
    Naive,
    /// Bluestein with a power-of-two convolution of length `l`.
    Bluestein { l: usize },
}

/// A plan for an exact DFT of one length. Cheap to build (no tables), `Copy`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Dft {
    n: usize,
    p: usize,
    m: usize,
    inner: Inner,
}

#[cfg(feature = "defmt")]
impl defmt::Format for Inner {
    fn format(&self, f: defmt::Formatter<'_>) {
        match self {
            Inner::None => defmt::write!(f, "None"),
            Inner::Naive => defmt::write!(f, "Naive"),
            Inner::Bluestein { l } => defmt::write!(f, "Bluestein({})", l),
        }
    }
}

const fn split(n: usize) -> (usize, usize) {
    let mut p = 1;
    while n % (p * 2) == 0 && p * 2 <= MAX_POW2 {
        p *= 2;
    }
    (p, n / p)
}

const fn plan_inner(m: usize) -> Option<Inner> {
    if m == 1 {
        Some(Inner::None)
    } else if m <= NAIVE_MAX {
        Some(Inner::Naive)
    } else {
        // Bluestein needs a linear convolution of length 2m - 1 without wrap-around.
        let mut l = 1;
        while l < 2 * m - 1 {
            l *= 2;
            if l > MAX_POW2 {
                return None;
            }
        }
        Some(Inner::Bluestein { l })
    }
}

/// Scratch values (`Complex32`) that [`Dft::process`] needs for length `n`, or `None` if the
/// length is not supported. Usable in const context to size static buffers.
pub const fn scratch_len(n: usize) -> Option<usize> {
    if n == 0 {
        return None;
    }
    let (_, m) = split(n);
    match plan_inner(m) {
        None => None,
        Some(Inner::None) => Some(0),
        // reorder buffer + column in + column out
        Some(Inner::Naive) => Some(n + 2 * m),
        // reorder buffer + chirp filter spectrum + convolution buffer + chirp table
        Some(Inner::Bluestein { l }) => Some(n + 2 * l + m),
    }
}

impl Dft {
    /// The plan of no transform (length 0; `run` does nothing): the placeholder of an
    /// unconfigured state (all zero bytes, so a `static` holding it lands in `.bss`).
    pub(crate) const NONE: Dft = Dft {
        n: 0,
        p: 0,
        m: 0,
        inner: Inner::None,
    };

    /// Plans a transform of length `n`.
    pub const fn try_new(n: usize) -> Result<Self, DftError> {
        if n == 0 {
            return Err(DftError::Empty);
        }
        let (p, m) = split(n);
        match plan_inner(m) {
            Some(inner) => Ok(Dft { n, p, m, inner }),
            None => Err(DftError::Unsupported { len: n }),
        }
    }

    /// Transform length.
    pub const fn len(&self) -> usize {
        self.n
    }

    /// Always false (a plan has length at least 1); present for API symmetry with `len`.
    pub const fn is_empty(&self) -> bool {
        false
    }

    /// Scratch values [`process`](Self::process) needs.
    pub const fn scratch_len(&self) -> usize {
        match self.inner {
            Inner::None => 0,
            Inner::Naive => self.n + 2 * self.m,
            Inner::Bluestein { l } => self.n + 2 * l + self.m,
        }
    }

    /// Transforms `data` in place. `scratch` must hold at least [`scratch_len`](Self::scratch_len)
    /// values (its content is overwritten); `data` exactly [`len`](Self::len).
    pub fn process(
        &self,
        data: &mut [Complex32],
        scratch: &mut [Complex32],
        dir: Direction,
    ) -> Result<(), BufferError> {
        if data.len() != self.n {
            return Err(BufferError {
                expected: self.n,
                got: data.len(),
            });
        }
        if scratch.len() < self.scratch_len() {
            return Err(BufferError {
                expected: self.scratch_len(),
                got: scratch.len(),
            });
        }
        self.run(data, scratch, dir);
        Ok(())
    }

    /// [`process`](Self::process) for the crate's own callers, whose buffer lengths follow
    /// from a validated configuration: infallible (a wrong length, impossible there, leaves
    /// `data` untouched).
    pub(crate) fn run(&self, data: &mut [Complex32], scratch: &mut [Complex32], dir: Direction) {
        if self.n == 0 || data.len() != self.n || scratch.len() < self.scratch_len() {
            return;
        }
        // Inverse through the forward transform: IDFT(x) = conj(DFT(conj(x))).
        if dir == Direction::Inverse {
            conj_all(data);
        }
        self.forward(data, scratch);
        if dir == Direction::Inverse {
            conj_all(data);
        }
    }

    fn forward(&self, data: &mut [Complex32], scratch: &mut [Complex32]) {
        let (n, p, m) = (self.n, self.p, self.m);
        if m == 1 {
            fft_pow2(data);
            return;
        }
        // `process` checked the buffer lengths; the checked accessors below keep the compiler
        // from leaving panic paths in the image (see mcu-demo's panic-check build).
        let Some((reorder, work)) = scratch.split_at_mut_checked(n) else {
            return;
        };
        // Bluestein: the chirp (a table of m values, used twice per column) and the spectrum of
        // the chirp filter are the same for every column.
        if let Inner::Bluestein { l } = self.inner {
            let Some((filt, rest)) = work.split_at_mut_checked(l) else {
                return;
            };
            let Some(chirps) = rest.get_mut(l..l + m) else {
                return;
            };
            for (k, c) in chirps.iter_mut().enumerate() {
                *c = chirp(k, m);
            }
            chirp_filter(chirps, filt);
        }
        // Step 1+2: for each n2, DFT of the strided column x[p*n1 + n2] (n1 < m), then twiddle,
        // written back to the same strided positions (so data[p*k1 + n2] = A_n2[k1] W^(n2 k1)).
        for n2 in 0..p {
            match self.inner {
                Inner::Naive => {
                    let Some((col, rest)) = work.split_at_mut_checked(m) else {
                        return;
                    };
                    let Some(out) = rest.get_mut(..m) else {
                        return;
                    };
                    for (n1, c) in col.iter_mut().enumerate() {
                        *c = at(data, p * n1 + n2);
                    }
                    naive_dft(col, out);
                    for (k1, v) in out.iter().enumerate() {
                        put(data, p * k1 + n2, *v * twiddle(n2 * k1, n));
                    }
                }
                Inner::Bluestein { l } => {
                    let Some((filt, rest)) = work.split_at_mut_checked(l) else {
                        return;
                    };
                    let Some((conv, chirps)) = rest.split_at_mut_checked(l) else {
                        return;
                    };
                    for (n1, c) in conv.iter_mut().enumerate() {
                        *c = if n1 < m {
                            at(data, p * n1 + n2) * at(chirps, n1)
                        } else {
                            Complex32::new(0.0, 0.0)
                        };
                    }
                    fft_pow2(conv);
                    for (c, f) in conv.iter_mut().zip(filt.iter()) {
                        // multiply and conjugate in one go: the inverse FFT is done as
                        // conj(FFT(conj(.)))
                        *c = (*c * *f).conj();
                    }
                    fft_pow2(conv);
                    let scale = 1.0 / l as f32;
                    for (k1, c) in conv.iter().take(m).enumerate() {
                        let y = c.conj() * scale * at(chirps, k1);
                        put(data, p * k1 + n2, y * twiddle(n2 * k1, n));
                    }
                }
                Inner::None => {}
            }
        }
        // Step 3: p-point FFT over n2 for each k1: rows data[p*k1 .. p*k1 + p] are contiguous.
        for row in data.chunks_exact_mut(p.max(1)) {
            fft_pow2(row);
        }
        // Output order: data[p*k1 + k2] = X[k1 + m*k2].
        for (r, d) in reorder.iter_mut().zip(data.iter()) {
            *r = *d;
        }
        for k1 in 0..m {
            for k2 in 0..p {
                put(data, k1 + m * k2, at(reorder, p * k1 + k2));
            }
        }
    }
}

/// `s[i]`, or zero past the end (never happens for planned lengths; no panic path).
#[inline(always)]
fn at(s: &[Complex32], i: usize) -> Complex32 {
    s.get(i).copied().unwrap_or_default()
}

/// `s[i] = v`, ignored past the end (never happens for planned lengths; no panic path).
#[inline(always)]
fn put(s: &mut [Complex32], i: usize, v: Complex32) {
    if let Some(d) = s.get_mut(i) {
        *d = v;
    }
}

fn conj_all(data: &mut [Complex32]) {
    for v in data.iter_mut() {
        v.im = -v.im;
    }
}

/// `exp(-2 pi i r / n)`.
#[inline]
fn twiddle(r: usize, n: usize) -> Complex32 {
    let (c, s) = cos_sin_turns(r, n);
    Complex32::new(c, -s)
}

/// Bluestein chirp `exp(-i pi k^2 / m)`: the turn `k^2 / 2m`, with `k^2` reduced in integers.
#[inline]
fn chirp(k: usize, m: usize) -> Complex32 {
    let two_m = 2 * m as u64;
    let r = (k as u64 * k as u64).checked_rem(two_m).unwrap_or(0);
    let (c, s) = cos_sin_turns_u64(r, two_m);
    Complex32::new(c, -s)
}

/// `(cos, sin)` of the angle `2 pi r / n` (`r` turns of `1/n`), in `f32` arithmetic only.
///
/// The reduction is exact: `8 r mod 8 n` is split in integers into an octant and a remainder,
/// so only an angle in `[0, pi/4]` meets floating point, where degree-9/10 Taylor polynomials
/// are accurate to well below one `f32` ulp. The result is within about 1e-7 of the exact
/// values for every `r` and `n` (tested against `f64`), with no `f64` arithmetic: on a
/// single-precision FPU (Cortex-M4F) it costs tens of instructions, where `libm::sinf` and
/// `cosf` evaluate their kernels in software `f64` (hundreds). `n == 0` gives `(1, 0)`.
#[inline]
pub fn cos_sin_turns(r: usize, n: usize) -> (f32, f32) {
    // u32 arithmetic (one UDIV on the M4) whenever 8 n fits, u64 otherwise
    match (u32::try_from(r), u32::try_from(n)) {
        (Ok(r), Ok(n)) if n <= u32::MAX / 8 => cos_sin_turns_u32(r, n),
        _ => cos_sin_turns_u64(r as u64, n as u64),
    }
}

/// `cos(2 pi r / n)` alone, as [`cos_sin_turns`] but evaluating one polynomial instead of
/// two (the window functions need only the cosine).
#[inline]
pub fn cos_turns(r: usize, n: usize) -> f32 {
    if n == 0 {
        return 1.0;
    }
    let (oct, rem, nf) = match (u32::try_from(r), u32::try_from(n)) {
        (Ok(r), Ok(n)) if n <= u32::MAX / 8 => {
            let r = r.checked_rem(n).unwrap_or(0);
            let t = 8 * r;
            let oct = t.checked_div(n).unwrap_or(0);
            (oct, (t - oct * n) as f32, n as f32)
        }
        _ => {
            let (r, n) = (r as u64, n as u64);
            let r = r.checked_rem(n).unwrap_or(0);
            let t = r.saturating_mul(8);
            let oct = t.checked_div(n).unwrap_or(0);
            let rem = t - oct.saturating_mul(n).min(t);
            (oct as u32, rem as f32, n as f32)
        }
    };
    const FRAC_PI_4: f32 = core::f32::consts::FRAC_PI_4;
    // cos of (q pi/2 + y): q = 0: cos y, 1: -sin y, 2: -cos y, 3: sin y; in odd octants
    // cos y = sin x' and sin y = cos x' with x' = (n - rem) / n * pi / 4
    let odd = oct & 1 == 1;
    let q = (oct >> 1) & 3;
    let x = if odd { (nf - rem) / nf } else { rem / nf } * FRAC_PI_4;
    let use_sin = (q & 1 == 1) != odd;
    let v = if use_sin { poly_sin(x) } else { poly_cos(x) };
    if q == 1 || q == 2 {
        -v
    } else {
        v
    }
}

#[inline]
fn cos_sin_turns_u32(r: u32, n: u32) -> (f32, f32) {
    if n == 0 {
        return (1.0, 0.0);
    }
    // r mod n, then 8 r = octant * n + rem with rem < n
    let r = r.checked_rem(n).unwrap_or(0);
    let t = 8 * r;
    let oct = t.checked_div(n).unwrap_or(0);
    let rem = t - oct * n;
    octant_cos_sin(oct, rem as f32, n as f32)
}

#[inline]
fn cos_sin_turns_u64(r: u64, n: u64) -> (f32, f32) {
    if n == 0 {
        return (1.0, 0.0);
    }
    let r = r.checked_rem(n).unwrap_or(0);
    // 8 r < 8 n; lengths here are far below 2^60
    let t = r.saturating_mul(8);
    let oct = t.checked_div(n).unwrap_or(0);
    let rem = t - oct.saturating_mul(n).min(t);
    octant_cos_sin(oct as u32, rem as f32, n as f32)
}

/// `(cos, sin)` of `(oct + rem / n) pi / 4` for `oct < 8`, `0 <= rem < n`.
#[inline(always)]
fn octant_cos_sin(oct: u32, rem: f32, n: f32) -> (f32, f32) {
    const FRAC_PI_4: f32 = core::f32::consts::FRAC_PI_4;
    // angle within the quadrant: y = (oct & 1 + rem / n) pi / 4 in [0, pi / 2); odd octants
    // use pi/2 - y = (n - rem) / n * pi / 4 so the polynomial argument stays in [0, pi / 4]
    let (cy, sy) = if oct & 1 == 0 {
        poly_cos_sin(rem / n * FRAC_PI_4)
    } else {
        let (c, s) = poly_cos_sin((n - rem) / n * FRAC_PI_4);
        (s, c)
    };
    match (oct >> 1) & 3 {
        0 => (cy, sy),
        1 => (-sy, cy),
        2 => (-cy, -sy),
        _ => (sy, -cy),
    }
}

/// Taylor polynomials of cos and sin on `[0, pi/4]` (truncation below 2e-9).
#[inline(always)]
fn poly_cos_sin(x: f32) -> (f32, f32) {
    (poly_cos(x), poly_sin(x))
}

#[inline(always)]
fn poly_cos(x: f32) -> f32 {
    let x2 = x * x;
    1.0 + x2
        * (-1.0 / 2.0
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0 + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0)))))
}

#[inline(always)]
fn poly_sin(x: f32) -> f32 {
    let x2 = x * x;
    x * (1.0
        + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))))
}

/// Spectrum of the Bluestein filter `b[k] = conj(chirp(|k|))` for `|k| < m` (`chirps[k]` =
/// `chirp(k, m)`), circularly placed in `filt` (length `l >= 2m - 1`).
fn chirp_filter(chirps: &[Complex32], filt: &mut [Complex32]) {
    let l = filt.len();
    for v in filt.iter_mut() {
        *v = Complex32::new(0.0, 0.0);
    }
    for (k, c) in chirps.iter().enumerate() {
        let c = c.conj();
        put(filt, k, c);
        if k != 0 {
            put(filt, l.wrapping_sub(k), c);
        }
    }
    fft_pow2(filt);
}

/// Direct DFT of `x` into `out` (same length).
fn naive_dft(x: &[Complex32], out: &mut [Complex32]) {
    let m = x.len();
    for (k, o) in out.iter_mut().enumerate() {
        let mut acc = Complex32::new(0.0, 0.0);
        for (j, v) in x.iter().enumerate() {
            acc += *v * twiddle(j * k, m);
        }
        *o = acc;
    }
}

/// In-place forward FFT of a power-of-two slice (length 1 ..= [`MAX_POW2`]).
/// Other lengths are left untouched; callers only pass lengths planned by [`Dft`].
fn fft_pow2(buf: &mut [Complex32]) {
    use microfft::complex as c;
    macro_rules! dispatch {
        ($($n:literal => $f:ident),*) => {
            match buf.len() {
                $($n => {
                    if let Ok(a) = <&mut [Complex32; $n]>::try_from(buf) {
                        // in place: the returned reference is `a` itself (not a Result)
                        let _in_place: &mut [Complex32; $n] = c::$f(a);
                    }
                })*
                _ => {}
            }
        };
    }
    dispatch!(2 => cfft_2, 4 => cfft_4, 8 => cfft_8, 16 => cfft_16, 32 => cfft_32,
        64 => cfft_64, 128 => cfft_128, 256 => cfft_256, 512 => cfft_512, 1024 => cfft_1024,
        2048 => cfft_2048, 4096 => cfft_4096, 8192 => cfft_8192, 16384 => cfft_16384,
        32768 => cfft_32768);
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// Reference: direct DFT in f64.
    fn reference(x: &[Complex32], dir: Direction) -> Vec<(f64, f64)> {
        let n = x.len();
        let s = if dir == Direction::Forward { -1.0 } else { 1.0 };
        (0..n)
            .map(|k| {
                let (mut re, mut im) = (0.0f64, 0.0f64);
                for (j, v) in x.iter().enumerate() {
                    let a = s * 2.0 * std::f64::consts::PI * ((j * k) % n) as f64 / n as f64;
                    let (sa, ca) = a.sin_cos();
                    re += v.re as f64 * ca - v.im as f64 * sa;
                    im += v.re as f64 * sa + v.im as f64 * ca;
                }
                (re, im)
            })
            .collect()
    }

    fn signal(n: usize, seed: u64) -> Vec<Complex32> {
        // small LCG: deterministic, no dependency
        let mut s = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as f32 / (1u64 << 31) as f32) - 0.5
        };
        (0..n).map(|_| Complex32::new(next(), next())).collect()
    }

    fn check(n: usize, dir: Direction) {
        let x = signal(n, n as u64);
        let want = reference(&x, dir);
        let plan = Dft::try_new(n).unwrap();
        let mut data = x.clone();
        let mut scratch = vec![Complex32::new(0.0, 0.0); plan.scratch_len()];
        assert_eq!(Some(plan.scratch_len()), scratch_len(n));
        plan.process(&mut data, &mut scratch, dir).unwrap();
        let rms = (want.iter().map(|(r, i)| r * r + i * i).sum::<f64>() / n as f64).sqrt();
        let err = data
            .iter()
            .zip(&want)
            .map(|(g, (r, i))| ((g.re as f64 - r).powi(2) + (g.im as f64 - i).powi(2)).sqrt())
            .fold(0.0f64, f64::max);
        assert!(
            err / rms < 2e-5,
            "n = {n} {dir:?}: max error {err:e} vs rms {rms:e}"
        );
    }

    #[test]
    fn cos_sin_turns_matches_f64_for_all_octants_and_large_lengths() {
        let mut worst = 0.0f64;
        for &n in &[
            1usize,
            2,
            3,
            5,
            7,
            8,
            15,
            120,
            1000,
            2048,
            4095,
            20480,
            1 << 22,
        ] {
            let step = (n / 4096).max(1);
            for r in (0..2 * n + 3).step_by(step) {
                let (c, s) = cos_sin_turns(r, n);
                assert_eq!(cos_turns(r, n).to_bits(), c.to_bits(), "cos_turns {r}/{n}");
                let a = std::f64::consts::TAU * (r % n) as f64 / n as f64;
                let e = (c as f64 - a.cos()).abs().max((s as f64 - a.sin()).abs());
                worst = worst.max(e);
                assert!(e < 1.5e-7, "r {r} n {n}: ({c}, {s}) vs {a}");
            }
        }
        // exact at the octant points, and the u64 path (8 n past u32) agrees with the u32 one
        assert_eq!(cos_sin_turns(0, 8), (1.0, 0.0));
        assert_eq!(cos_sin_turns(2, 8), (0.0, 1.0));
        assert_eq!(cos_sin_turns(4, 8), (-1.0, 0.0));
        assert_eq!(cos_sin_turns(6, 8), (0.0, -1.0));
        assert_eq!(cos_sin_turns(5, 0), (1.0, 0.0));
        let a = cos_sin_turns(12_345, 1 << 30);
        let want = std::f64::consts::TAU * 12_345.0 / (1u64 << 30) as f64;
        assert!((a.0 as f64 - want.cos()).abs() < 1.5e-7);
        assert!((a.1 as f64 - want.sin()).abs() < 1.5e-7);
        let r = 987_654_321;
        assert_eq!(
            cos_sin_turns_u64(r, 1 << 27),
            cos_sin_turns_u32(r as u32, 1 << 27)
        );
        assert!(worst > 0.0);
    }

    #[test]
    fn matches_direct_dft_for_many_lengths() {
        // pure powers of two, small odd factors (naive), large odd factors (Bluestein),
        // primes, and the lengths the measurement chain uses.
        for n in [
            1, 2, 3, 5, 7, 8, 12, 15, 16, 64, 75, 97, 120, 127, 129, 256, 257, 625, 1111, 1200,
            2048, 4999, 5000,
        ] {
            check(n, Direction::Forward);
            check(n, Direction::Inverse);
        }
    }

    #[test]
    fn round_trip_20480() {
        // too long for the f64 direct reference in a unit test; a round trip checks it
        let n = 20480;
        let x = signal(n, 7);
        let plan = Dft::try_new(n).unwrap();
        let mut data = x.clone();
        let mut scratch = vec![Complex32::new(0.0, 0.0); plan.scratch_len()];
        plan.process(&mut data, &mut scratch, Direction::Forward)
            .unwrap();
        plan.process(&mut data, &mut scratch, Direction::Inverse)
            .unwrap();
        let err = data
            .iter()
            .zip(&x)
            .map(|(a, b)| {
                let d = *a / n as f32 - *b;
                (d.re * d.re + d.im * d.im).sqrt()
            })
            .fold(0.0f32, f32::max);
        assert!(err < 1e-5, "round trip error {err}");
        // one bin against a direct sum
        let k = 1234usize;
        let mut plan_data = x.clone();
        plan.process(&mut plan_data, &mut scratch, Direction::Forward)
            .unwrap();
        let (mut re, mut im) = (0.0f64, 0.0f64);
        for (j, v) in x.iter().enumerate() {
            let a = -2.0 * std::f64::consts::PI * ((j * k) % n) as f64 / n as f64;
            re += v.re as f64 * a.cos() - v.im as f64 * a.sin();
            im += v.re as f64 * a.sin() + v.im as f64 * a.cos();
        }
        let got = plan_data[k];
        let e = ((got.re as f64 - re).powi(2) + (got.im as f64 - im).powi(2)).sqrt();
        assert!(e < 2e-5 * (n as f64).sqrt() * 0.6, "bin {k}: error {e}");
    }

    #[test]
    fn rejects_bad_lengths_and_buffers() {
        assert_eq!(Dft::try_new(0), Err(DftError::Empty));
        // a large prime needs a Bluestein convolution longer than MAX_POW2
        assert_eq!(
            Dft::try_new(32771),
            Err(DftError::Unsupported { len: 32771 })
        );
        assert_eq!(scratch_len(32771), None);
        let plan = Dft::try_new(12).unwrap();
        let mut d = [Complex32::new(0.0, 0.0); 11];
        let mut s = [Complex32::new(0.0, 0.0); 64];
        assert!(matches!(
            plan.process(&mut d, &mut s, Direction::Forward),
            Err(BufferError {
                expected: 12,
                got: 11
            })
        ));
        let mut d = [Complex32::new(0.0, 0.0); 12];
        let mut s = [Complex32::new(0.0, 0.0); 2];
        assert!(plan.process(&mut d, &mut s, Direction::Forward).is_err());
    }
}

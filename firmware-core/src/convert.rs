//! Displacement to acceleration (method.md §2.3): the displacement spectrum times `-omega^2`
//! (`omega = 2 pi f` at each bin, negative frequencies for the upper half, DC zeroed), then the
//! inverse transform; plus the unit scalings of the vision channel.
//!
//! The spectral operation itself lives with the upsampler, which fuses it with the zero-padding
//! (one forward `n`-point DFT, one multiply, one inverse `m`-point DFT):
//! [`Upsampler::process_acceleration`](crate::upsample::Upsampler::process_acceleration).
//! The standalone conversion at the same rate is the `n -> n` case, offered here as
//! [`Differentiator`]. For even `n` the Nyquist bin is multiplied by `-(2 pi fs/2)^2`, the same
//! factor as its mirror, so the output stays real.
//!
//! ```
//! use firmware_core::convert::{px_to_m_scale, px_to_mm, Differentiator};
//! use firmware_core::upsample::scratch_capacity;
//! // 0.1266 mm/px: a centroid of 10 px is 1.266 mm; mm s^-2 -> m/s^2 through px_to_m_scale
//! assert!((px_to_mm(10.0, 0.1266) - 1.266).abs() < 1e-6);
//! // the second derivative of cos(2 pi 4 t) over one period of 64 samples at 64 Hz
//! const N: usize = 64;
//! let mut d = Differentiator::<N, { scratch_capacity(N, N) }>::try_new(N, N).unwrap();
//! let x: [f32; N] = core::array::from_fn(|j| libm::cosf(2.0 * core::f32::consts::PI * 4.0 * j as f32 / 64.0));
//! let mut a = [0.0f32; N];
//! d.process_acceleration(&x, &mut a, 64.0, px_to_m_scale(1.0) * 1e3).unwrap();
//! let w2 = (2.0 * core::f32::consts::PI * 4.0f32).powi(2);
//! assert!((a[0] + w2).abs() < 1e-3 * w2); // -omega^2 cos(0)
//! ```

/// Standard gravity, m/s^2 (accelerometer channels in g convert with it).
pub const STANDARD_GRAVITY: f32 = STANDARD_GRAVITY_F64 as f32;

/// Standard gravity in `f64` (the exact conventional value, for hosts that compute in `f64`).
pub const STANDARD_GRAVITY_F64: f64 = 9.806_65;

/// Millimetres to metres.
pub const MM_TO_M: f32 = 1.0e-3;

/// Spectral differentiator of a record of `n` samples (`N >= n` work values, `S` scratch, see
/// [`crate::upsample::scratch_capacity`]`(n, n)`): build it with `Differentiator::try_new(n, n)`
/// and call `process_acceleration(input, output, fs_hz, scale)`.
pub type Differentiator<const N: usize, const S: usize> = crate::upsample::Upsampler<N, S>;

/// Pixels to millimetres with the calibration scale `mm_per_px`.
pub fn px_to_mm(px: f32, mm_per_px: f32) -> f32 {
    px * mm_per_px
}

/// Factor that turns (displacement unit) x s^-2 into m/s^2 for a displacement in mm measured
/// as pixels at `mm_per_px`: the `scale` argument of the fused conversion for pixel input.
pub fn px_to_m_scale(mm_per_px: f32) -> f32 {
    mm_per_px * MM_TO_M
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::upsample::scratch_capacity;
    use core::f32::consts::PI;

    #[test]
    fn second_derivative_of_a_periodic_sum_is_exact() {
        // two sinusoids with whole numbers of cycles in 100 samples at 50 Hz, in pixels
        let (n, fs, mm_per_px) = (100usize, 50.0f32, 0.05f32);
        let x: std::vec::Vec<f32> = (0..n)
            .map(|i| {
                let t = i as f32 / fs;
                3.0 * libm::sinf(2.0 * PI * 2.0 * t) + libm::cosf(2.0 * PI * 5.0 * t) + 7.0
            })
            .collect();
        let mut d = Differentiator::<100, { scratch_capacity(100, 100) }>::try_new(n, n).unwrap();
        let mut a = [0.0f32; 100];
        d.process_acceleration(&x, &mut a, fs, px_to_m_scale(mm_per_px))
            .unwrap();
        for (i, v) in a.iter().enumerate() {
            let t = i as f32 / fs;
            let (w1, w2) = (2.0 * PI * 2.0, 2.0 * PI * 5.0);
            let want = -(3.0 * w1 * w1 * libm::sinf(w1 * t) + w2 * w2 * libm::cosf(w2 * t))
                * mm_per_px
                * MM_TO_M;
            // f32: rounding of the DFT is amplified by omega^2 at the high bins; 1e-4 of the
            // peak acceleration
            let peak = (3.0 * w1 * w1 + w2 * w2) * mm_per_px * MM_TO_M;
            assert!((v - want).abs() < 1e-4 * peak, "{i}: {v} vs {want}");
        }
    }

    #[test]
    fn scalings() {
        assert_eq!(px_to_mm(10.0, 0.1266), 1.266);
        assert!((px_to_m_scale(0.1266) - 0.1266e-3).abs() < 1e-12);
    }
}

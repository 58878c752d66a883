//! The host side of firmware-core's measurement chain, used alike by `frf`, `analyze` and the
//! studies (method.md §2):
//!
//! - [`displacement`]: frames -> centroids (firmware-core) -> displacement in mm, with the one
//!   lost-frame policy (linear interpolation, more than 5 % lost fails);
//! - [`frf`]: two channels -> Welch H1 and coherence (firmware-core, one settings type, one place
//!   that centres and scales in `f64` before the `f32` core) -> peaks of |Im H1| in bands;
//! - [`exposure`]: the exposure transfer the vision amplitudes are divided by (sinc for the
//!   weighted centroid, a measured table for the binary one);
//! - [`vision_acceleration`]: displacement at the frame rate -> acceleration at the transducer
//!   rate (firmware-core's Fourier upsampling fused with `-omega^2`).

pub mod displacement;
pub mod exposure;
pub mod frf;

/// Runs `job` on a helper thread with a 64 MiB stack: firmware-core's estimators keep their
/// fixed buffers inline (several MiB at the host's capacities), which would overflow the stack
/// of an ordinary thread.
pub fn on_large_stack<T: Send + 'static>(
    what: &str,
    job: impl FnOnce() -> T + Send + 'static,
) -> anyhow::Result<T> {
    std::thread::Builder::new()
        .name(what.into())
        .stack_size(64 << 20)
        .spawn(job)
        .map_err(|e| anyhow::anyhow!("cannot start the {what} thread: {e}"))?
        .join()
        .map_err(|_| anyhow::anyhow!("the {what} thread panicked"))
}

/// Largest record (upsampler output) the host chain handles: 65 536 samples (32 s at 2048 Hz).
pub const MAX_SAMPLES: usize = frf::MAX_NFFT;

/// Fourier upsampling of the displacement (mm, `N` samples at `fc`) to `m` samples at the
/// transducer rate, fused with the `-omega^2` differentiation and the mm -> m scaling, with
/// firmware-core's [`firmware_core::upsample::Upsampler::process_acceleration`] (`f32`):
/// acceleration in m/s^2 (method.md §2.2, §2.3).
pub fn vision_acceleration(disp_mm: &[f64], fc: f64, m: usize) -> anyhow::Result<Vec<f64>> {
    use firmware_core::upsample::Upsampler;
    let n = disp_mm.len();
    let input: Vec<f32> = disp_mm.iter().map(|&v| v as f32).collect();
    let out = on_large_stack("upsampling", move || -> Result<Vec<f32>, String> {
        let mut up = Box::new(
            Upsampler::<MAX_SAMPLES, { frf::SCRATCH }>::try_new(n, m).map_err(|e| e.to_string())?,
        );
        let mut out = vec![0.0f32; m];
        up.process_acceleration(&input, &mut out, fc as f32, 1.0e-3)
            .map_err(|e| e.to_string())?;
        Ok(out)
    })?
    .map_err(|e| {
        crate::bad_input(format!(
            "upsampling {n} frames to {m} samples (at most {MAX_SAMPLES}): {e}"
        ))
    })?;
    Ok(out.into_iter().map(f64::from).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bad_input;
    use num_complex::Complex64;

    /// Reference upsampling + -omega^2 (rustfft, f64, written from method.md §2.2/§2.3).
    fn reference_vision_acceleration(
        disp_mm: &[f64],
        fc: f64,
        fa: f64,
        m: usize,
    ) -> anyhow::Result<Vec<f64>> {
        use rustfft::FftPlanner;
        let n = disp_mm.len();
        let _ = fc;
        if n == 0 || m < n {
            return Err(bad_input(format!(
                "cannot upsample {n} frames to {m} samples"
            )));
        }
        let mut planner = FftPlanner::<f64>::new();
        let mut x: Vec<Complex64> = disp_mm.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        planner.plan_fft_forward(n).process(&mut x);
        let mut y = vec![Complex64::new(0.0, 0.0); m];
        let half = n / 2;
        for k in 1..n.div_ceil(2) {
            y[k] = x[k];
            y[m - k] = x[n - k];
        }
        if n.is_multiple_of(2) && half > 0 {
            y[half] = x[half] * 0.5;
            y[m - half] += x[half] * 0.5;
        }
        let two_pi = 2.0 * std::f64::consts::PI;
        for (k, v) in y.iter_mut().enumerate() {
            let signed = if k <= m / 2 {
                k as f64
            } else {
                k as f64 - m as f64
            };
            let w = two_pi * signed * fa / m as f64;
            *v *= -w * w;
        }
        y[0] = Complex64::new(0.0, 0.0);
        planner.plan_fft_inverse(m).process(&mut y);
        Ok(y.iter().map(|v| v.re / n as f64 / 1000.0).collect())
    }

    /// Window coefficients, periodic (scipy `get_window(..., fftbins=True)`).
    #[test]
    fn vision_acceleration_matches_the_closed_form() {
        let (fc, fa, n) = (120.0, 2048.0, 1200usize);
        let m = n * 2048 / 120;
        let (f, amp_mm) = (7.3, 2.0);
        let w = 2.0 * std::f64::consts::PI * f;
        let x: Vec<f64> = (0..n)
            .map(|k| amp_mm * (w * k as f64 / fc).sin() + 0.7)
            .collect();
        let acc = vision_acceleration(&x, fc, m).unwrap();
        assert_eq!(acc.len(), m);
        let peak = w * w * amp_mm / 1000.0;
        let worst = acc
            .iter()
            .enumerate()
            .map(|(j, a)| (a + peak * (w * j as f64 / fa).sin()).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-4 * peak, "worst error {worst} of peak {peak}");
    }

    /// The firmware upsampler (f32) agrees with the f64 reference on a random record, 1200
    /// frames at 120 fps to 2048 Hz.
    #[test]
    fn firmware_upsampling_matches_the_reference() {
        let x = crate::testing::uniform_noise(5, 1200);
        let got = vision_acceleration(&x, 120.0, 20480).unwrap();
        let want = reference_vision_acceleration(&x, 120.0, 2048.0, 20480).unwrap();
        let peak = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let worst = got
            .iter()
            .zip(&want)
            .fold(0.0f64, |a, (g, w)| a.max((g - w).abs()));
        assert!(worst < 1e-4 * peak, "worst {worst} of peak {peak}");
    }
}

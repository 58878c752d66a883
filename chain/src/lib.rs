//! The host side of firmware-core's measurement chain, used alike by `frf`, `analyze` and the
//! studies (method.md §2):
//!
//! - [`displacement`]: frames -> centroids (firmware-core) -> displacement in mm, with the one
//!   lost-frame policy (linear interpolation, more than 5 % lost fails);
//! - [`frf`]: two channels -> Welch H1 and coherence (firmware-core, one settings type, one place
//!   that centres and scales in `f64` before the `f32` core) -> peaks of |Im H1| in bands;
//! - [`lk`]: firmware-core's Lucas-Kanade tracker at the host's capacities;
//! - [`tracker`]: the one tracker enum (blob, weighted, Lucas-Kanade);
//! - [`resample`]: one column of samples upsampled (the `upsample` command);
//! - [`vision_acceleration`]: displacement at the frame rate -> acceleration at the transducer
//!   rate (firmware-core's Fourier upsampling fused with `-omega^2`).

pub mod displacement;
pub mod frf;
pub mod lk;
pub mod resample;
pub mod tracker;

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
/// acceleration in m/s^2 (method.md §2.2, §2.3). The record is taken as periodic (see
/// [`vision_acceleration_end_matched`] for a real, non-periodic record).
pub fn vision_acceleration(disp_mm: &[f64], fc: f64, m: usize) -> anyhow::Result<Vec<f64>> {
    vision_acceleration_with(disp_mm, fc, m, false)
}

/// [`vision_acceleration`] of a whole record that is not periodic (a real recording): the
/// straight line through its first and last samples is subtracted before the transform (the
/// periodic extension then has no jump between the last sample and the first, whose Gibbs
/// ringing `omega^2` would amplify), as firmware-core's pipeline does per block
/// ([`firmware_core::upsample::UpsampleOptions::end_match`]); a line has no acceleration, so
/// nothing is added back. (A periodic record, first == last + one step, gets a kink of one
/// step at the wrap instead of its jump of zero: a small ringing near its ends.)
pub fn vision_acceleration_end_matched(
    disp_mm: &[f64],
    fc: f64,
    m: usize,
) -> anyhow::Result<Vec<f64>> {
    vision_acceleration_with(disp_mm, fc, m, true)
}

/// The end-matching `next` sample of a whole record: on the line through its first and last
/// samples, one step past the last, so that the record minus the line starts and ends at 0.
/// (Extrapolating the record itself instead, by a line or a cubic through its last samples,
/// left 1.8 times the RMS error on the test record of
/// `end_matching_removes_the_ringing_of_a_non_periodic_record`.)
fn end_match_next(x: &[f64]) -> Option<f32> {
    let n = x.len();
    (n > 1).then(|| (x[0] + (x[n - 1] - x[0]) * n as f64 / (n - 1) as f64) as f32)
}

fn vision_acceleration_with(
    disp_mm: &[f64],
    fc: f64,
    m: usize,
    end_match: bool,
) -> anyhow::Result<Vec<f64>> {
    use firmware_core::upsample::{Accel, UpsampleOptions, Upsampler};
    let n = disp_mm.len();
    let input: Vec<f32> = disp_mm.iter().map(|&v| v as f32).collect();
    // the sample that would follow the record on the line through its first and last samples
    let next = if end_match {
        end_match_next(disp_mm)
    } else {
        None
    };
    let out = on_large_stack("upsampling", move || -> Result<Vec<f32>, String> {
        let mut up = Box::new(
            Upsampler::<MAX_SAMPLES, { frf::SCRATCH }>::try_new(n, m).map_err(|e| e.to_string())?,
        );
        let mut out = vec![0.0f32; m];
        let options = UpsampleOptions {
            accel: Some(Accel {
                fs_in_hz: fc as f32,
                scale: 1.0e-3,
            }),
            end_match: next,
            exposure: None,
        };
        up.process_options(&input, &mut out, options)
            .map_err(|e| e.to_string())?;
        Ok(out)
    })?
    .map_err(|e| {
        vibcam_readers::bad_input(format!(
            "upsampling {n} frames to {m} samples (at most {MAX_SAMPLES}): {e}"
        ))
    })?;
    Ok(out.into_iter().map(f64::from).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64;
    use vibcam_readers::bad_input;

    /// Reference upsampling + -omega^2 (rustfft, f64, written from method.md §2.2/§2.3).
    fn reference_vision_acceleration(
        disp_mm: &[f64],
        fc: f64,
        fa: f64,
        m: usize,
    ) -> anyhow::Result<Vec<f64>> {
        let n = disp_mm.len();
        let _ = fc;
        if n == 0 || m < n {
            return Err(bad_input(format!(
                "cannot upsample {n} frames to {m} samples"
            )));
        }
        let mut planner = vibcam_fft::Planner::new();
        let mut x: Vec<Complex64> = disp_mm.iter().map(|&v| Complex64::new(v, 0.0)).collect();
        planner.forward(n).process(&mut x);
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
        planner.inverse(m).process(&mut y);
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
        let x = vibcam_common::testing::uniform_noise(5, 1200);
        let got = vision_acceleration(&x, 120.0, 20480).unwrap();
        let want = reference_vision_acceleration(&x, 120.0, 2048.0, 20480).unwrap();
        let peak = want.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let worst = got
            .iter()
            .zip(&want)
            .fold(0.0f64, |a, (g, w)| a.max((g - w).abs()));
        assert!(worst < 1e-4 * peak, "worst {worst} of peak {peak}");
    }
    /// A record that is not periodic (7.05 Hz over 10 s plus a slow drift, 1200 frames at
    /// 120 fps): taken as periodic, its end-to-end jump rings through the whole record,
    /// amplified by omega^2; the end-matched acceleration follows the analytic one. Measured
    /// RMS errors (printed): see the assertion's message.
    #[test]
    fn end_matching_removes_the_ringing_of_a_non_periodic_record() {
        let (fc, fa, n) = (120.0, 2048.0, 1200usize);
        let m = n * 2048 / 120;
        let (f, amp_mm, drift) = (7.05, 2.0, 0.3);
        let w = 2.0 * std::f64::consts::PI * f;
        let x: Vec<f64> = (0..n)
            .map(|k| {
                let t = k as f64 / fc;
                amp_mm * (w * t + 0.4).sin() + drift * t
            })
            .collect();
        let truth: Vec<f64> = (0..m)
            .map(|j| -w * w * amp_mm / 1000.0 * (w * j as f64 / fa + 0.4).sin())
            .collect();
        let rms = |a: &[f64]| {
            let e: f64 = a.iter().zip(&truth).map(|(a, t)| (a - t).powi(2)).sum();
            (e / m as f64).sqrt()
        };
        // the middle half, away from the ends
        let mid = |a: &[f64]| {
            let e: f64 = a[m / 4..3 * m / 4]
                .iter()
                .zip(&truth[m / 4..3 * m / 4])
                .map(|(a, t)| (a - t).powi(2))
                .sum();
            (e / (m / 2) as f64).sqrt()
        };
        let plain = vision_acceleration(&x, fc, m).unwrap();
        let matched = vision_acceleration_end_matched(&x, fc, m).unwrap();
        let peak = w * w * amp_mm / 1000.0;
        let (rp, rm) = (rms(&plain), rms(&matched));
        let (mp, mm) = (mid(&plain), mid(&matched));
        println!(
            "rms error / peak: periodic {:.2e} (middle {:.2e}), end-matched {:.2e} (middle {:.2e})",
            rp / peak,
            mp / peak,
            rm / peak,
            mm / peak
        );
        // measured: RMS 0.117 against 0.551 of the peak (what is left is the slope mismatch
        // at the ends, which rings near them); in the middle half 1.6e-4 against 1.2e-2
        assert!(rm < 0.5 * rp, "end-matched {rm} vs periodic {rp}");
        assert!(mm < 0.05 * mp, "middle: end-matched {mm} vs periodic {mp}");
        assert!(
            mm < 1e-3 * peak,
            "end-matched middle error {mm} of peak {peak}"
        );
        // a periodic record is not one a camera gives, but the synthetic recordings are: the
        // line through its ends (one step of the motion) leaves a kink at the wrap, whose
        // ringing stays near the ends
        let xp: Vec<f64> = (0..n)
            .map(|k| amp_mm * (2.0 * std::f64::consts::PI * 7.0 * k as f64 / fc).sin())
            .collect();
        let wp = 2.0 * std::f64::consts::PI * 7.0;
        let b = vision_acceleration_end_matched(&xp, fc, m).unwrap();
        let e: f64 = (m / 4..3 * m / 4)
            .map(|j| (b[j] + wp * wp * amp_mm / 1000.0 * (wp * j as f64 / fa).sin()).powi(2))
            .sum();
        let middle = (e / (m / 2) as f64).sqrt();
        println!(
            "periodic record, end-matched: middle rms error / peak {:.2e}",
            middle / peak
        );
        assert!(
            middle < 0.01 * peak,
            "periodic record, middle error {middle}"
        );
    }
}

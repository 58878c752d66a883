//! Fourier upsampling of one column of samples through firmware-core's upsampler (`f32`,
//! method.md §2.2, the convention of `scipy.signal.resample`): the output length, the core's
//! capacity, the exact power-of-two scaling of values the `f32` core could overflow on, and the
//! large stack its fixed buffers need. `upsample` is this plus reading and writing CSV.

use crate::bad_input;
use firmware_core::upsample::Upsampler;

/// Largest output length the host instantiation handles.
pub const MAX_OUTPUT: usize = 1 << 16;

/// Largest input magnitude taken into the f32 core as it is: its transform (sums over up to
/// 65 536 values, times the window of the output) stays far from `f32::MAX` (3.4e38).
const F32_SAFE: f64 = 1e30;

type HostUpsampler = Upsampler<MAX_OUTPUT, { 2 * MAX_OUTPUT + 256 }>;

/// Output length `n * to / from` if it is an integer (within 1e-9 relative).
pub fn output_len(n: usize, from: f64, to: f64) -> Option<usize> {
    if !(from.is_finite() && to.is_finite() && from > 0.0 && to > 0.0) {
        return None;
    }
    let m = n as f64 * to / from;
    let r = m.round();
    ((m - r).abs() <= 1e-9 * m.max(1.0) && r >= 1.0).then_some(r as usize)
}

/// An upsampled column: sample `k` is `values[k] * scale` (`scale` 1, or the power of two the
/// input was divided by to keep it in the `f32` core's range).
#[derive(Debug, Clone, PartialEq)]
pub struct Upsampled {
    /// The core's output.
    pub values: Vec<f32>,
    /// The exact power-of-two factor to multiply them by.
    pub scale: f64,
}

/// `values` (finite, at `from_hz`) upsampled to `to_hz`: `n * to / from` samples. Values whose
/// transform could overflow the `f32` core are divided by a power of two (exact), which
/// [`Upsampled::scale`] gives back.
pub fn upsample_column(values: &[f64], from_hz: f64, to_hz: f64) -> anyhow::Result<Upsampled> {
    let n = values.len();
    let m = output_len(n, from_hz, to_hz).ok_or_else(|| {
        bad_input(format!(
            "--from {from_hz} / --to {to_hz}: {n} samples at {from_hz} Hz do not make an \
             integer number of samples at {to_hz} Hz"
        ))
    })?;
    if m < n {
        return Err(bad_input(format!(
            "--to {to_hz} Hz is below --from {from_hz} Hz: this command only upsamples"
        )));
    }
    if m > MAX_OUTPUT {
        return Err(bad_input(format!(
            "{m} output samples exceed this command's capacity of {MAX_OUTPUT}"
        )));
    }
    let peak = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let scale = if peak > F32_SAFE {
        super::frf::pow2_scale(values)
    } else {
        1.0
    };
    let x: Vec<f32> = values.iter().map(|v| (*v / scale) as f32).collect();
    let y = super::on_large_stack("upsampling", move || -> anyhow::Result<Vec<f32>> {
        let mut up = Box::new(
            HostUpsampler::try_new(n, m).map_err(|e| bad_input(format!("{n} -> {m}: {e}")))?,
        );
        let mut y = vec![0.0f32; m];
        up.process(&x, &mut y)
            .map_err(|e| anyhow::anyhow!("upsampling: {e}"))?;
        Ok(y)
    })??;
    Ok(Upsampled { values: y, scale })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_length_must_be_an_integer() {
        assert_eq!(output_len(1200, 120.0, 2048.0), Some(20480));
        assert_eq!(output_len(120, 120.0, 2048.0), Some(2048));
        assert_eq!(output_len(100, 120.0, 2048.0), None);
        assert_eq!(output_len(10, 0.0, 2048.0), None);
    }
}

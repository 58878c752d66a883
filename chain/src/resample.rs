//! Fourier upsampling of one column of samples through firmware-core's upsampler (`f32`,
//! method.md §2.2, the convention of `scipy.signal.resample`): the output length, the core's
//! capacity, the exact power-of-two scaling of values the `f32` core could overflow on, and the
//! large stack its fixed buffers need. `upsample` is this plus reading and writing CSV.

use firmware_core::upsample::Upsampler;
use vibcam_readers::bad_input;

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
            "$from {from_hz} / $to {to_hz}: {n} samples at {from_hz} Hz do not make an \
             integer number of samples at {to_hz} Hz"
        ))
    })?;
    if m < n {
        return Err(bad_input(format!(
            "$to {to_hz} Hz is below $from {from_hz} Hz: this command only upsamples"
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

/// The smallest number of input samples `q` (up to 4096) that makes a whole number of samples
/// at `to_hz`: records are resampled in multiples of it.
pub fn rate_period(from_hz: f64, to_hz: f64) -> Option<usize> {
    (1..=4096).find(|&q| output_len(q, from_hz, to_hz).is_some())
}

/// The most samples [`upsample_record`] makes of one record (1 GiB of f64).
pub const MAX_UPSAMPLED: usize = 1 << 27;

/// The largest ratio of rates [`upsample_record`] takes (a camera at 25 fps beside a DAQ at
/// 2.5 MHz is 10^5).
pub const MAX_UPSAMPLE_RATIO: f64 = 1e5;

/// A whole record (not periodic, of any length) upsampled from `from_hz` to `to_hz` through
/// firmware-core's Fourier upsampler, in overlapping chunks of `q 2^j` samples (`q` the
/// [`rate_period`]: the chunk and its upsampled length then have small odd factors, which the
/// core's transforms need): each chunk has the line through its first and last samples taken
/// out (its periodic extension then has no jump to ring at; a chunk shorter than the rest, at
/// a short record's end, is padded with zeros after that), is upsampled, and the line is added
/// back on the finer grid; of each chunk only its middle half is kept (a quarter of a chunk of
/// margin either side: the ringing of a chunk's ends decays long before). The record is first
/// cut to a multiple of `q` samples (at most `q - 1` samples dropped at its end); the output
/// has `n * to / from` samples of that.
pub fn upsample_record(values: &[f64], from_hz: f64, to_hz: f64) -> anyhow::Result<Vec<f64>> {
    let q = rate_period(from_hz, to_hz).ok_or_else(|| {
        bad_input(format!(
            "{from_hz} Hz and {to_hz} Hz: no whole number of samples (up to 4096) at the one \
             makes a whole number at the other; state both rates exactly"
        ))
    })?;
    if to_hz < from_hz {
        return Err(bad_input(format!(
            "{to_hz} Hz is below {from_hz} Hz: records are only upsampled"
        )));
    }
    let ratio = to_hz / from_hz;
    let n = values.len() - values.len() % q;
    let out_len = n as f64 * ratio;
    if out_len.is_nan() || out_len > MAX_UPSAMPLED as f64 || ratio > MAX_UPSAMPLE_RATIO {
        return Err(bad_input(format!(
            "{} samples at {from_hz} Hz upsampled to {to_hz} Hz would be {out_len:.3e} samples \
             (a ratio of {ratio:.4e}); at most {MAX_UPSAMPLED} samples and a ratio of \
             {MAX_UPSAMPLE_RATIO} are made: check the rates (a time column in ms or us read \
             as seconds?)",
            values.len()
        )));
    }
    let out_of = |k: usize| (k as f64 * ratio).round() as usize;
    // a chunk: q 2^j samples, its upsampled length at most 32768 (and at least 4 q)
    let mut chunk = q * 4;
    while out_of(chunk * 2) <= 32_768 {
        chunk *= 2;
    }
    let core = chunk / 2;
    let margin = chunk / 4;
    let mut out = vec![0.0; out_of(n)];
    let mut s = 0;
    while s < n {
        let e = (s + core).min(n);
        let a = s.saturating_sub(margin).min(n.saturating_sub(chunk));
        let b = (a + chunk).min(n);
        let part = &values[a..b];
        let len = part.len();
        let (first, last) = (part[0], part[len - 1]);
        let slope = if len > 1 {
            (last - first) / (len - 1) as f64
        } else {
            0.0
        };
        let mut detrended: Vec<f64> = part
            .iter()
            .enumerate()
            .map(|(k, v)| v - first - slope * k as f64)
            .collect();
        detrended.resize(chunk, 0.0);
        let up = upsample_column(&detrended, from_hz, to_hz)?;
        let (from, base) = (out_of(s), out_of(a));
        for (j, o) in out[from..out_of(e)].iter_mut().enumerate() {
            let local = from + j - base;
            let t = local as f64 / ratio;
            *o = f64::from(up.values[local]) * up.scale + first + slope * t;
        }
        s = e;
    }
    Ok(out)
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

    #[test]
    fn a_long_record_upsampled_in_chunks_matches_the_signal() {
        // 15 kHz -> 50 kHz (10/3), 60 000 samples: 200 000 out, many chunks; a decaying
        // sinusoid plus an offset and a drift (not periodic)
        let (from, to) = (15_000.0, 50_000.0);
        let x = |t: f64| {
            3.0 + 0.5 * t
                + (-2.0 * t).exp() * (2.0 * std::f64::consts::PI * 312.5 * t).sin()
                + 0.3 * (2.0 * std::f64::consts::PI * 1234.0 * t + 0.4).cos()
        };
        let v: Vec<f64> = (0..60_001).map(|k| x(k as f64 / from)).collect();
        assert_eq!(rate_period(from, to), Some(3));
        let up = upsample_record(&v, from, to).unwrap();
        assert_eq!(up.len(), 200_000);
        let mut worst = 0.0f64;
        // away from the record's two ends (a record is not periodic there)
        for (j, u) in up.iter().enumerate().take(199_000).skip(1000) {
            worst = worst.max((u - x(j as f64 / to)).abs());
        }
        assert!(worst < 2e-4, "largest error {worst}");
    }
}

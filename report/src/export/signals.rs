//! The outputs of the signal commands: `frf --out` and its peaks, `upsample --out`, and the
//! rows `centroid` prints.

use super::analysis::{position, Spectrum};
use firmware_core::centroid::Centroid;

/// One CSV record (quoted as the `csv` crate quotes, e.g. a file name with a comma), with its
/// newline.
fn record<const N: usize>(cells: [&str; N]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    // a record written to memory cannot fail
    w.write_record(cells).ok();
    w.into_inner().unwrap_or_default()
}

/// `frf --out`: `freq_hz,h1_re,h1_im,h1_abs,coherence`, H1 and coherence in `f32` (the
/// firmware's precision), one row per line.
pub fn frf_csv(frf: Spectrum<'_>) -> Vec<u8> {
    let mut out = record(["freq_hz", "h1_re", "h1_im", "h1_abs", "coherence"]);
    for ((f, h), c) in frf.freq_hz.iter().zip(frf.h1).zip(frf.coherence) {
        let (re, im) = (h.re as f32, h.im as f32);
        out.extend(record([
            &f.to_string(),
            &re.to_string(),
            &im.to_string(),
            &re.hypot(im).to_string(),
            &(*c as f32).to_string(),
        ]));
    }
    out
}

/// The peaks of `frf --bands` (standard output): `band,f_hz,amplitude`, one row per
/// `(band label, f_hz, amplitude)`, in `f32`.
pub fn peaks_csv<'a>(peaks: impl IntoIterator<Item = (&'a str, f64, f64)>) -> Vec<u8> {
    let mut out = record(["band", "f_hz", "amplitude"]);
    for (label, f, a) in peaks {
        out.extend(record([
            label,
            &(f as f32).to_string(),
            &(a as f32).to_string(),
        ]));
    }
    out
}

/// `upsample --out`: `t_s,value` at `fs_hz`; each value is `values[k] * scale` (written as the
/// `f32` itself when `scale` is 1).
pub fn upsampled_csv(values: &[f32], scale: f64, fs_hz: f64) -> Vec<u8> {
    let mut text = String::from("t_s,value\n");
    for (k, v) in values.iter().enumerate() {
        let t = k as f64 / fs_hz;
        if scale == 1.0 {
            text.push_str(&format!("{t},{v}\n"));
        } else {
            text.push_str(&format!("{t},{}\n", *v as f64 * scale));
        }
    }
    text.into_bytes()
}

/// The header `centroid` prints: `file,cx,cy,pixels,flags`.
pub fn centroid_header() -> Vec<u8> {
    record(["file", "cx", "cy", "pixels", "flags"])
}

/// One row `centroid` prints: `file,cx,cy,pixels,flags` (cx, cy empty when there is no
/// centroid; `flags` the firmware-core flag byte).
pub fn centroid_row(file: &str, c: &Centroid) -> Vec<u8> {
    let (cx, cy) = position(c);
    record([
        file,
        &cx,
        &cy,
        &c.pixels().to_string(),
        &c.flags.bits().to_string(),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_complex::Complex64;

    #[test]
    fn the_signal_writers_emit_the_contract_headers() {
        let empty = Centroid {
            cx: 0.0,
            cy: 0.0,
            moments: Default::default(),
            flags: firmware_core::centroid::Flags::EMPTY,
        };
        let h1 = [Complex64::new(3.0, -4.0)];
        let frf = Spectrum {
            freq_hz: &[0.5],
            h1: &h1,
            coherence: &[0.25],
        };
        assert_eq!(
            String::from_utf8(frf_csv(frf)).unwrap(),
            "freq_hz,h1_re,h1_im,h1_abs,coherence\n0.5,3,-4,5,0.25\n"
        );
        assert_eq!(
            String::from_utf8(peaks_csv([("1-2", 1.5, 2.0)])).unwrap(),
            "band,f_hz,amplitude\n1-2,1.5,2\n"
        );
        assert_eq!(
            String::from_utf8(centroid_row("a,b.png", &empty)).unwrap(),
            "\"a,b.png\",,,0,1\n"
        );
    }
}

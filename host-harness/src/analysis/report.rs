//! The outputs of an analysis as text (pure writers: results in, text out; the caller writes the
//! files): `frf.csv`, `modes.csv`, `displacement.csv` and the human report.

use super::{Analysis, Displacement, MAX_LOST_FRACTION};
use firmware_core::centroid::Centroid;

/// `frf.csv`: `freq_hz,acc_h1_re,acc_h1_im,acc_h1_abs,acc_coherence,vis_h1_re,vis_h1_im,
/// vis_h1_abs,vis_coherence`, one row per bin.
pub fn frf_csv(a: &Analysis) -> String {
    use std::fmt::Write as _;
    let mut s = String::from(
        "freq_hz,acc_h1_re,acc_h1_im,acc_h1_abs,acc_coherence,vis_h1_re,vis_h1_im,vis_h1_abs,\
         vis_coherence\n",
    );
    for (k, f) in a.acc_frf.freq_hz.iter().enumerate() {
        let (ha, ca) = (a.acc_frf.h1[k], a.acc_frf.coherence[k]);
        let (hv, cv) = (a.vis_frf.h1[k], a.vis_frf.coherence[k]);
        let _ = writeln!(
            s,
            "{f},{},{},{},{ca},{},{},{},{cv}",
            ha.re,
            ha.im,
            ha.norm(),
            hv.re,
            hv.im,
            hv.norm()
        );
    }
    s
}

/// `modes.csv`: `system,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr` (`system` is
/// `accelerometer` or `vision`, `mode` is 1-based, `f_hz` and `amplitude` the picked peak,
/// `damping` the ratio of a single-mode fit to the complex FRF in the band
/// ([`super::modal::fit_mode`]; empty when the fit fails), `e2pr` empty without an exposure).
pub fn modes_csv(a: &Analysis) -> String {
    use super::modal::{fit_mode, FrfForm};
    use std::fmt::Write as _;
    let mut s = String::from("system,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr\n");
    for (system, modes, frf) in [
        ("accelerometer", &a.acc_modes, &a.acc_frf),
        ("vision", &a.vis_modes, &a.vis_frf),
    ] {
        for (i, m) in modes.iter().enumerate() {
            let e2pr = m
                .e2pr
                .map(|e| super::compensate::round_e2pr(e).to_string())
                .unwrap_or_default();
            let damping = fit_mode(&frf.freq_hz, &frf.h1, m.band_hz, FrfForm::Accelerance)
                .map(|f| f.pole.damping.to_string())
                .unwrap_or_default();
            let _ = writeln!(
                s,
                "{system},{},{},{},{},{},{damping},{e2pr}",
                i + 1,
                m.band_hz.0,
                m.band_hz.1,
                m.f_hz,
                m.amplitude
            );
        }
    }
    s
}

/// `displacement.csv`: `frame,t_s,cx,cy,pixels,flags,disp_mm,lost`, one row per frame. `t_s` is
/// the frame time from the first accelerometer sample (`time_offset_s + frame / fc`); `cx`,
/// `cy` are empty for lost frames, `flags` is the firmware-core flag byte, `lost` is 0 or 1.
pub fn displacement_csv(
    centroids: &[Centroid],
    disp: &Displacement,
    frame_rate_hz: f64,
    time_offset_s: f64,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("frame,t_s,cx,cy,pixels,flags,disp_mm,lost\n");
    for (k, (c, (d, lost))) in centroids
        .iter()
        .zip(disp.mm.iter().zip(&disp.lost))
        .enumerate()
    {
        let t = time_offset_s + k as f64 / frame_rate_hz;
        let (cx, cy) = match c.position() {
            Some((x, y)) => (x.to_string(), y.to_string()),
            None => (String::new(), String::new()),
        };
        let _ = writeln!(
            s,
            "{k},{t},{cx},{cy},{},{},{d},{}",
            c.pixels(),
            c.flags.bits(),
            u8::from(*lost)
        );
    }
    s
}

/// `x` with about 5 significant digits: fixed notation between 0.01 and 1e5, else scientific.
fn significant(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (0.01..1e5).contains(&a) {
        format!("{x:.4}")
    } else {
        format!("{x:.4e}")
    }
}

/// The short human report: `inputs` (label, value) lines, lost frames, the modes of both
/// systems and the vision / accelerometer ratios. `analysis` is `None` when the analysis
/// failed before the FRFs (`failure` then says why).
pub fn report_text(
    inputs: &[(String, String)],
    disp: &Displacement,
    analysis: Option<&Analysis>,
    failure: Option<&str>,
) -> String {
    use std::fmt::Write as _;
    let mut s = String::from("host-harness analyze\n\ninputs\n");
    let w = inputs.iter().map(|(k, _)| k.len()).max().unwrap_or(0);
    for (k, v) in inputs {
        let _ = writeln!(s, "  {k:<w$}  {v}");
    }
    let _ = writeln!(
        s,
        "\nlost frames: {} of {} ({:.2} %, limit {} %){}",
        disp.lost_count,
        disp.mm.len(),
        100.0 * disp.lost_fraction(),
        100.0 * MAX_LOST_FRACTION,
        if disp.lost_count > 0 {
            format!(" - {}", disp.policy.describe())
        } else {
            String::new()
        }
    );
    if let Some(f) = failure {
        let _ = writeln!(s, "\nANALYSIS FAILED: {f}");
    }
    let Some(a) = analysis else {
        return s;
    };
    if a.frames_used < disp.mm.len() {
        let _ = writeln!(
            s,
            "note: the last {} of {} frames were left out: the first {} are the longest record \
             that spans a whole number of accelerometer samples",
            disp.mm.len() - a.frames_used,
            disp.mm.len(),
            a.frames_used
        );
    }
    let (nperseg, noverlap, nfft) = (a.welch.nperseg, a.welch.noverlap, a.welch.nfft);
    let df = a.acc_frf.freq_hz.get(1).copied().unwrap_or(0.0);
    let _ = writeln!(
        s,
        "aligned: frames cover accelerometer samples {}..{} ({} samples); alignment rounding \
         residual {:.3e} s (removed from the vision H1)\n\
         H1: nperseg {nperseg}, noverlap {noverlap}, nfft {nfft}, bin {df} Hz",
        a.alignment.start,
        a.alignment.start + a.alignment.len,
        a.alignment.len,
        a.alignment.residual_s
    );
    let _ = writeln!(
        s,
        "\nmode  band_hz        acc_f_hz  acc_amp     vis_f_hz  vis_amp     vis/acc_amp  \
         vis-acc_f_hz  e2pr"
    );
    for (i, (am, vm)) in a.acc_modes.iter().zip(&a.vis_modes).enumerate() {
        let e2pr = vm
            .e2pr
            .map(|e| format!("{e:.4}"))
            .unwrap_or_else(|| "-".into());
        let _ = writeln!(
            s,
            "{:<4}  {:<13}  {:<8.3}  {:<10}  {:<8.3}  {:<10}  {:<11.4}  {:<12.3}  {e2pr}",
            i + 1,
            format!("{}-{}", am.band_hz.0, am.band_hz.1),
            am.f_hz,
            significant(am.amplitude),
            vm.f_hz,
            significant(vm.amplitude),
            vm.amplitude / am.amplitude,
            vm.f_hz - am.f_hz
        );
    }
    s
}

//! An analysis's results as the rows of its output files (written by [`crate::export`]) and
//! the human report.

use super::oma::uncertainty::Interval;
use super::{Analysis, Displacement, MAX_LOST_FRACTION};
use crate::export::analysis::{ModeRow, Spectrum};

/// The rows of `modes.csv` ([`crate::export::analysis::modes_csv`]): both systems' picked
/// modes, each with the damping of a single-mode fit to the complex FRF in its band
/// ([`super::frf_uncertainty::damping`]; `None` when the fit fails) and the intervals where
/// computed.
pub fn mode_rows(a: &Analysis) -> Vec<ModeRow> {
    let cells = |i: Option<Interval>| i.map(|i| (i.u, i.lo, i.hi));
    let mut rows = Vec::new();
    for (system, modes, frf, unc) in [
        (
            "accelerometer",
            &a.acc_modes,
            &a.acc_frf,
            a.intervals.as_ref().map(|i| &i.acc),
        ),
        (
            "vision",
            &a.vis_modes,
            &a.vis_frf,
            a.intervals.as_ref().map(|i| &i.vis),
        ),
    ] {
        for (i, m) in modes.iter().enumerate() {
            let u = unc.and_then(|u| u.get(i));
            // the intervals' smoothed fit is the damping's when there is one (not fitted again)
            let damping = match u {
                Some(u) if frf.segments > 1 => u.damping_fit,
                _ => super::frf_uncertainty::damping(frf, m),
            };
            let u = u.cloned().unwrap_or_default();
            rows.push(ModeRow {
                system,
                mode: i + 1,
                band_hz: m.band_hz,
                f_hz: m.f_hz,
                amplitude: m.amplitude,
                damping,
                e2pr: m.e2pr,
                intervals: [cells(u.f_hz), cells(u.damping), cells(u.amplitude)],
            });
        }
    }
    rows
}

/// An H1 estimate as [`crate::export`] takes it.
pub fn spectrum(f: &crate::chain::frf::Frf) -> Spectrum<'_> {
    Spectrum {
        freq_hz: &f.freq_hz,
        h1: &f.h1,
        coherence: &f.coherence,
    }
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
    s.push_str(&modes_table(a));
    if let Some(i) = &a.intervals {
        s.push_str(&intervals_text(a, i));
    }
    s
}

/// The report's table of modes: each band's accelerometer and vision peaks side by side.
fn modes_table(a: &Analysis) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
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

/// The report's section on the intervals ([`super::frf_uncertainty`]).
fn intervals_text(a: &Analysis, i: &super::frf_uncertainty::Intervals) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    if let Some(why) = i.none_why() {
        let _ = writeln!(s, "{why}");
    } else {
        let _ = writeln!(
            s,
            "\n95 % intervals (statistical, from the record: the jackknife over {} groups of \
             its {} Welch segments; |FRF| = the FRF at the line, the window's smoothing \
             removed by a modal fit of the smoothed model):",
            i.groups, i.segments
        );
    }
    for (system, modes, unc) in [
        ("accelerometer", &a.acc_modes, &i.acc),
        ("vision", &a.vis_modes, &i.vis),
    ] {
        for (k, (m, u)) in modes.iter().zip(unc).enumerate() {
            let mut parts = Vec::new();
            if let Some(f) = u.f_hz {
                parts.push(format!("f = {:.3} +- {:.3} Hz", m.f_hz, f.half_width()));
            }
            if let (Some(z), Some(iz)) = (u.damping_fit, u.damping) {
                parts.push(format!("damping = {z:.4} ({:.4} to {:.4})", iz.lo, iz.hi));
            }
            if let (Some(c), Some(ia)) = (u.smoothing, u.amplitude) {
                parts.push(format!(
                    "|FRF| at {:.3} Hz = {} ({} to {}) (|H1| {}, {:+.1} % by the window's \
                     smoothing)",
                    m.f_hz,
                    significant((ia.lo + ia.hi) / 2.0),
                    significant(ia.lo),
                    significant(ia.hi),
                    significant(m.amplitude),
                    100.0 * (c - 1.0)
                ));
            }
            if !parts.is_empty() {
                let _ = writeln!(s, "  {system} mode {}: {}", k + 1, parts.join(", "));
            }
        }
    }
    for n in &i.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    s
}

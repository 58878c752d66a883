//! The hits of an impact test found in the force record, and the blocks of force and response
//! they start (docs/method.md §3.13).
//!
//! * **Baseline and noise**: the force's median and `1.4826 MAD` (most samples are quiet).
//! * **Pulses**: runs where the force leaves the baseline by more than 5 % of the record's
//!   largest excursion (and 6 noise sd), merged across gaps shorter than the run itself, each
//!   widened to where it falls back to 1 % of its peak (or 3 noise sd).
//! * **Hits**: pulses grouped, a pulse starting within `double_gap_s` of the previous one's end
//!   joining its group. A group of more than one pulse is a **double hit**, named and left out;
//!   a pulse whose peak sample repeats three or more times in a row is **clipped** (the
//!   transducer or the ADC saturated), named and left out.
//! * **Blocks**: every hit's block has the same length, the shortest spacing between hits (the
//!   last: to the record's end), starting a fiftieth of it before its pulse (at most the first
//!   pulse's start).
//! * **Force window**: inside a block the force is kept from half a pulse width before its
//!   pulse to half a width after it, zero elsewhere (the noise between hits is not force).
//! * **Exponential window** `exp(-t / tau)` from the block's start, on force and response alike:
//!   the windowed record is exactly that of a structure whose poles are `p - 1 / tau`, so the
//!   damping it adds is removed from each pole afterwards ([`ExpWindow::pole_shift`]).

use vibcam_readers::bad_input;

/// The rules of hit finding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactRule {
    /// A pulse starting within this time after the previous one's end belongs to its hit.
    pub double_gap_s: f64,
    /// Longest block, s (none: the spacing of the hits).
    pub block_s: Option<f64>,
}

impl Default for ImpactRule {
    /// Pulses within 50 ms are one hit (a hammer's rebound), blocks as long as the spacing.
    fn default() -> Self {
        ImpactRule {
            double_gap_s: 0.05,
            block_s: None,
        }
    }
}

/// One pulse of the force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pulse {
    /// First sample above 1 % of its peak.
    pub start: usize,
    /// One past the last.
    pub end: usize,
    /// Peak excursion from the baseline (signed).
    pub peak: f64,
    /// Longest run of samples at the peak's value.
    pub flat: usize,
}

/// A hit and what became of it.
#[derive(Debug, Clone, PartialEq)]
pub struct Hit {
    /// Its pulses (more than one: a double hit).
    pub pulses: Vec<Pulse>,
    /// Why it is left out (`None`: used).
    pub left_out: Option<String>,
}

impl Hit {
    /// The first pulse.
    pub fn pulse(&self) -> &Pulse {
        &self.pulses[0]
    }
}

/// The hits of a force record and their blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct Hits {
    /// Baseline (median), in the force's unit.
    pub baseline: f64,
    /// Noise standard deviation (1.4826 MAD).
    pub noise_sd: f64,
    /// Every hit, in time order.
    pub hits: Vec<Hit>,
    /// Block length, samples.
    pub block: usize,
    /// Samples of a block before its pulse.
    pub pre: usize,
    /// Single-sample spikes of the force set aside (a glitch of the DAQ or a cable, not a
    /// hit: no hammer pulse is one sample wide), as sample indexes.
    pub spikes: Vec<usize>,
}

impl Hits {
    /// The used hits.
    pub fn used(&self) -> impl Iterator<Item = &Hit> {
        self.hits.iter().filter(|h| h.left_out.is_none())
    }

    /// The first sample of `hit`'s block.
    pub fn block_start(&self, hit: &Hit) -> usize {
        hit.pulse().start - self.pre
    }
}

/// The median of `v` (a copy sorted).
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// The single-sample spikes of `dev` (the excursions from the baseline): both neighbours below
/// a tenth of it, and it well above the noise. No hammer's pulse is one sample wide; a spike 100
/// times the hits would otherwise hide them below the pulses' threshold.
fn single_sample_spikes(dev: &[f64], noise_sd: f64) -> Vec<usize> {
    (0..dev.len())
        .filter(|&k| {
            let d = dev[k];
            let side = |j: Option<usize>| j.and_then(|j| dev.get(j)).is_none_or(|&n| n < 0.1 * d);
            d > 10.0 * noise_sd && side(k.checked_sub(1)) && side(Some(k + 1))
        })
        .collect()
}

/// Finds the hits of `force` (sampled at `fs_hz`; `name` names it in errors). Errors when there
/// is no pulse clearly above the noise, or no hit is left to use (each left-out hit named).
pub fn find(force: &[f64], fs_hz: f64, rule: ImpactRule, name: &str) -> anyhow::Result<Hits> {
    let baseline = median(force);
    let mut dev: Vec<f64> = force.iter().map(|v| (v - baseline).abs()).collect();
    let noise_sd = 1.4826 * median(&dev);
    let spikes = single_sample_spikes(&dev, noise_sd);
    for &k in &spikes {
        dev[k] = 0.0;
    }
    let level = dev.iter().fold(0.0f64, |a, &b| a.max(b));
    if !(level > 10.0 * noise_sd && level > 0.0) {
        return Err(bad_input(format!(
            "{name}: no impact found (the largest excursion, {level:.4}, is not 10 times the \
             noise's standard deviation {noise_sd:.4}); is this the force channel, and was the \
             structure hit?{}",
            if spikes.is_empty() {
                String::new()
            } else {
                format!(
                    " ({} single-sample spike(s) were set aside: a pulse one sample wide is a \
                     glitch, or a force sampled too slowly for the hammer's pulses)",
                    spikes.len()
                )
            }
        )));
    }
    let above = (0.05 * level).max(6.0 * noise_sd);
    let runs = runs_above(&dev, above);
    let pulses: Vec<Pulse> = runs
        .iter()
        .map(|&run| pulse_of(force, &dev, run, (baseline, noise_sd)))
        .collect();
    let mut hits = hits_of(pulses, (rule.double_gap_s * fs_hz).round() as usize);
    leave_out_bad_hits(&mut hits, baseline, fs_hz);
    let (pre, mut block) = spacing_block(&mut hits, force.len(), fs_hz, name)?;
    let width = hits
        .iter()
        .map(|h| h.pulses[0].end - h.pulses[0].start)
        .max()
        .unwrap_or(1);
    if let Some(b) = rule.block_s {
        let given = (b * fs_hz).round();
        let least = pre + 8 * width.max(4);
        if given < least as f64 {
            return Err(anyhow::Error::new(
                vibcam_common::setting::SpecError::setting(format!(
                    "$block_s {b}: {given} samples at {fs_hz} Hz, shorter than the {pre} samples \
                 kept before each pulse and 8 pulse widths after it ({least} samples, {:.6} s)",
                    least as f64 / fs_hz
                )),
            ));
        }
        block = block.min(given as usize);
    }
    if block < pre + 8 * width.max(4) {
        return Err(bad_input(format!(
            "{name}: the hits' blocks would be {block} samples, too short beside the pulses \
             ({width} samples): hits closer than the response takes to decay"
        )));
    }
    Ok(Hits {
        baseline,
        noise_sd,
        hits,
        block,
        pre,
        spikes,
    })
}

/// One block length for every hit: the shortest spacing between hits, and the last used hit's
/// rest of the record, unless that is less than half the spacing: then that hit is left out
/// rather than every block cut short. Returns the samples kept before each pulse and the block.
fn spacing_block(
    hits: &mut [Hit],
    len: usize,
    fs_hz: f64,
    name: &str,
) -> anyhow::Result<(usize, usize)> {
    let at = |i: usize| format!("{:.4} s", i as f64 / fs_hz);
    let starts: Vec<usize> = hits.iter().map(|h| h.pulses[0].start).collect();
    let between = starts.windows(2).map(|w| w[1] - w[0]).min();
    let last = starts[starts.len() - 1];
    let tail = len - last;
    let others_used = hits[..hits.len() - 1].iter().any(|h| h.left_out.is_none());
    let mut spacing = between.unwrap_or(tail);
    if let Some(h) = hits.last_mut().filter(|h| h.left_out.is_none()) {
        if others_used && between.is_some_and(|b| 2 * tail < b) {
            h.left_out = Some(format!(
                "hit {} at {}: the record ends {:.3} s after it, less than half the hits' \
                 spacing ({:.3} s)",
                starts.len(),
                at(last),
                tail as f64 / fs_hz,
                spacing as f64 / fs_hz
            ));
        } else {
            spacing = spacing.min(tail);
        }
    }
    if hits.iter().all(|h| h.left_out.is_some()) {
        let why: Vec<&str> = hits.iter().filter_map(|h| h.left_out.as_deref()).collect();
        return Err(bad_input(format!(
            "{name}: no hit can be used: {}",
            why.join("; ")
        )));
    }
    let pre = (spacing / 50).min(starts[0]);
    let mut block = spacing;
    if hits.last().is_some_and(|h| h.left_out.is_none()) {
        block = block.min(tail + pre);
    }
    Ok((pre, block))
}

/// The runs of `dev` above `above`, `(start, end)`; a run closer to the last than the last's
/// length (at least 2 samples) joins it.
fn runs_above(dev: &[f64], above: f64) -> Vec<(usize, usize)> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut k = 0;
    while k < dev.len() {
        if dev[k] > above {
            let s = k;
            while k < dev.len() && dev[k] > above {
                k += 1;
            }
            match runs.last_mut() {
                Some(last) if s - last.1 < (last.1 - last.0).max(2) => last.1 = k,
                _ => runs.push((s, k)),
            }
        } else {
            k += 1;
        }
    }
    runs
}

/// The pulse of a run `(s, e)`: its peak (the baseline removed), its edges where the force falls
/// to 1 % of the peak (at least 3 noise sd), and the longest run of samples at the peak.
fn pulse_of(
    force: &[f64],
    dev: &[f64],
    (s, e): (usize, usize),
    (baseline, noise_sd): (f64, f64),
) -> Pulse {
    let (mut ip, mut peak) = (s, 0.0f64);
    for (i, v) in force.iter().enumerate().take(e).skip(s) {
        if (v - baseline).abs() > peak.abs() {
            peak = v - baseline;
            ip = i;
        }
    }
    let edge = (0.01 * peak.abs()).max(3.0 * noise_sd);
    let mut start = s;
    while start > 0 && dev[start - 1] > edge {
        start -= 1;
    }
    let mut end = e;
    while end < dev.len() && dev[end] > edge {
        end += 1;
    }
    let top = force[ip];
    let tol = 1e-9 * peak.abs();
    let (mut flat, mut run) = (0usize, 0usize);
    for v in &force[start..end] {
        run = if (v - top).abs() <= tol { run + 1 } else { 0 };
        flat = flat.max(run);
    }
    Pulse {
        start,
        end,
        peak,
        flat,
    }
}

/// Pulses closer than `gap` samples after the last one's end are one hit (a double hit).
fn hits_of(pulses: Vec<Pulse>, gap: usize) -> Vec<Hit> {
    let mut hits: Vec<Hit> = Vec::new();
    for p in pulses {
        match hits.last_mut() {
            Some(h) if p.start <= h.pulses.last().map_or(0, |q| q.end) + gap => h.pulses.push(p),
            _ => hits.push(Hit {
                pulses: vec![p],
                left_out: None,
            }),
        }
    }
    hits
}

/// A double hit, a hit whose rise the record does not hold, a clipped hit: left out, and why.
fn leave_out_bad_hits(hits: &mut [Hit], baseline: f64, fs_hz: f64) {
    let at = |i: usize| format!("{:.4} s", i as f64 / fs_hz);
    for (i, h) in hits.iter_mut().enumerate() {
        let first = h.pulses[0];
        if let Some(second) = h.pulses.get(1) {
            h.left_out = Some(format!(
                "hit {} at {}: a double hit (a second pulse {:.1} ms after the first, {:.0} % of \
                 its peak)",
                i + 1,
                at(first.start),
                (second.start - first.start) as f64 / fs_hz * 1e3,
                100.0 * second.peak.abs() / first.peak.abs()
            ));
        } else if first.start == 0 {
            h.left_out = Some(format!(
                "hit {} at {}: the record starts inside its pulse (its rise is not recorded)",
                i + 1,
                at(first.start)
            ));
        } else if first.flat >= 2 {
            h.left_out = Some(format!(
                "hit {} at {}: the force is clipped ({} samples in a row at its peak {:.4}: the \
                 hammer's transducer or the ADC saturated)",
                i + 1,
                at(first.start),
                first.flat,
                first.peak + baseline
            ));
        }
    }
}

/// The force window of a block: the force from half a pulse width before the pulse to half a
/// width after, the baseline removed; zero elsewhere. `pulse` in block samples.
pub fn force_window(block: &[f64], baseline: f64, pulse: (usize, usize)) -> Vec<f64> {
    let width = pulse.1 - pulse.0;
    let lo = pulse.0.saturating_sub(width / 2);
    let hi = (pulse.1 + width / 2).min(block.len());
    block
        .iter()
        .enumerate()
        .map(|(i, v)| {
            if (lo..hi).contains(&i) {
                v - baseline
            } else {
                0.0
            }
        })
        .collect()
}

/// An exponential window `exp(-t / tau)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExpWindow {
    /// Time constant, s.
    pub tau_s: f64,
}

impl ExpWindow {
    /// The window whose value at the block's end (`block_s` after its start) is `end`.
    pub fn ending_at(end: f64, block_s: f64) -> ExpWindow {
        ExpWindow {
            tau_s: block_s / (1.0 / end).ln(),
        }
    }

    /// Its value `t_s` after the block's start.
    pub fn at(&self, t_s: f64) -> f64 {
        (-t_s / self.tau_s).exp()
    }

    /// What it adds to the real part of every pole, rad/s (`-1 / tau`); subtract it to undo.
    pub fn pole_shift(&self) -> f64 {
        -1.0 / self.tau_s
    }

    /// The damping ratio it adds to a lightly damped mode at `f_hz` (`1 / (tau w)`).
    pub fn added_damping(&self, f_hz: f64) -> f64 {
        1.0 / (self.tau_s * 2.0 * std::f64::consts::PI * f_hz)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(pulses: &[(usize, usize, f64)], n: usize) -> Vec<f64> {
        let mut f = vec![0.0; n];
        for &(s, w, peak) in pulses {
            for k in 0..=w {
                f[s + k] += peak * (std::f64::consts::PI * k as f64 / w as f64).sin();
            }
        }
        // a small deterministic noise
        for (k, v) in f.iter_mut().enumerate() {
            *v += 0.01 * ((k as f64 * 1.7).sin() + (k as f64 * 0.31).cos());
        }
        f
    }

    #[test]
    fn three_hits_one_double_one_clipped() {
        let fs = 10_000.0;
        let mut f = record(
            &[
                (1000, 20, 100.0),
                (11_000, 20, 80.0),
                (11_150, 20, 30.0),
                (21_000, 20, 120.0),
            ],
            40_000,
        );
        // clip the third hit at 90
        for v in &mut f[21_000..21_021] {
            *v = v.min(90.0);
        }
        let h = find(&f, fs, ImpactRule::default(), "force").unwrap();
        assert_eq!(h.hits.len(), 3);
        assert!(h.hits[0].left_out.is_none());
        let double = h.hits[1].left_out.as_deref().unwrap();
        assert!(double.contains("double hit"), "{double}");
        assert!(double.contains("15.0 ms"), "{double}");
        let clipped = h.hits[2].left_out.as_deref().unwrap();
        assert!(clipped.contains("clipped"), "{clipped}");
        assert_eq!(h.block, 10_000);
        assert_eq!(h.pre, 200);
        assert!(h.hits[0].pulse().start <= 1001 && h.hits[0].pulse().end >= 1019);
    }

    #[test]
    fn a_last_hit_close_to_the_record_end_is_left_out_not_every_block_cut() {
        let f = record(
            &[(1000, 20, 100.0), (11_000, 20, 100.0), (21_000, 20, 100.0)],
            23_000,
        );
        let h = find(&f, 10_000.0, ImpactRule::default(), "force").unwrap();
        let why = h.hits[2].left_out.as_deref().unwrap();
        assert!(why.contains("the record ends 0.200 s after it"), "{why}");
        assert_eq!(h.block, 10_000);
        assert_eq!(h.used().count(), 2);
    }

    #[test]
    fn no_pulse_and_no_usable_hit_are_errors() {
        let quiet: Vec<f64> = (0..1000).map(|k| (k as f64 * 1.3).sin()).collect();
        let e = find(&quiet, 1000.0, ImpactRule::default(), "ch").unwrap_err();
        assert!(e.to_string().contains("no impact found"), "{e}");
        let f = record(&[(1000, 20, 100.0), (1100, 20, 50.0)], 5000);
        let e = find(&f, 10_000.0, ImpactRule::default(), "ch").unwrap_err();
        assert!(e.to_string().contains("no hit can be used"), "{e}");
    }

    #[test]
    fn a_spike_a_cut_first_pulse_and_a_two_sample_flat_top_are_named() {
        let fs = 10_000.0;
        // a record that starts inside its first pulse (its rise missing), two good hits, a
        // third clipped flat over two samples only, and a one-sample spike 100 times the hits
        let mut f = record(
            &[
                (0, 20, 0.0),
                (11_000, 20, 100.0),
                (21_000, 20, 100.0),
                (31_000, 20, 100.0),
            ],
            42_000,
        );
        for (k, v) in f.iter_mut().take(10).enumerate() {
            *v += 100.0 * (std::f64::consts::PI * (k + 10) as f64 / 20.0).sin();
        }
        let top = f[31_010].max(f[31_009]);
        f[31_009] = top;
        f[31_010] = top;
        f[5_000] = 10_000.0;
        let h = find(&f, fs, ImpactRule::default(), "force").unwrap();
        assert_eq!(h.spikes, vec![5_000]);
        assert_eq!(h.hits.len(), 4, "{:?}", h.hits);
        let cut = h.hits[0].left_out.as_deref().unwrap();
        assert!(cut.contains("starts inside its pulse"), "{cut}");
        assert!(h.hits[1].left_out.is_none() && h.hits[2].left_out.is_none());
        let clipped = h.hits[3].left_out.as_deref().unwrap();
        assert!(clipped.contains("clipped (2 samples"), "{clipped}");
    }

    #[test]
    fn a_block_shorter_than_the_pre_trigger_is_refused_naming_the_setting() {
        let f = record(&[(10_000, 20, 100.0), (40_000, 20, 100.0)], 70_000);
        let rule = ImpactRule {
            block_s: Some(0.01),
            ..ImpactRule::default()
        };
        let e = find(&f, 10_000.0, rule, "force").unwrap_err();
        let m = vibcam_common::setting::message(&e, vibcam_common::setting::Naming::Cli);
        assert!(
            m.contains("--block-s 0.01") && m.contains("before each pulse"),
            "{m}"
        );
    }

    #[test]
    fn the_exponential_window_shifts_a_pole_by_one_over_tau() {
        let w = ExpWindow::ending_at(0.01, 2.0);
        assert!((w.at(2.0) - 0.01).abs() < 1e-12);
        assert!((w.pole_shift() + 100f64.ln() / 2.0).abs() < 1e-12);
    }
}

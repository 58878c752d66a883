//! Free decays: a structure pulled (or hit) and let go rings down at its modes. The record's
//! free decays are found from its motion's energy ([`find_decays`]); each decay is a sum of
//! damped sinusoids with the structure's poles, so the output correlations taken over one
//! fixed range of times, `R_l = sum_t y(t + l) y(t)^T`, are sums of the same exponentials in
//! the lag `l` (whatever the initial conditions): the block Toeplitz matrix of SSI-cov
//! ([`super::ssi::poles_of`]) built from them gives the poles (the eigensystem realisation of
//! the decays' correlations, docs/method.md §3.12). The decays' correlations are added, so
//! every decay and every target speaks for the same poles; each decay is also identified
//! alone, so that a frequency that depends on the amplitude is shown, not averaged away.

use super::cluster::{self, ClusterRule, SsiMode};
use super::ssi::{self, Pole, SsiRule};
use nalgebra::DMatrix;

/// One free decay of the record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Decay {
    /// Its first sample (where the motion's energy peaks after the release or hit).
    pub start: usize,
    /// One past its last sample.
    pub end: usize,
    /// Its amplitude: the largest excursion from its mean in its first quarter, RMS over the
    /// channels (the record's unit).
    pub amplitude: f64,
}

/// The fewest samples a decay needs.
pub const MIN_DECAY_SAMPLES: usize = 16;

/// How far the motion's energy must rise above the record's quiet level for a decay to start
/// (energy ratio: 30 dB). A stationary Gaussian response's energy envelope is about
/// exponentially distributed: its largest value over `N` independent stretches is `ln N` times
/// its mean and its 10th percentile 0.105 times it, so 20 dB (100) is reached by a long record
/// (`N` near 4e4) while 30 dB (1000) needs `ln N` near 105: never.
const ONSET_RATIO: f64 = 1000.0;

/// The record's quiet level: this quantile of the smoothed energy.
const QUIET_QUANTILE: f64 = 0.1;

/// A decay ends where its energy has fallen to this multiple of the quiet level.
const END_RATIO: f64 = 4.0;

/// A decay's energy must fall by this ratio from its start to its end (20 dB).
const FALL_RATIO: f64 = 100.0;

/// The free decays in `channels` (one record per target): where the energy of the motion's
/// sample-to-sample change (summed over the targets, smoothed over 5 samples) rises 30 dB above
/// the record's quiet level (its 10th percentile) to a peak, the decay runs from the peak until
/// the energy's envelope falls back to 4x the quiet level, or rises 6 dB over its lowest since
/// the peak (a new pull or hit), or the record ends; a decay shorter than [`MIN_DECAY_SAMPLES`] or falling less than 20 dB is not
/// one. A stationary response (no such rise and fall) has none.
pub fn find_decays(channels: &[Vec<f64>]) -> Vec<Decay> {
    let n = channels.first().map_or(0, Vec::len);
    if n < MIN_DECAY_SAMPLES + 2 {
        return Vec::new();
    }
    let (s, env, quiet) = energy(channels);
    let mut decays = Vec::new();
    let mut t = 0usize;
    while t < s.len() {
        if s[t] < ONSET_RATIO * quiet {
            t += 1;
            continue;
        }
        // the peak of this rise: the largest change within a window of it, then uphill
        let reach = (t + 2 * ENVELOPE + 1).min(s.len());
        let mut peak = (t..reach)
            .max_by(|&i, &j| s[i].total_cmp(&s[j]))
            .unwrap_or(t);
        while peak + 1 < s.len() && s[peak + 1] >= s[peak] {
            peak += 1;
        }
        // the end: the envelope back at the quiet level, or rising again 6 dB over its lowest
        // since the peak and above the onset level (a new pull or hit, whatever its size)
        let mut end = peak + 1;
        let mut lowest = env[peak];
        while end < s.len() {
            if env[end] <= END_RATIO * quiet {
                break;
            }
            if env[end] > RISE_RATIO * lowest && env[end] >= ONSET_RATIO * quiet {
                break;
            }
            lowest = lowest.min(env[end]);
            end += 1;
        }
        // samples of the positions: the change s[t] is between samples t and t + 1
        let (start, stop) = (peak + 1, (end + 1).min(n));
        if stop - start >= MIN_DECAY_SAMPLES && s[peak] >= FALL_RATIO * lowest.max(quiet) {
            decays.push(Decay {
                start,
                end: stop,
                amplitude: amplitude(channels, start, stop),
            });
        }
        t = end.max(peak + 1);
    }
    decays
}

/// Half-width of the envelope's window, samples: a turning point of a vibration slower than
/// the frame rate / 32 (where the change is momentarily nil) does not end a decay.
const ENVELOPE: usize = 8;

/// A rise of the envelope by this ratio over its lowest since the decay's peak is a new pull or
/// hit (6 dB of energy).
const RISE_RATIO: f64 = 4.0;

/// The energy of the motion's sample-to-sample change summed over the channels (a slow pull
/// moves little from one sample to the next, a free vibration much), averaged over 5 samples;
/// its envelope (the largest over +-[`ENVELOPE`] samples); the record's quiet level.
fn energy(channels: &[Vec<f64>]) -> (Vec<f64>, Vec<f64>, f64) {
    let n = channels.first().map_or(0, Vec::len);
    let e: Vec<f64> = (1..n)
        .map(|t| channels.iter().map(|c| (c[t] - c[t - 1]).powi(2)).sum())
        .collect();
    let s: Vec<f64> = (0..e.len())
        .map(|t| {
            let (a, b) = (t.saturating_sub(2), (t + 3).min(e.len()));
            e[a..b].iter().sum::<f64>() / (b - a) as f64
        })
        .collect();
    let env: Vec<f64> = (0..s.len())
        .map(|t| {
            let (a, b) = (t.saturating_sub(ENVELOPE), (t + ENVELOPE + 1).min(s.len()));
            s[a..b].iter().copied().fold(0.0f64, f64::max)
        })
        .collect();
    let mut sorted = s.clone();
    sorted.sort_by(f64::total_cmp);
    let quiet =
        sorted[((sorted.len() - 1) as f64 * QUIET_QUANTILE) as usize].max(f64::MIN_POSITIVE);
    (s, env, quiet)
}

/// A decay's amplitude: the largest excursion from its mean in its first quarter, RMS over
/// the targets (its start is where the motion is fastest, not furthest).
fn amplitude(channels: &[Vec<f64>], start: usize, stop: usize) -> f64 {
    let first = start + ((stop - start) / 4).max(4);
    (channels
        .iter()
        .map(|c| {
            let m = c[start..stop].iter().sum::<f64>() / (stop - start) as f64;
            c[start..first]
                .iter()
                .map(|v| (v - m).powi(2))
                .fold(0.0f64, f64::max)
        })
        .sum::<f64>()
        / channels.len() as f64)
        .sqrt()
}

/// Block rows for decays of these lengths: a quarter of the shortest, 2 to 20.
pub fn block_rows(decays: &[Decay]) -> usize {
    let shortest = decays.iter().map(|d| d.end - d.start).min().unwrap_or(0);
    (shortest / 4).clamp(2, 20)
}

/// The correlations `R_l`, `l = 0 .. 2i`, of the decays (each over one fixed range of its
/// times, its mean removed), added over the decays.
pub fn correlations(channels: &[Vec<f64>], decays: &[Decay], i: usize) -> Vec<DMatrix<f64>> {
    let k = channels.len();
    let lags = 2 * i;
    let mut r = vec![DMatrix::<f64>::zeros(k, k); lags];
    for d in decays {
        let len = d.end - d.start;
        if len <= lags {
            continue;
        }
        let y: Vec<Vec<f64>> = channels
            .iter()
            .map(|c| {
                let seg = &c[d.start..d.end];
                let m = seg.iter().sum::<f64>() / len as f64;
                seg.iter().map(|v| v - m).collect()
            })
            .collect();
        let times = len - lags;
        for (l, rl) in r.iter_mut().enumerate() {
            for a in 0..k {
                for b in 0..k {
                    rl[(a, b)] += y[a][l..l + times]
                        .iter()
                        .zip(&y[b][..times])
                        .map(|(p, q)| p * q)
                        .sum::<f64>();
                }
            }
        }
    }
    r
}

/// The poles of the decays at `fs_hz` for `rule` (its block rows used as given), then the
/// stable ones clustered into modes by `clusters`: `(poles, kept, rejected with reasons)`.
pub fn modes(
    channels: &[Vec<f64>],
    decays: &[Decay],
    fs_hz: f64,
    rule: SsiRule,
    clusters: ClusterRule,
) -> anyhow::Result<(Vec<Pole>, Vec<SsiMode>, Vec<cluster::Rejected>)> {
    let r = correlations(channels, decays, rule.block_rows);
    let (poles, _) = ssi::poles_of(&r, fs_hz, rule)?;
    let (kept, rejected) = cluster::cluster(&poles, clusters);
    Ok((poles, kept, rejected))
}

/// The rule of a decays' identification at `fs_hz`: block rows from the decays, orders up to
/// 40 (a decay that rings at another frequency in a larger swing makes fewer orders agree),
/// stable at 1 % in frequency, 5 % in damping and MAC 0.98 as SSI-cov's, damping up to 30 %
/// (a structure let go rings down fast), from `f_min_hz` to the Nyquist frequency.
pub fn rule(decays: &[Decay], fs_hz: f64, f_min_hz: f64) -> SsiRule {
    SsiRule {
        block_rows: block_rows(decays),
        max_order: 40,
        df_max: 0.01,
        dz_max: 0.05,
        mac_min: 0.98,
        zeta_max: 0.3,
        f_range_hz: (f_min_hz, fs_hz / 2.0),
        kind: ssi::SsiKind::Cov,
    }
}

/// The modes of the record's free decays ([`super::Method::Decay`]) for `s` (its bands, or
/// every stable cluster without them; clusters too small or incoherent go to `rejected`):
/// each mode's evidence names what each decay alone gives (its start, amplitude, frequency and
/// damping: a frequency that moves with the amplitude is seen there), and with two decays or
/// more its 95 % intervals come from the jackknife over the decays (each left out in turn).
pub fn decay_modes(
    channels: &[Vec<f64>],
    decays: &[Decay],
    s: &super::OmaSettings,
    notes: &mut Vec<String>,
    rejected: &mut Vec<String>,
) -> anyhow::Result<Vec<super::OmaMode>> {
    let of = |some: &[Decay]| -> Vec<SsiMode> {
        let rule = rule(some, s.fs_hz, s.ssi.f_range_hz.0);
        modes(channels, some, s.fs_hz, rule, s.cluster)
            .map(|m| m.1)
            .unwrap_or_default()
    };
    let rule = rule(decays, s.fs_hz, s.ssi.f_range_hz.0);
    let (_, kept, dropped) = modes(channels, decays, s.fs_hz, rule, s.cluster)?;
    let chosen = cluster::chosen(
        (&kept, &dropped),
        &s.bands,
        ("decay", "free decays"),
        notes,
        rejected,
    );
    // what each decay alone gives, and the decays without each one (the jackknife)
    let alone: Vec<Vec<SsiMode>> = decays.iter().map(|d| of(std::slice::from_ref(d))).collect();
    let without: Vec<Vec<SsiMode>> = match decays.len() {
        0 | 1 => Vec::new(),
        n => (0..n)
            .map(|i| {
                let rest: Vec<Decay> = (0..n).filter(|j| *j != i).map(|j| decays[j]).collect();
                of(&rest)
            })
            .collect(),
    };
    Ok(chosen
        .into_iter()
        .map(|(n, band, c)| super::OmaMode {
            method: super::Method::Decay,
            mode: n,
            band_hz: band.map(|b| s.bands[b]),
            f_hz: c.f_hz,
            amplitude: None,
            damping: Some(c.damping),
            shape: crate::modal::normalise_shape(&c.shape),
            evidence: evidence(c, decays, &alone),
            uncertainty: jackknife(c, &without),
        })
        .collect())
}

/// The frequency and damping of the cluster in `list` nearest `f` (within 5 %).
fn near(list: &[SsiMode], f: f64) -> Option<(f64, f64)> {
    list.iter()
        .filter(|c| (c.f_hz - f).abs() <= 0.05 * f)
        .min_by(|a, b| (a.f_hz - f).abs().total_cmp(&(b.f_hz - f).abs()))
        .map(|c| (c.f_hz, c.damping))
}

/// A mode's evidence: its cluster, then what each decay alone gives.
fn evidence(c: &SsiMode, decays: &[Decay], alone: &[Vec<SsiMode>]) -> String {
    let each: Vec<String> = decays
        .iter()
        .zip(alone)
        .enumerate()
        .map(|(i, (d, a))| match near(a, c.f_hz) {
            Some((f, z)) => format!(
                "decay {} (samples {}-{}, amplitude {:.3e}): {f:.4} Hz, damping {z:.4}",
                i + 1,
                d.start + 1,
                d.end,
                d.amplitude
            ),
            None => format!("decay {}: not found alone", i + 1),
        })
        .collect();
    format!(
        "{} free decay(s) together, {}; {}",
        decays.len(),
        super::modes::cluster_evidence(c),
        each.join("; ")
    )
}

/// The jackknife over the decays: each left out in turn (`without`), the mode found again
/// near its frequency; none when a replicate misses it or there are fewer than two.
fn jackknife(c: &SsiMode, without: &[Vec<SsiMode>]) -> super::uncertainty::Uncertainty {
    let reps: Option<Vec<(f64, f64)>> = without.iter().map(|w| near(w, c.f_hz)).collect();
    match reps.filter(|r| r.len() >= 2) {
        Some(r) => {
            let fs: Vec<f64> = r.iter().map(|x| x.0).collect();
            let zs: Vec<f64> = r.iter().map(|x| x.1).collect();
            super::uncertainty::Uncertainty {
                f_hz: super::uncertainty::jackknife(c.f_hz, &fs),
                damping: super::uncertainty::jackknife(c.damping, &zs),
                ..Default::default()
            }
        }
        None => Default::default(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// `k` targets ringing down in two modes (`f`, `zeta`, shape) after each of `starts`, at
    /// rest (with noise) before the first, at `fs` Hz for `n` samples.
    fn decays_of(
        modes: &[(f64, f64, Vec<f64>)],
        starts: &[(usize, f64)],
        fs: f64,
        n: usize,
        noise: f64,
    ) -> Vec<Vec<f64>> {
        let k = modes[0].2.len();
        (0..k)
            .map(|j| {
                let e = vibcam_common::testing::gaussian_noise(7 + j as u64, n);
                (0..n)
                    .map(|t| {
                        let mut v = noise * e[t];
                        // each release restarts the ring-down from its own amplitude
                        if let Some(&(s, a)) = starts.iter().rev().find(|(s, _)| t >= *s) {
                            let u = (t - s) as f64 / fs;
                            for (f, z, shape) in modes {
                                let w = TAU * f;
                                let wd = w * (1.0 - z * z).sqrt();
                                v += a * shape[j] * (-z * w * u).exp() * (wd * u).cos();
                            }
                        }
                        v
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn two_decays_are_found_and_their_poles_are_the_structures() {
        let fs = 23.0;
        let modes_true = vec![
            (3.6, 0.08, vec![1.0, 0.75, 0.5, 0.25]),
            (7.9, 0.03, vec![0.6, -0.4, -0.7, 0.5]),
        ];
        let ch = decays_of(&modes_true, &[(20, 100.0), (110, 60.0)], fs, 200, 0.2);
        let decays = find_decays(&ch);
        assert_eq!(decays.len(), 2, "{decays:?}");
        assert!(decays[0].start.abs_diff(20) <= 2 && decays[1].start.abs_diff(110) <= 2);
        assert!(decays[0].end <= 111, "{decays:?}");
        let (_, kept, rejected) = modes(
            &ch,
            &decays,
            fs,
            rule(&decays, fs, 0.5),
            ClusterRule::default(),
        )
        .unwrap();
        for (f, z, _) in &modes_true {
            let m = kept
                .iter()
                .find(|c| (c.f_hz - f).abs() < 0.02 * f)
                .unwrap_or_else(|| panic!("no mode at {f} Hz: {kept:?} {rejected:?}"));
            assert!(
                (m.damping - z).abs() < 0.1 * z,
                "{f} Hz: damping {}",
                m.damping
            );
        }
    }

    #[test]
    fn a_decay_alone_shorter_than_a_segment_is_analysed_and_a_short_stationary_record_refused() {
        let fs = 23.0;
        let welch = vibcam_chain::frf::WelchSettings::default();
        // 54 samples: one release (before: refused as shorter than one segment of 64)
        let ch = decays_of(
            &[(3.6, 0.08, vec![1.0, 0.6, 0.3])],
            &[(3, 100.0)],
            fs,
            54,
            0.1,
        );
        let s = super::super::segment_settings(fs, &ch, &welch, "the record").unwrap();
        let r = super::super::analyze(&ch, &s).unwrap();
        assert_eq!(r.decays.len(), 1);
        let m = r
            .modes
            .iter()
            .find(|m| m.method == super::super::Method::Decay)
            .unwrap_or_else(|| panic!("{:?}", r.modes));
        assert!((m.f_hz - 3.6).abs() < 0.01 * 3.6, "{}", m.f_hz);
        assert!(
            (m.damping.unwrap() - 0.08).abs() < 0.1 * 0.08,
            "{:?}",
            m.damping
        );
        // 54 samples of noise: no decay, and too short for the spectra
        let noise: Vec<Vec<f64>> = (0..3)
            .map(|j| vibcam_common::testing::gaussian_noise(11 + j, 54))
            .collect();
        let e = super::super::segment_settings(fs, &noise, &welch, "the record").unwrap_err();
        assert!(e.to_string().contains("no free decay"), "{e}");
    }

    #[test]
    fn a_hand_pulled_frame_at_a_slow_frame_rate_gives_each_decays_frequency() {
        // the lab's commonest test as a phone films it: 22.7 fps, a 7 Hz storey mode (3.2
        // samples a cycle), damping 0.089, pulled slowly by hand twice and let go; 28 targets
        // with 0.05 px of tracking noise; the joint slips more in the larger swing, so the two
        // decays ring at 7.03 and 7.22 Hz (a second mode at 2.4 Hz, 2 %, weakly excited)
        let fs = 22.7;
        let k = 28;
        let n = 202;
        let shape: Vec<f64> = (0..k).map(|j| 1.0 - (j / 7) as f64 * 0.25).collect();
        let releases = [(40usize, 35usize, 40.0, 7.03), (120, 54, 25.0, 7.22)];
        let ch: Vec<Vec<f64>> = (0..k)
            .map(|j| {
                let e = vibcam_common::testing::gaussian_noise(100 + j as u64, n);
                (0..n)
                    .map(|t| {
                        let mut v = 0.05 * e[t];
                        for &(at, _, a, f) in &releases {
                            // a pull over 1 s before the release, then the free decay
                            let pull = (22.7f64).round() as usize;
                            if t + pull >= at && t < at {
                                v += a * shape[j] * (t + pull - at) as f64 / pull as f64;
                            } else if t >= at {
                                let u = (t - at) as f64 / fs;
                                let w = TAU * f;
                                let z = 0.089;
                                v += a
                                    * shape[j]
                                    * (-z * w * u).exp()
                                    * (w * (1.0 - z * z).sqrt() * u).cos();
                                v +=
                                    0.1 * a * (-0.02 * TAU * 2.4 * u).exp() * (TAU * 2.4 * u).sin();
                            }
                        }
                        v
                    })
                    .collect()
            })
            .collect();
        let decays = find_decays(&ch);
        assert_eq!(decays.len(), 2, "{decays:?}");
        let welch = vibcam_chain::frf::WelchSettings::default();
        let s = super::super::segment_settings(fs, &ch, &welch, "the record").unwrap();
        let r = super::super::analyze(&ch, &s).unwrap();
        let m = r
            .modes
            .iter()
            .find(|m| m.method == super::super::Method::Decay && (m.f_hz - 7.1).abs() < 0.4)
            .unwrap_or_else(|| panic!("{:#?} {:#?}", r.rejected, r.decays));
        // together: between the two decays' frequencies; each alone: its own within 1 %
        assert!(m.f_hz > 7.0 && m.f_hz < 7.25, "{}", m.f_hz);
        assert!(
            (m.damping.unwrap() - 0.089).abs() < 0.25 * 0.089,
            "{:?}",
            m.damping
        );
        for f in ["7.03", "7.22"] {
            let want: f64 = f.parse().unwrap();
            let near = m.evidence.split("; decay ").skip(1).any(|d| {
                d.split(": ")
                    .nth(1)
                    .and_then(|v| v.split(' ').next())
                    .and_then(|v| v.parse::<f64>().ok())
                    .is_some_and(|got| (got - want).abs() < 0.01 * want)
            });
            assert!(near, "no decay at {f} Hz alone: {}", m.evidence);
        }
    }

    #[test]
    fn a_stationary_response_holds_no_decay() {
        // a random response: white noise through a 5 Hz resonator (damping 0.5 %) at 50 Hz,
        // 200 minutes: the energy's largest excursion grows with the record's length (such a
        // record reaches about 21 dB over its 10th percentile: the onset is 30 dB)
        let e = vibcam_common::testing::gaussian_noise(3, 600_000);
        let (fs, f, z) = (50.0, 5.0, 0.005);
        let w = TAU * f / fs;
        let (a1, a2) = (
            2.0 * (-z * w).exp() * (w * (1.0 - z * z).sqrt()).cos(),
            -(-2.0 * z * w).exp(),
        );
        let mut y = vec![0.0f64; 600_000];
        for t in 2..y.len() {
            y[t] = a1 * y[t - 1] + a2 * y[t - 2] + e[t];
        }
        let ch = vec![y.clone(), y.iter().map(|v| 0.5 * v).collect()];
        assert!(find_decays(&ch).is_empty());
    }
}

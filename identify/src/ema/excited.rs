//! What the hits of an impact test excited, line by line (docs/method.md §3.13): the band where
//! the responses stand above their noise, whether they decayed within the block, and which of
//! two sets of responses (a camera's y and x) the hits moved.
//!
//! Each used hit's block after the pulse is cut into quarters; the first quarter (**early**) and
//! the last (**late**) are Hann-windowed, their power summed over responses and hits and
//! smoothed over 5 lines. A response to a hit decays; noise and stationary interference (a
//! lamp's flicker, the camera's own lines) do not. So a line is **excited** where the early power
//! stands 10 dB above the noise floor (the median of the late power over the band) and 6 dB above
//! the late power there, or, when the record holds a quarter's worth before the pulse, 6 dB
//! above the power **before** the hit (a mode too lightly damped to decay within the block is
//! still the hit's). With one hit there is no coherence to tell signal from noise, and a camera's
//! pre-trigger is often a few frames: the decay is what the record holds.

use super::impact::Hits;

/// Early power over the noise floor for a line to be excited, dB.
pub const ABOVE_FLOOR_DB: f64 = 10.0;
/// Early power over late power for a line to be excited (it decays), dB.
pub const DECAY_DB: f64 = 6.0;
/// The band from the data reaches this factor beyond the excited lines on each side.
pub const MARGIN: f64 = 1.25;

/// What the hits excited.
#[derive(Debug, Clone, PartialEq)]
pub struct Excited {
    /// The lowest and highest excited line, Hz (none: no line stands out).
    pub span_hz: Option<(f64, f64)>,
    /// Excited lines.
    pub lines: usize,
    /// Over the excited lines, the amplitude of the late quarter (its noise floor taken away)
    /// relative to the early: what of the response is left at the block's end.
    pub undecayed: f64,
    /// The excited line where most is left at the end, Hz.
    pub undecayed_at_hz: Option<f64>,
    /// The strongest excited line's early power over the noise floor, dB (0 without one).
    pub peak_snr_db: f64,
    /// The summed early power over the floor across the excited lines (a score of how much
    /// the hits moved these responses above their noise).
    pub score: f64,
}

impl Excited {
    /// The band analysed: the excited lines widened by [`MARGIN`], inside `outer`; `None`
    /// without excited lines.
    pub fn band(&self, outer: (f64, f64)) -> Option<(f64, f64)> {
        let (lo, hi) = self.span_hz?;
        let band = ((lo / MARGIN).max(outer.0), (hi * MARGIN).min(outer.1));
        (band.1 > band.0).then_some(band)
    }
}

/// Hann-windowed power of `x`, its own mean removed, added into `acc`.
fn add_power(
    x: &[f64],
    win: &[f64],
    fft: &std::sync::Arc<dyn vibcam_fft::RealToComplex<f64>>,
    acc: &mut [f64],
) {
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let mut buf: Vec<f64> = x.iter().zip(win).map(|(v, w)| (v - mean) * w).collect();
    let mut out = fft.make_output_vec();
    if fft.process(&mut buf, &mut out).is_ok() {
        for (a, c) in acc.iter_mut().zip(&out) {
            *a += c.norm_sqr();
        }
    }
}

/// 5-line moving average (fewer lines at the ends).
fn smooth(p: &[f64]) -> Vec<f64> {
    (0..p.len())
        .map(|k| {
            let s = &p[k.saturating_sub(2)..(k + 3).min(p.len())];
            s.iter().sum::<f64>() / s.len() as f64
        })
        .collect()
}

/// Power per line of each quarter: early and late after the pulse, and before it (`None`
/// when the pre-trigger is shorter than a quarter).
struct Quarters {
    freq: Vec<f64>,
    early: Vec<f64>,
    late: Vec<f64>,
    before: Option<Vec<f64>>,
}

/// The [`Quarters`] of `responses` around each used hit of `hits`, smoothed; `None` when the
/// block after the pulse is under 64 samples.
fn quarters<R: AsRef<[f64]>>(responses: &[R], hits: &Hits, fs_hz: f64) -> Option<Quarters> {
    let after = hits.block.saturating_sub(hits.pre);
    let q = after / 4;
    if q < 16 || responses.is_empty() {
        return None;
    }
    let fft = vibcam_fft::RealPlanner::new().forward(q);
    let win: Vec<f64> = (0..q)
        .map(|i| {
            (std::f64::consts::PI * (i as f64 + 0.5) / q as f64)
                .sin()
                .powi(2)
        })
        .collect();
    let lines = q / 2 + 1;
    let (mut early, mut late, mut before) = (vec![0.0; lines], vec![0.0; lines], vec![0.0; lines]);
    for hit in hits.used() {
        let s = hits.block_start(hit) + hits.pre;
        for x in responses.iter().map(AsRef::as_ref) {
            if s + after > x.len() {
                continue;
            }
            add_power(&x[s..s + q], &win, &fft, &mut early);
            add_power(&x[s + after - q..s + after], &win, &fft, &mut late);
            if hits.pre >= q {
                add_power(&x[s - q..s], &win, &fft, &mut before);
            }
        }
    }
    Some(Quarters {
        freq: (0..lines).map(|k| k as f64 * fs_hz / q as f64).collect(),
        early: smooth(&early),
        late: smooth(&late),
        before: (hits.pre >= q).then(|| smooth(&before)),
    })
}

/// What the hits of `hits` excited in `responses` (at `fs_hz`) between `outer.0` and
/// `outer.1` Hz; `None` when the blocks are too short to tell (under 64 samples after the
/// pulse) or the band holds no line.
pub fn excited<R: AsRef<[f64]>>(
    responses: &[R],
    hits: &Hits,
    fs_hz: f64,
    outer: (f64, f64),
) -> Option<Excited> {
    let Quarters {
        freq,
        early,
        late,
        before,
    } = quarters(responses, hits, fs_hz)?;
    let inside: Vec<usize> = (0..freq.len())
        .filter(|&k| freq[k] >= outer.0 && freq[k] <= outer.1)
        .collect();
    let mut floors: Vec<f64> = inside.iter().map(|&k| late[k]).collect();
    if floors.is_empty() {
        return None;
    }
    floors.sort_by(f64::total_cmp);
    let floor = floors[floors.len() / 2].max(f64::MIN_POSITIVE);
    let (above, decay) = (
        10f64.powf(ABOVE_FLOOR_DB / 10.0),
        10f64.powf(DECAY_DB / 10.0),
    );
    let hit: Vec<usize> = inside
        .into_iter()
        .filter(|&k| {
            let new = early[k] > decay * late[k]
                || before.as_ref().is_some_and(|b| early[k] > decay * b[k]);
            early[k] > above * floor && new
        })
        .collect();
    let (mut e, mut l, mut score, mut peak) = (0.0, 0.0, 0.0, 0.0f64);
    let mut worst: Option<(f64, f64)> = None;
    for &k in &hit {
        let left = (late[k] - floor).max(0.0);
        e += early[k];
        l += left;
        score += early[k] / floor;
        peak = peak.max(early[k] / floor);
        if worst.is_none_or(|(w, _)| left > w) {
            worst = Some((left, freq[k]));
        }
    }
    Some(Excited {
        span_hz: hit
            .first()
            .map(|&a| (freq[a], freq[*hit.last().unwrap_or(&a)])),
        lines: hit.len(),
        undecayed: if e > 0.0 { (l / e).sqrt() } else { 0.0 },
        undecayed_at_hz: worst.filter(|w| w.0 > 0.0).map(|w| w.1),
        peak_snr_db: if peak > 0.0 { 10.0 * peak.log10() } else { 0.0 },
        score,
    })
}

/// Standard deviations above the noise (from the samples before the pulse) at which a response
/// has started to move.
pub const ONSET_SIGMAS: f64 = 5.0;
/// Samples a response must stay above [`ONSET_SIGMAS`] for its onset.
pub const ONSET_HOLD: usize = 8;

/// Median of `v` (sorted in place); `None` when empty.
fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then(|| v[v.len() / 2])
}

/// How long after each used hit's pulse the responses start to move, s: per response, the
/// first sample from which it stays [`ONSET_SIGMAS`] noise deviations (1.4826 MAD of the
/// samples before the pulse) off their mean for [`ONSET_HOLD`] samples;
/// the median over responses and hits. A structure answers its hit at once: an onset well after
/// the pulse says the responses' record began earlier than the force's. `None` without a
/// pre-trigger of 16 samples or an onset in the block.
pub fn onset_lag_s(responses: &[Vec<f64>], hits: &Hits, fs_hz: f64) -> Option<f64> {
    if hits.pre < 16 {
        return None;
    }
    let mut lags = Vec::new();
    for hit in hits.used() {
        let (s, p) = (hits.block_start(hit), hit.pulse().start);
        for x in responses {
            if s + hits.block > x.len() {
                continue;
            }
            let pre = &x[s..p];
            let mean = pre.iter().sum::<f64>() / pre.len() as f64;
            let mut d: Vec<f64> = pre.iter().map(|v| (v - mean).abs()).collect();
            let Some(mad) = median(&mut d) else { continue };
            let sd = 1.4826 * mad;
            if sd.is_nan() || sd <= 0.0 {
                continue;
            }
            let off = |i: usize| (x[i] - mean).abs() > ONSET_SIGMAS * sd;
            let end = s + hits.block - ONSET_HOLD;
            if let Some(i) = (p..end).find(|&i| (i..i + ONSET_HOLD).all(off)) {
                lags.push((i - p) as f64 / fs_hz);
            }
        }
    }
    median(&mut lags)
}

/// Coherence from which a line of a continuous test counts as measured: the median over the
/// responses of the ordinary coherence with the force, over 5 lines.
pub const COHERENT: f64 = 0.8;
/// Fewest Welch segments for the coherence to tell signal from noise (with one, every line's
/// is 1).
pub const COHERENCE_SEGMENTS: usize = 8;

/// The lines of a continuous test where the responses follow the force: the lowest and highest
/// line within `outer` whose median coherence over the responses (over 5 lines) is at least
/// [`COHERENT`], and how many lines are; `None` when no line is. Outside the force's band (a
/// shaker's) or where the responses are their noise the coherence falls.
pub fn coherent_span(
    freq_hz: &[f64],
    coherence: &[Vec<f64>],
    outer: (f64, f64),
) -> Option<(f64, f64, usize)> {
    let per_line: Vec<f64> = (0..freq_hz.len())
        .map(|k| {
            let mut at: Vec<f64> = coherence.iter().filter_map(|c| c.get(k).copied()).collect();
            median(&mut at).unwrap_or(0.0)
        })
        .collect();
    let smoothed = smooth(&per_line);
    let coherent: Vec<f64> = freq_hz
        .iter()
        .zip(&smoothed)
        .filter(|(f, c)| **f >= outer.0 && **f <= outer.1 && **c >= COHERENT)
        .map(|(f, _)| *f)
        .collect();
    Some((*coherent.first()?, *coherent.last()?, coherent.len()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ema::impact::{find, ImpactRule};
    use vibcam_common::testing::gaussian_noise;

    /// A hit at 0.1 s of a 2 s record at 10 kHz, the response a decaying 300 Hz mode (damping
    /// `zeta`) plus a stationary 2 kHz line and white noise of `noise` sd.
    fn record(zeta: f64, noise: f64) -> (Vec<f64>, Vec<f64>) {
        let fs = 10_000.0;
        let n = 20_000;
        let noise_v = gaussian_noise(3, n);
        let mut force = vec![0.0; n];
        for (i, f) in force.iter_mut().enumerate().skip(1000).take(7) {
            *f = 100.0 * (std::f64::consts::PI * (i - 999) as f64 / 8.0).sin();
        }
        let w = 2.0 * std::f64::consts::PI * 300.0;
        let resp = (0..n)
            .map(|i| {
                let t = i as f64 / fs;
                let m = if i > 1003 {
                    let u = t - 0.1003;
                    (-zeta * w * u).exp() * (w * u).sin()
                } else {
                    0.0
                };
                m + 0.05 * (2.0 * std::f64::consts::PI * 2000.0 * t).sin() + noise * noise_v[i]
            })
            .collect();
        (force, resp)
    }

    #[test]
    fn the_decaying_mode_is_excited_the_stationary_line_and_the_noise_are_not() {
        let (force, resp) = record(0.01, 0.002);
        let hits = find(&force, 10_000.0, ImpactRule::default(), "force").unwrap();
        let e = excited(&[resp], &hits, 10_000.0, (20.0, 4000.0)).unwrap();
        let (lo, hi) = e.span_hz.unwrap();
        assert!(lo > 250.0 && hi < 350.0, "{lo}-{hi}");
        // damping 1 % at 300 Hz decays by exp(-19 * 0.75 * 1.9) within the block: nothing left
        assert!(e.undecayed < 0.01, "{}", e.undecayed);
        let band = e.band((20.0, 4000.0)).unwrap();
        assert!(
            band.1 < 2000.0,
            "{band:?}: the stationary 2 kHz line is not the hits'"
        );
    }

    #[test]
    fn a_response_whose_record_began_earlier_starts_moving_that_long_after_the_pulse() {
        let (force, resp) = record(0.01, 0.002);
        let hits = find(&force, 10_000.0, ImpactRule::default(), "force").unwrap();
        let lag = onset_lag_s(std::slice::from_ref(&resp), &hits, 10_000.0).unwrap();
        assert!(lag < 0.001, "{lag}");
        // the same response recorded from 3 ms earlier: its events 30 samples later
        let late: Vec<f64> = std::iter::repeat_n(resp[0], 30).chain(resp).collect();
        let lag = onset_lag_s(&[late], &hits, 10_000.0).unwrap();
        assert!((lag - 0.003).abs() < 0.001, "{lag}");
    }

    #[test]
    fn a_mode_that_has_not_decayed_is_said_and_pure_noise_excites_nothing() {
        let (force, resp) = record(0.0003, 0.002);
        let hits = find(&force, 10_000.0, ImpactRule::default(), "force").unwrap();
        let e = excited(&[resp], &hits, 10_000.0, (20.0, 4000.0)).unwrap();
        // 0.03 % at 300 Hz: exp(-0.57 * 1.4) of the amplitude is left at the end
        assert!(e.undecayed > 0.3, "{}", e.undecayed);
        assert!((e.undecayed_at_hz.unwrap() - 300.0).abs() < 15.0);
        let noise = gaussian_noise(9, 20_000);
        let e = excited(&[noise], &hits, 10_000.0, (20.0, 4000.0)).unwrap();
        assert_eq!(e.lines, 0);
        assert!(e.band((20.0, 4000.0)).is_none());
    }

    #[test]
    fn the_coherent_span_is_where_the_median_response_follows_the_force() {
        let freq: Vec<f64> = (0..100).map(f64::from).collect();
        // two responses coherent over 20-60 Hz, one over 25-80 Hz: the median is coherent over
        // 20-60 Hz, and over 5 lines its sharp edges reach 0.8 two lines in (22-58 Hz); a lone
        // coherent line at 90 Hz stays out
        let c = |lo: usize, hi: usize| -> Vec<f64> {
            (0..100)
                .map(|k| {
                    if (lo..=hi).contains(&k) || k == 90 {
                        0.95
                    } else {
                        0.1
                    }
                })
                .collect()
        };
        let coherence = vec![c(20, 60), c(20, 60), c(25, 80)];
        let (lo, hi, lines) = coherent_span(&freq, &coherence, (0.0, 99.0)).unwrap();
        assert_eq!((lo, hi, lines), (22.0, 58.0, 37));
        assert_eq!(
            coherent_span(&freq, &coherence, (30.0, 40.0)),
            Some((30.0, 40.0, 11))
        );
        assert_eq!(coherent_span(&freq, &[c(200, 200)], (0.0, 99.0)), None);
    }
}

//! Records of known modes for the tests (test builds only): exact discrete oscillators.

/// Each mode `(f_hz, damping, shape)` as a second-order autoregression whose poles are
/// `exp(s / fs_hz)` of that frequency and damping, driven by white noise (seed `seed + mode`),
/// mixed into the channels by its shape; then white noise of `noise` times the first
/// channel's RMS on each channel (seed `seed + 10 + channel`). `n` samples.
pub fn oscillators(
    fs_hz: f64,
    n: usize,
    modes: &[(f64, f64, &[f64])],
    (seed, noise): (u64, f64),
) -> Vec<Vec<f64>> {
    let k = modes.first().map_or(0, |m| m.2.len());
    let mut channels = vec![vec![0.0; n]; k];
    for (m, (f, z, shape)) in modes.iter().enumerate() {
        let w = 2.0 * std::f64::consts::PI * f / fs_hz;
        let (r, th) = ((-z * w).exp(), w * (1.0 - z * z).sqrt());
        let e = vibcam_common::testing::gaussian_noise(seed + m as u64, n);
        let mut x = vec![0.0; n];
        for t in 2..n {
            x[t] = 2.0 * r * th.cos() * x[t - 1] - r * r * x[t - 2] + e[t];
        }
        for (c, a) in shape.iter().enumerate() {
            channels[c]
                .iter_mut()
                .zip(&x)
                .for_each(|(y, v)| *y += a * v);
        }
    }
    let rms = (channels[0].iter().map(|v| v * v).sum::<f64>() / n.max(1) as f64).sqrt();
    for (c, y) in channels.iter_mut().enumerate() {
        let e = vibcam_common::testing::gaussian_noise(seed + 10 + c as u64, n);
        y.iter_mut()
            .zip(&e)
            .for_each(|(v, e)| *v += noise * rms * e);
    }
    channels
}

/// Six points, two modes: `(f_hz, damping, shape over the six points)`.
pub const SIX_POINTS: [(f64, f64, [f64; 6]); 2] = [
    (2.7, 0.02, [1.0, 0.8, 0.6, 0.4, -0.3, 0.2]),
    (6.3, 0.015, [0.5, -0.9, 0.2, 1.0, 0.7, -0.6]),
];

/// Two setups of [`SIX_POINTS`] at 50 Hz, 30000 samples, noise 0.3: setup 1 records points
/// 1-4 (seed `seeds.0`), setup 2 points 5, 2, 6, 1 (seed `seeds.1`, 2.5 times larger), so
/// they share points 1 and 2, setup 2 listing them as its channels 4 and 2.
pub fn two_setups(seeds: (u64, u64)) -> [Vec<Vec<f64>>; 2] {
    let of: Vec<(f64, f64, &[f64])> = SIX_POINTS
        .iter()
        .map(|(f, z, v)| (*f, *z, &v[..]))
        .collect();
    let record = |points: [usize; 4], seed: u64, gain: f64| -> Vec<Vec<f64>> {
        let all = oscillators(50.0, 30_000, &of, (seed, 0.3));
        points
            .iter()
            .map(|&p| all[p].iter().map(|v| gain * v).collect())
            .collect()
    };
    [
        record([0, 1, 2, 3], seeds.0, 1.0),
        record([4, 1, 5, 0], seeds.1, 2.5),
    ]
}

/// The mean and sample standard deviation of `x` (a Monte Carlo's column).
pub fn mean_sd(x: impl Iterator<Item = f64>) -> (f64, f64) {
    let x: Vec<f64> = x.collect();
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let sd = (x.iter().map(|a| (a - mean).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt();
    (mean, sd)
}

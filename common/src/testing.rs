//! Helpers for tests, examples and benchmarks: seeded noise from one portable generator (ChaCha8,
//! never `StdRng`), so that every test's "random" record is reproducible on every platform, and
//! the calling thread's CPU time for benchmark figures.

use rand::{Rng as _, SeedableRng as _};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution as _, StandardNormal};

/// `n` values uniform in `[-0.5, 0.5)` from the stream of `seed`.
pub fn uniform_noise(seed: u64, n: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| rng.random::<f64>() - 0.5).collect()
}

/// `n` standard normal values from the stream of `seed`.
pub fn gaussian_noise(seed: u64, n: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| StandardNormal.sample(&mut rng)).collect()
}

/// CPU seconds of the calling thread (`/proc/thread-self/stat`, 10 ms ticks), so that a busy
/// machine does not inflate a benchmark's figures; wall-clock seconds since the first call where
/// that file is missing.
pub fn thread_cpu_seconds() -> f64 {
    let ticks = std::fs::read_to_string("/proc/thread-self/stat")
        .ok()
        .and_then(|s| {
            // fields after the command name's closing parenthesis; utime and stime are 14 and 15
            let rest = s.rsplit_once(')')?.1;
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some(f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?)
        });
    match ticks {
        Some(t) => t / 100.0,
        None => {
            static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
            START
                .get_or_init(std::time::Instant::now)
                .elapsed()
                .as_secs_f64()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_reproducible_and_has_the_stated_moments() {
        assert_eq!(uniform_noise(3, 100), uniform_noise(3, 100));
        assert_ne!(uniform_noise(3, 100), uniform_noise(4, 100));
        let u = uniform_noise(1, 100_000);
        let g = gaussian_noise(1, 100_000);
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        let var = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64;
        // 5 standard errors of the sample moments at n = 1e5
        assert!(u.iter().all(|x| (-0.5..0.5).contains(x)));
        assert!(mean(&u).abs() < 5.0 * (1.0f64 / 12.0 / 1e5).sqrt());
        assert!((var(&u) - 1.0 / 12.0).abs() < 5.0 * 0.0745 / 1e5f64.sqrt() / 12.0);
        assert!(mean(&g).abs() < 5.0 / 1e5f64.sqrt());
        assert!((var(&g) - 1.0).abs() < 5.0 * 2f64.sqrt() / 1e5f64.sqrt());
    }
}

//! Do the output-only intervals hold? (docs/validation.md, "Intervals of output-only
//! results".) Per field case, record length and noise, over seeded records whose truth is
//! known: for SSI-cov and EFDD, the share of records whose 95 % interval of the frequency and
//! of the damping contains the true value, and the mean width of the interval against the
//! width the estimates' real spread calls for (`2 x 1.96 x` their standard deviation over the
//! records); `modal`'s defaults (jackknife over 10 groups).
//!
//! ```text
//! cargo run --release -p host-harness --example oma_coverage [-- RECORDS [MINUTES,... [NOISE,...]]]
//! ```
//! (defaults: 40 records, 5 and 10 and 30 minutes, 3 % and 10 % noise; 60 Hz).

use host_harness::analysis::oma::{analyze, Method, OmaSettings};
use host_harness::model::field::{simulate, FieldCase};
use rayon::prelude::*;

/// Per method, mode and quantity: (covered, counted, estimates, widths).
type Tally = (usize, usize, Vec<f64>, Vec<f64>);

fn list(arg: Option<&String>, default: &[f64]) -> Vec<f64> {
    arg.map_or_else(
        || default.to_vec(),
        |s| s.split(',').filter_map(|v| v.parse().ok()).collect(),
    )
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let records: u64 = args.first().and_then(|s| s.parse().ok()).unwrap_or(40);
    let minutes = list(args.get(1), &[5.0, 10.0, 30.0]);
    let noises = list(args.get(2), &[0.03, 0.10]);
    let fs = 60.0;
    println!("| case | minutes | noise | method | mode | f covered | f width / needed | damping covered | damping width / needed |");
    println!("|---|---:|---:|---|---:|---:|---:|---:|---:|");
    let (mut all_cov, mut all_n) = (0usize, 0usize);
    for case in [
        FieldCase::ShearFrame,
        FieldCase::WeakHighMode,
        FieldCase::CloseModes,
    ] {
        let model = case.model();
        for &min in &minutes {
            for &noise in &noises {
                let n = (fs * 60.0 * min) as usize;
                let results: Vec<_> = (0..records)
                    .into_par_iter()
                    .map(|seed| {
                        let rec = simulate(&model, fs, n, noise, 9000 + seed);
                        analyze(&rec, &OmaSettings::new(fs, n, None))
                    })
                    .collect::<Result<_, _>>()?;
                for method in [Method::Efdd, Method::Ssi] {
                    // per mode: f tally, damping tally
                    let mut t: Vec<(Tally, Tally)> = vec![Default::default(); model.modes.len()];
                    for r in &results {
                        let df = r.csd.df_hz();
                        for (i, m) in model.modes.iter().enumerate() {
                            let tol = model.match_window(i, df);
                            let Some(got) = r.nearest(method, m.f_hz, tol) else {
                                continue;
                            };
                            let (tf, tz) = &mut t[i];
                            if let Some(iv) = got.uncertainty.f_hz {
                                tf.0 += usize::from(iv.lo <= m.f_hz && m.f_hz <= iv.hi);
                                tf.1 += 1;
                                tf.2.push(got.f_hz);
                                tf.3.push(iv.hi - iv.lo);
                            }
                            if let (Some(iv), Some(z)) = (got.uncertainty.damping, got.damping) {
                                tz.0 += usize::from(iv.lo <= m.damping && m.damping <= iv.hi);
                                tz.1 += 1;
                                tz.2.push(z);
                                tz.3.push(iv.hi - iv.lo);
                            }
                        }
                    }
                    for (i, (tf, tz)) in t.iter().enumerate() {
                        let show = |x: &Tally| -> (String, String) {
                            if x.1 < 2 {
                                return ("-".into(), "-".into());
                            }
                            let k = x.2.len() as f64;
                            let mean = x.2.iter().sum::<f64>() / k;
                            let sd = (x.2.iter().map(|v| (v - mean).powi(2)).sum::<f64>()
                                / (k - 1.0))
                                .sqrt();
                            let width = x.3.iter().sum::<f64>() / x.3.len() as f64;
                            (
                                format!(
                                    "{}/{} ({:.0} %)",
                                    x.0,
                                    x.1,
                                    100.0 * x.0 as f64 / x.1 as f64
                                ),
                                format!("{:.2}", width / (2.0 * 1.96 * sd)),
                            )
                        };
                        let (fc, fw) = show(tf);
                        let (zc, zw) = show(tz);
                        all_cov += tf.0 + tz.0;
                        all_n += tf.1 + tz.1;
                        println!(
                            "| {case:?} | {min} | {noise} | {} | {} | {fc} | {fw} | {zc} | {zw} |",
                            method.name(),
                            i + 1
                        );
                    }
                }
            }
        }
    }
    println!(
        "\nall intervals: {all_cov} of {all_n} hold ({:.1} %)",
        100.0 * all_cov as f64 / all_n.max(1) as f64
    );
    Ok(())
}

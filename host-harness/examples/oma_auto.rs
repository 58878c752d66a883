//! Output-only analysis without bands, counted against the truth (docs/method.md §3.12): per
//! field case, over seeded records, how many times each method (FDD, EFDD, SSI-cov) reported
//! exactly the structure's modes (as many modes as the truth, each true mode matched by one
//! within `max(3 lines, 3 zeta f)` and nearer than half the distance to another true mode), what
//! it reported besides or missed, and the damping's relative error per mode (mean +- standard
//! deviation over the records that found it), with the wall time. The settings are `modal`'s
//! defaults (`OmaSettings::new`, no `--nperseg`).
//!
//! ```text
//! cargo run --release -p host-harness --example oma_auto [-- MINUTES [RECORDS [NOISE [FPS]]]]
//! ```
//! (defaults: 10 minutes, 20 records, 3 % noise, 60 Hz).

use host_harness::analysis::oma::{analyze, Method, OmaSettings};
use host_harness::model::field::{simulate, FieldCase, FieldModel};
use rayon::prelude::*;
use std::time::Instant;

/// One record's outcome for one method: exact or not, what was extra or missing, per true
/// mode the damping found.
struct Count {
    exact: bool,
    extra: Vec<f64>,
    missing: Vec<f64>,
    damping: Vec<Option<f64>>,
}

fn count(model: &FieldModel, found: &[(f64, Option<f64>)], df: f64) -> Count {
    let mut used = vec![false; found.len()];
    let mut damping = Vec::new();
    let mut missing = Vec::new();
    for (i, m) in model.modes.iter().enumerate() {
        let tol = model.match_window(i, df);
        let best = found
            .iter()
            .enumerate()
            .filter(|(i, (f, _))| !used[*i] && (f - m.f_hz).abs() <= tol)
            .min_by(|a, b| (a.1 .0 - m.f_hz).abs().total_cmp(&(b.1 .0 - m.f_hz).abs()));
        match best {
            Some((i, (_, z))) => {
                used[i] = true;
                damping.push(*z);
            }
            None => {
                missing.push(m.f_hz);
                damping.push(None);
            }
        }
    }
    let extra: Vec<f64> = found
        .iter()
        .zip(&used)
        .filter(|(_, u)| !**u)
        .map(|(f, _)| f.0)
        .collect();
    Count {
        exact: extra.is_empty() && missing.is_empty(),
        extra,
        missing,
        damping,
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let minutes = args.first().copied().unwrap_or(10.0);
    let records = args.get(1).copied().unwrap_or(20.0) as u64;
    let noise = args.get(2).copied().unwrap_or(0.03);
    let fs = args.get(3).copied().unwrap_or(60.0);
    let n = (fs * 60.0 * minutes) as usize;
    println!("{minutes} min at {fs} Hz, {records} records per case, noise {noise}");
    for case in [
        FieldCase::ShearFrame,
        FieldCase::CloseModes,
        FieldCase::WeakHighMode,
    ] {
        let model = case.model();
        let t0 = Instant::now();
        let results: Vec<_> = (0..records)
            .into_par_iter()
            .map(|seed| {
                let rec = simulate(&model, fs, n, noise, 5000 + seed);
                analyze(&rec, &OmaSettings::new(fs, n, None)).map(|r| (seed, r))
            })
            .collect::<Result<_, _>>()?;
        let secs = t0.elapsed().as_secs_f64();
        println!(
            "\n{case:?}: modes {:?} ({:.2} s per record, both cores)",
            model
                .modes
                .iter()
                .map(|m| (m.f_hz, m.damping))
                .collect::<Vec<_>>(),
            secs / records as f64 * 2.0
        );
        for method in [Method::Fdd, Method::Efdd, Method::Ssi] {
            let mut exact = 0;
            let mut notes = Vec::new();
            let mut z: Vec<Vec<f64>> = vec![Vec::new(); model.modes.len()];
            for (seed, r) in &results {
                let found: Vec<(f64, Option<f64>)> = r
                    .modes
                    .iter()
                    .filter(|m| m.method == method)
                    .map(|m| (m.f_hz, m.damping))
                    .collect();
                let c = count(&model, &found, r.csd.df_hz());
                if c.exact {
                    exact += 1;
                } else {
                    notes.push(format!(
                        "seed {seed}: extra {:.3?} missing {:.3?}",
                        c.extra, c.missing
                    ));
                }
                for ((zs, m), d) in z.iter_mut().zip(&model.modes).zip(&c.damping) {
                    if let Some(d) = d {
                        zs.push(100.0 * (d / m.damping - 1.0));
                    }
                }
            }
            let damping: Vec<String> = z
                .iter()
                .map(|v| {
                    if v.is_empty() {
                        return "-".into();
                    }
                    let k = v.len() as f64;
                    let mean = v.iter().sum::<f64>() / k;
                    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()
                        / (k - 1.0).max(1.0))
                    .sqrt();
                    format!("{mean:+.1} +- {sd:.1} (t {:+.1})", mean / sd * k.sqrt())
                })
                .collect();
            println!(
                "  {:<4} exact {exact}/{records}; damping % {}",
                method.name(),
                damping.join(" | ")
            );
            for n in notes {
                println!("       {n}");
            }
        }
    }
    Ok(())
}

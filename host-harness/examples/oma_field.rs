//! Output-only modal analysis against the truth on synthetic field records (docs/method.md
//! §3.12): per record length, over 20 seeded records of the five-storey shear frame (60 Hz,
//! 2 % measurement noise, Welch segments of 2048), the largest frequency error in spectral
//! lines, the damping's relative error (mean and standard deviation over the records), the
//! smallest MAC and how many records found the mode (an identified mode within 3 lines and
//! nearer than half the distance to another true mode), per method and mode; then the
//! close-modes case.
//!
//! ```text
//! cargo run --release -p host-harness --example oma_field [MINUTES ...]
//! ```

use host_harness::analysis::modal::mac;
use host_harness::analysis::oma::{analyze, Method, OmaSettings};
use host_harness::model::field::{simulate, FieldCase};
use num_complex::Complex64;

/// Per method and mode: largest |df| in lines, damping errors (%), smallest MAC, found.
type Stat = (f64, Vec<f64>, f64, usize);

fn main() -> anyhow::Result<()> {
    let minutes: Vec<f64> = {
        let given: Vec<f64> = std::env::args()
            .skip(1)
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?;
        if given.is_empty() {
            vec![5.0, 10.0, 30.0, 60.0]
        } else {
            given
        }
    };
    let fs = 60.0;
    for case in [FieldCase::ShearFrame, FieldCase::CloseModes] {
        let model = case.model();
        println!(
            "\n{case:?}: modes {:?}",
            model
                .modes
                .iter()
                .map(|m| (m.f_hz, m.damping))
                .collect::<Vec<_>>()
        );
        println!("| minutes | method | mode | f error, lines (max) | damping error, % (mean +- sd) | MAC (min) | found |");
        println!("|---:|---|---:|---:|---:|---:|---:|");
        for &min in &minutes {
            let n = (fs * 60.0 * min) as usize;
            let runs = 20;
            // per method and mode: (max |df| in lines, damping errors, min MAC, found count)
            let mut stats: Vec<Vec<Stat>> =
                vec![vec![(0.0, Vec::new(), 1.0, 0); model.modes.len()]; 3];
            for seed in 0..runs {
                let rec = simulate(&model, fs, n, 0.02, 1000 + seed);
                let r = analyze(&rec, &OmaSettings::new(fs, n, Some(2048)))?;
                let df = r.csd.df_hz();
                for (mi, method) in [Method::Fdd, Method::Efdd, Method::Ssi]
                    .into_iter()
                    .enumerate()
                {
                    for (i, m) in model.modes.iter().enumerate() {
                        // the identified mode nearest the true one, within 3 lines and
                        // nearer than half the distance to another true mode
                        let gap = model
                            .modes
                            .iter()
                            .filter(|o| o.f_hz != m.f_hz)
                            .map(|o| (o.f_hz - m.f_hz).abs() / 2.0)
                            .fold(3.0 * df, f64::min);
                        let Some(got) = r.nearest(method, m.f_hz, gap) else {
                            continue;
                        };
                        let s = &mut stats[mi][i];
                        s.0 = f64::max(s.0, (got.f_hz - m.f_hz).abs() / df);
                        if let Some(z) = got.damping {
                            s.1.push(100.0 * (z / m.damping - 1.0));
                        }
                        let truth: Vec<Complex64> =
                            m.shape.iter().map(|&v| Complex64::new(v, 0.0)).collect();
                        s.2 = f64::min(s.2, mac(&got.shape, &truth));
                        s.3 += 1;
                    }
                }
            }
            for (mi, name) in ["fdd", "efdd", "ssi"].iter().enumerate() {
                for (i, s) in stats[mi].iter().enumerate() {
                    let z = if s.1.is_empty() {
                        String::new()
                    } else {
                        let n = s.1.len() as f64;
                        let mean = s.1.iter().sum::<f64>() / n;
                        let sd = (s.1.iter().map(|v| (v - mean).powi(2)).sum::<f64>()
                            / (n - 1.0).max(1.0))
                        .sqrt();
                        format!("{mean:+.1} +- {sd:.1}")
                    };
                    println!(
                        "| {min} | {name} | {} | {:.2} | {z} | {:.4} | {}/{runs} |",
                        i + 1,
                        s.0,
                        s.2,
                        s.3
                    );
                }
            }
        }
    }
    Ok(())
}

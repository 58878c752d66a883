//! Writes a universal file (one dataset 58 per FRF) of the cantilever rig's closed-form FRFs
//! (method.md §3.2) at 0.1 Hz bins, for `scripts/check_uff.py` to read with pyuff and fit with
//! sdypy-EMA; prints our own fit of the same FRFs ([`host_harness::analysis::modal`]) to compare.
//!
//! FRFs, all acceleration over base acceleration: the tip accelerometer (node 101) and five
//! vision targets along the beam (nodes 1-5, at x/L = 0.2 ... 1.0, Euler-Bernoulli cantilever
//! shapes); reference node 100 (the base accelerometer), direction +Z.
//!
//! ```text
//! cargo run -p host-harness --example uff_synthetic -- out/synthetic.uff
//! python3 scripts/check_uff.py out/synthetic.uff --expect 7.1,32.4
//! ```

use host_harness::analysis::modal::{self, FrfForm};
use host_harness::export::uff;
use host_harness::model::Rig;
use host_harness::recording::RecordingSpec;
use num_complex::Complex64;
use std::f64::consts::PI;
use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    let path = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "synthetic.uff".into()),
    );
    let spec = RecordingSpec::cantilever(0, 2.0);
    let Rig::Cantilever(host_harness::model::cantilever::Rig { modes, .. }) = &spec.rig else {
        unreachable!("the cantilever preset")
    };
    let df = 0.1;
    let freq: Vec<f64> = (0..=1000).map(|k| k as f64 * df).collect();
    let tip: Vec<Complex64> = freq.iter().map(|&f| spec.frf(f)).collect();
    let targets: Vec<Vec<Complex64>> = (1..=5)
        .map(|j| {
            let xi = j as f64 / 5.0;
            freq.iter()
                .map(|&f| {
                    let w = 2.0 * PI * f;
                    let mut h = Complex64::new(1.0, 0.0);
                    for (m, mode) in modes.iter().enumerate() {
                        let wn = 2.0 * PI * mode.f_hz;
                        let gphi = mode.g_phi * host_harness::model::cantilever::mode_shape(m, xi)
                            / host_harness::model::cantilever::mode_shape(m, 1.0);
                        h += gphi * w * w
                            / Complex64::new(wn * wn - w * w, 2.0 * mode.zeta * wn * w);
                    }
                    h
                })
                .collect()
        })
        .collect();

    let frfs: Vec<_> = targets.iter().map(|h| Some((0.0, h.as_slice()))).collect();
    let accel = ("tip accelerometer / base acceleration", 101, 0.0, &tip[..]);
    let datasets = uff::vision_frfs(100, accel, &frfs, df);
    let bytes = uff::write_file(&datasets)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::write(&path, bytes)?;
    println!("wrote {} ({} datasets 58)", path.display(), datasets.len());

    let refs: Vec<&[Complex64]> = targets.iter().map(|v| v.as_slice()).collect();
    for (m, band) in [(5.0, 15.0), (25.0, 45.0)].into_iter().enumerate() {
        let fit = modal::fit_mode(&freq, &tip, band, FrfForm::Accelerance)?;
        let shape = modal::fit_shape(&freq, &refs, band, FrfForm::Accelerance, Some(fit.pole))?;
        let truth: Vec<Complex64> = (1..=5)
            .map(|j| {
                Complex64::new(
                    host_harness::model::cantilever::mode_shape(m, j as f64 / 5.0),
                    0.0,
                )
            })
            .collect();
        println!(
            "mode {}: model {:.4} Hz damping {:.5}; ours {:.4} Hz damping {:.5}; shape MAC {:.6}",
            m + 1,
            modes[m].f_hz,
            modes[m].zeta,
            fit.f_hz(),
            fit.damping(),
            modal::mac(&shape.shape, &truth)
        );
    }
    Ok(())
}

//! `analyze --targets K`: the multi-target path of `host-harness analyze`
//! ([`crate::analysis::targets`]); writes `modes.csv`, `shapes.csv`, `frf.uff` and `report.txt`
//! into the staged output directory.

use super::analyze::Args;
use crate::analysis::frames::FrameSource;
use crate::analysis::targets::{self, TargetAnalysis};
use crate::analysis::uff::{self, Dataset58, Dof};
use crate::analysis::{DisplacementSettings, Settings};
use crate::outdir::{Owner, Staged};
use std::fmt::Write as _;

/// Runs the multi-target analysis of `k` targets.
pub fn run(
    args: &Args,
    source: &FrameSource,
    (base, tip): (&[f64], &[f64]),
    (settings, ds): (&Settings, &DisplacementSettings),
    k: usize,
) -> anyhow::Result<()> {
    if !(2..=32).contains(&k) {
        return Err(crate::bad_input(format!("--targets {k}: between 2 and 32")));
    }
    let config = args.centroid.config(None)?;
    let tracks = targets::track(source, args.fps, &config, k, args.gate_px)?;
    let a = targets::analyze_targets(&tracks, ds, (base, tip), settings)?;
    let out = Staged::new(&args.out, args.force, Owner::Holds("report.txt"))?;
    out.write("modes.csv", targets::modes_csv(&a.modes))?;
    out.write("shapes.csv", targets::shapes_csv(&a, &tracks.first))?;
    out.write("frf.uff", uff_bytes(&a)?)?;
    let report = report(&a, &tracks.first, k);
    out.write("report.txt", &report)?;
    out.commit()?;
    print!("{report}");
    Ok(())
}

/// One dataset 58 per FRF: the accelerometer (node 100) and each target (node 1..K), all over
/// the base acceleration (node 1000), direction +Z (image up).
fn uff_bytes(a: &TargetAnalysis) -> anyhow::Result<Vec<u8>> {
    let base = Dof {
        node: 1000,
        direction: 3,
    };
    let acc = &a.analyses[0].acc_frf;
    let df = acc.freq_hz.get(1).copied().unwrap_or(0.0) - acc.freq_hz[0];
    let mut sets = vec![Dataset58::acceleration_frf(
        "accelerometer / base acceleration",
        1,
        Dof {
            node: 100,
            direction: 3,
        },
        base,
        acc.freq_hz[0],
        df,
        &acc.h1,
    )];
    let names: Vec<String> = (1..=a.analyses.len())
        .map(|t| format!("vision target {t} / base acceleration"))
        .collect();
    for (t, an) in a.analyses.iter().enumerate() {
        sets.push(Dataset58::acceleration_frf(
            &names[t],
            t as u32 + 2,
            Dof {
                node: t as u32 + 1,
                direction: 3,
            },
            base,
            an.vis_frf.freq_hz[0],
            df,
            &an.vis_frf.h1,
        ));
    }
    Ok(uff::write_file(&sets)?)
}

/// The printed report: lost frames per target, modes, shapes.
fn report(a: &TargetAnalysis, first: &[(f64, f64)], k: usize) -> String {
    let mut s = format!("analyze --targets {k}\n\nlost frames per target:");
    for (t, d) in a.displacements.iter().enumerate() {
        let _ = write!(s, " {}: {} of {}", t + 1, d.lost_count, d.mm.len());
    }
    s.push_str("\n\nsystem        | target | mode |    f_hz | damping  | amplitude\n");
    for m in &a.modes {
        let system = if m.target == 0 {
            "accelerometer"
        } else {
            "vision"
        };
        let f = m.f_hz.map_or("-".into(), |v| format!("{v:.4}"));
        let z = m.damping.map_or("-".into(), |v| format!("{v:.5}"));
        let _ = writeln!(
            s,
            "{system:<13} | {:>6} | {:>4} | {f:>7} | {z:<8} | {:.4}",
            m.target, m.mode, m.amplitude
        );
    }
    for (b, shape) in a.shapes.iter().enumerate() {
        match shape {
            Some((pole, v)) => {
                let _ = write!(
                    s,
                    "\nmode {} shape (pole {:.4} Hz, damping {:.5}):",
                    b + 1,
                    pole.f_hz,
                    pole.damping
                );
                for (c, (x, _)) in v.iter().zip(first) {
                    let _ = write!(s, " x {x:.0} px: {:+.4}{:+.4}i", c.re, c.im);
                }
            }
            None => {
                let _ = write!(s, "\nmode {}: no shape (the fit failed)", b + 1);
            }
        }
    }
    s.push('\n');
    s
}

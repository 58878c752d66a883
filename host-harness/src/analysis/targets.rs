//! Several targets in one recording (issue 14, `analyze --targets K`): firmware-core's
//! multi-target centroider on every frame, targets numbered left to right (then top to bottom)
//! in the first frame, each followed by its nearest detection within a gate; a target with no
//! detection in the gate, or whose detection is also the nearest of another target, is a lost
//! frame of that target only. Per target the chain of [`super::analyze`]; per band the modal fit
//! ([`super::modal`]): the accelerometer's and each target's pole (frequency, damping) and the
//! shape across targets from one pole fitted to all their FRFs.

use super::frames::FrameSource;
use super::modal::{self, FrfForm};
use super::{Analysis, Displacement, DisplacementSettings, Settings};
use crate::bad_input;
use crate::chain::displacement::GreyFrame;
use firmware_core::centroid::{Centroid, CentroidConfig, Flags, Frame, Moments, MultiCentroider};
use num_complex::Complex64;

/// Widest frame the multi-target labelling buffer holds, px.
const MAX_WIDTH: usize = 8192;
/// Most detections per frame (targets plus clutter).
const MAX_DETECTIONS: usize = 64;

/// Each target's centroid per frame (an empty centroid where it was lost) and where it was
/// first seen.
#[derive(Debug, Clone)]
pub struct Tracks {
    /// `centroids[t][k]`: target `t`, frame `k`.
    pub centroids: Vec<Vec<Centroid>>,
    /// Position in the first frame, px.
    pub first: Vec<(f64, f64)>,
}

/// A centroid standing for a lost frame.
fn lost() -> Centroid {
    Centroid {
        cx: 0.0,
        cy: 0.0,
        moments: Moments {
            pixels: 0,
            weight: 0,
            sum_x: 0,
            sum_y: 0,
        },
        flags: Flags::EMPTY,
    }
}

/// Follows `k` targets through the frames of `source` (see the module documentation).
pub fn track(
    source: &FrameSource,
    fps: f64,
    config: &CentroidConfig,
    k: usize,
    gate_px: f64,
) -> anyhow::Result<Tracks> {
    let mut mc = Box::new(
        MultiCentroider::<MAX_WIDTH, MAX_DETECTIONS>::try_new(*config)
            .map_err(|e| bad_input(format!("centroid settings: {e}")))?,
    );
    let mut tracks = Tracks {
        centroids: vec![Vec::new(); k],
        first: Vec::new(),
    };
    let mut last: Vec<(f64, f64)> = Vec::new();
    let mut frame_no = 0usize;
    let mut one = |label: String, frame: GreyFrame| -> anyhow::Result<()> {
        frame_no += 1;
        let found = detect(&mut mc, &frame, &label)?;
        if frame_no == 1 {
            if found.len() != k {
                return Err(bad_input(format!(
                    "{label}: {} targets above the threshold in the first frame, --targets {k} \
                     expected",
                    found.len()
                )));
            }
            let mut order: Vec<Centroid> = found.clone();
            order.sort_by(|a, b| a.cx.total_cmp(&b.cx).then(a.cy.total_cmp(&b.cy)));
            last = order.iter().map(|c| (c.cx as f64, c.cy as f64)).collect();
            tracks.first = last.clone();
            for (t, c) in order.into_iter().enumerate() {
                tracks.centroids[t].push(c);
            }
            return Ok(());
        }
        let nearest: Vec<Option<usize>> = last
            .iter()
            .map(|&(x, y)| {
                let d =
                    |c: &Centroid| ((c.cx as f64 - x).powi(2) + (c.cy as f64 - y).powi(2)).sqrt();
                let mut inside: Vec<usize> = (0..found.len())
                    .filter(|&j| d(&found[j]) <= gate_px)
                    .collect();
                inside.sort_by(|&a, &b| d(&found[a]).total_cmp(&d(&found[b])));
                // two detections equally near: ambiguous
                match inside.as_slice() {
                    [] => None,
                    [j] => Some(*j),
                    [j, n, ..] if d(&found[*n]) - d(&found[*j]) > 1e-3 => Some(*j),
                    _ => None,
                }
            })
            .collect();
        for t in 0..k {
            let claimed =
                nearest[t].filter(|j| nearest.iter().filter(|n| **n == Some(*j)).count() == 1);
            match claimed {
                Some(j) => {
                    let c = found[j];
                    last[t] = (c.cx as f64, c.cy as f64);
                    tracks.centroids[t].push(c);
                }
                None => tracks.centroids[t].push(lost()),
            }
        }
        Ok(())
    };
    source.for_each(fps, &mut one)?;
    Ok(tracks)
}

/// The detections of one frame.
fn detect(
    mc: &mut MultiCentroider<MAX_WIDTH, MAX_DETECTIONS>,
    frame: &GreyFrame,
    label: &str,
) -> anyhow::Result<Vec<Centroid>> {
    let (w, h) = frame.dimensions();
    if w > MAX_WIDTH {
        return Err(bad_input(format!(
            "{label}: {w} px wide; --targets handles frames up to {MAX_WIDTH} px"
        )));
    }
    let r = match frame {
        GreyFrame::U8 { data, .. } => Frame::new(data, w, h, w).and_then(|f| mc.process(&f)),
        GreyFrame::U16 { data, .. } => Frame::new(data, w, h, w).and_then(|f| mc.process(&f)),
    };
    r.map_err(|e| bad_input(format!("{label}: cannot centroid the frame: {e}")))?;
    if mc.flags().contains(Flags::CAPACITY) {
        return Err(bad_input(format!(
            "{label}: more than {MAX_DETECTIONS} components above the threshold"
        )));
    }
    Ok(mc.targets().iter().map(|t| t.centroid).collect())
}

/// One mode of one system (accelerometer: target 0; vision: targets 1..K).
#[derive(Debug, Clone, PartialEq)]
pub struct TargetMode {
    /// 0 for the accelerometer, 1..K for the targets.
    pub target: usize,
    /// 1-based mode (band) number.
    pub mode: usize,
    /// The band, Hz.
    pub band_hz: (f64, f64),
    /// Fitted natural frequency, Hz (`None` when the fit failed).
    pub f_hz: Option<f64>,
    /// Picked |H1| at the band's peak.
    pub amplitude: f64,
    /// Fitted damping ratio.
    pub damping: Option<f64>,
    /// Exposure-to-period ratio at the peak (vision only).
    pub e2pr: Option<f64>,
}

/// Per target: the displacement and the analysis.
#[derive(Debug)]
pub struct TargetAnalysis {
    /// Per target, its displacement.
    pub displacements: Vec<Displacement>,
    /// Per target, the chain's result.
    pub analyses: Vec<Analysis>,
    /// Accelerometer and every target, every band.
    pub modes: Vec<TargetMode>,
    /// Per band, the shape across targets (normalised) and the shared pole.
    pub shapes: Vec<Option<(modal::Pole, Vec<Complex64>)>>,
}

/// The chain on every target and the modal fits.
pub fn analyze_targets(
    tracks: &Tracks,
    ds: &DisplacementSettings,
    (base, tip): (&[f64], &[f64]),
    s: &Settings,
) -> anyhow::Result<TargetAnalysis> {
    let mut displacements = Vec::new();
    let mut analyses = Vec::new();
    for (t, c) in tracks.centroids.iter().enumerate() {
        let d = super::displacement_mm(c, ds)
            .map_err(|e| bad_input(format!("target {}: {e:#}", t + 1)))?;
        let a = super::analyze(&d, base, tip, s)
            .map_err(|e| bad_input(format!("target {}: {e:#}", t + 1)))?;
        displacements.push(d);
        analyses.push(a);
    }
    let mut modes = Vec::new();
    let mut shapes = Vec::new();
    let acc = &analyses[0].acc_frf;
    for (b, &band) in s.bands.iter().enumerate() {
        let fit = |f: &crate::chain::frf::Frf| {
            modal::fit_mode(&f.freq_hz, &f.h1, band, FrfForm::Accelerance).ok()
        };
        let a = fit(acc);
        modes.push(TargetMode {
            target: 0,
            mode: b + 1,
            band_hz: band,
            f_hz: a.as_ref().map(|m| m.pole.f_hz),
            amplitude: analyses[0].acc_modes[b].amplitude,
            damping: a.as_ref().map(|m| m.pole.damping),
            e2pr: None,
        });
        for (t, an) in analyses.iter().enumerate() {
            let v = fit(&an.vis_frf);
            modes.push(TargetMode {
                target: t + 1,
                mode: b + 1,
                band_hz: band,
                f_hz: v.as_ref().map(|m| m.pole.f_hz),
                amplitude: an.vis_modes[b].amplitude,
                damping: v.as_ref().map(|m| m.pole.damping),
                e2pr: an.vis_modes[b].e2pr,
            });
        }
        let frfs: Vec<&[Complex64]> = analyses.iter().map(|a| a.vis_frf.h1.as_slice()).collect();
        let shape = modal::fit_shape(&acc.freq_hz, &frfs, band, FrfForm::Accelerance, None).ok();
        shapes.push(shape.map(|s| (s.pole, s.shape)));
    }
    Ok(TargetAnalysis {
        displacements,
        analyses,
        modes,
        shapes,
    })
}

/// `modes.csv`: `system,target,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr` (f_hz and
/// damping fitted; empty where the fit failed).
pub fn modes_csv(modes: &[TargetMode]) -> String {
    let opt = |v: Option<f64>| v.map(|v| v.to_string()).unwrap_or_default();
    let mut s =
        String::from("system,target,mode,band_lo_hz,band_hi_hz,f_hz,amplitude,damping,e2pr\n");
    for m in modes {
        let system = if m.target == 0 {
            "accelerometer"
        } else {
            "vision"
        };
        s.push_str(&format!(
            "{system},{},{},{},{},{},{},{},{}\n",
            m.target,
            m.mode,
            m.band_hz.0,
            m.band_hz.1,
            opt(m.f_hz),
            m.amplitude,
            opt(m.damping),
            opt(m.e2pr)
        ));
    }
    s
}

/// `shapes.csv`: `mode,target,x_px,y_px,re,im,abs`.
pub fn shapes_csv(a: &TargetAnalysis, first: &[(f64, f64)]) -> String {
    let mut s = String::from("mode,target,x_px,y_px,re,im,abs\n");
    for (b, shape) in a.shapes.iter().enumerate() {
        let Some((_, v)) = shape else { continue };
        for (t, (c, &(x, y))) in v.iter().zip(first).enumerate() {
            s.push_str(&format!(
                "{},{},{x},{y},{},{},{}\n",
                b + 1,
                t + 1,
                c.re,
                c.im,
                c.norm()
            ));
        }
    }
    s
}

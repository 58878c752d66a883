//! The camera's view in the outputs: the references as `report.html` marks them, and
//! `camera_motion.csv` with its spectrum. The view itself (the camera's motion, the scale) is
//! `vibcam_track::view`, re-exported here.

pub use vibcam_track::view::*;

/// The references for `report.html`: each one's median position, numbered as in the report,
/// and whether it was left out.
pub fn reference_markers(v: &Viewed) -> Vec<crate::export::html::ReferenceMarker> {
    let (Some(refs), Some(m)) = (&v.references, &v.motion) else {
        return Vec::new();
    };
    refs.centroids
        .iter()
        .enumerate()
        .filter_map(|(r, c)| {
            median_position(c).map(|xy| crate::export::html::ReferenceMarker {
                number: r + 1,
                xy,
                left_out: !m.used.contains(&(r + 1)),
            })
        })
        .collect()
}

/// The camera's motion outputs of a view, in memory: the report's line, `camera_motion.csv`
/// and the spectrum's figure (with `plots` and 32 frames or more); all empty without
/// references.
#[derive(Debug, Default)]
pub struct CameraOutputs {
    /// The report's line naming the files.
    pub text: String,
    /// `camera_motion.csv`.
    pub csv: Option<Vec<u8>>,
    /// `camera_motion.png`/`.svg`.
    pub figure: Option<crate::plots::Figure>,
}

impl CameraOutputs {
    /// Stages `camera_motion.csv` and the figure in `out`.
    pub fn write_staged(&self, out: &crate::outdir::Staged) -> anyhow::Result<()> {
        if let Some(csv) = &self.csv {
            out.write("camera_motion.csv", csv)?;
        }
        if let Some(f) = &self.figure {
            f.write_staged(out)?;
        }
        Ok(())
    }
}

/// `camera_motion.csv` and the camera motion's spectrum when references were given, with the
/// report's line naming them; nothing written.
pub fn camera_outputs(viewed: &Viewed, fps: f64, plots: bool) -> anyhow::Result<CameraOutputs> {
    let Some(m) = &viewed.motion else {
        return Ok(CameraOutputs::default());
    };
    let n = m.transforms.len();
    let motion: Vec<Option<vibcam_track::camera_motion::MotionRow>> =
        (0..n).map(|k| m.row(k)).collect();
    let rows: Vec<crate::export::targets::CameraRow> = motion
        .iter()
        .enumerate()
        .map(|(k, r)| crate::export::targets::CameraRow {
            t_s: k as f64 / fps,
            motion: r.map(|r| (r.dx_px, r.dy_px, r.rotation_deg, r.scale)),
            references: m.seen[k],
            residual_px: m.residual_px[k],
        })
        .collect();
    let csv = crate::export::targets::camera_motion_csv(&rows);
    let mut line = "camera motion per frame: camera_motion.csv".to_string();
    let mut figure = None;
    if plots && n >= 32 {
        // a frame whose motion is unknown counts as the mean's
        let series = |f: fn(&vibcam_track::camera_motion::MotionRow) -> f64| -> Vec<f64> {
            let known: Vec<f64> = motion.iter().flatten().map(f).collect();
            let mean = crate::stats::mean(&known).unwrap_or(0.0);
            motion.iter().map(|r| r.as_ref().map_or(mean, f)).collect()
        };
        let channels = vec![series(|r| r.dx_px), series(|r| r.dy_px)];
        let nperseg = (1usize << ((n / 4).max(16).ilog2())).clamp(16, 4096);
        let c = super::oma::csd::CsdConfig {
            window: firmware_core::spectrum::Window::Hann,
            nperseg,
            noverlap: nperseg / 2,
            nfft: nperseg,
            detrend: firmware_core::spectrum::Detrend::Constant,
        };
        let csd = super::oma::csd::csd_matrix(&channels, fps, c)?;
        let curve = |i: usize| -> Vec<f64> { csd.g.iter().map(|g| g[i * 2 + i].re).collect() };
        let f = crate::plots::db_figure(
            "camera_motion",
            (
                "Camera motion at the image centre: power spectral density",
                "PSD (dB re 1 px^2/Hz)",
            ),
            &csd.freq_hz,
            &[("x".to_string(), curve(0)), ("y".to_string(), curve(1))],
            &[],
        )?;
        figure = Some(f);
        line.push_str(", its spectrum camera_motion.png");
    }
    line.push('\n');
    Ok(CameraOutputs {
        text: line,
        csv: Some(csv),
        figure,
    })
}

/// [`camera_outputs`] staged in `out`: the report's line and the figure.
pub fn write_camera_outputs(
    out: &crate::outdir::Staged,
    viewed: &Viewed,
    fps: f64,
    plots: bool,
) -> anyhow::Result<(String, Option<crate::plots::Figure>)> {
    let c = camera_outputs(viewed, fps, plots)?;
    c.write_staged(out)?;
    Ok((c.text, c.figure))
}

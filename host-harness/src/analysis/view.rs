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

/// Writes `camera_motion.csv` and the camera motion's spectrum (`camera_motion.png`/`.svg`)
/// into `out` when references were given; returns the report's line naming them (empty
/// without references) and the spectrum's figure (for `report.html`).
pub fn write_camera_outputs(
    out: &crate::outdir::Staged,
    viewed: &Viewed,
    fps: f64,
    plots: bool,
) -> anyhow::Result<(String, Option<crate::plots::Figure>)> {
    let Some(m) = &viewed.motion else {
        return Ok((String::new(), None));
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
    out.write(
        "camera_motion.csv",
        crate::export::targets::camera_motion_csv(&rows),
    )?;
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
        f.write_staged(out)?;
        figure = Some(f);
        line.push_str(", its spectrum camera_motion.png");
    }
    line.push('\n');
    Ok((line, figure))
}

//! Synthetic recordings: one simulated run written as a real rig would record it — grey PNG
//! frames plus a transducer CSV — so that `host-harness analyze` can be tried at once and its
//! output checked against known modal parameters. No physics of its own: the run comes from
//! [`vibcam_model::simulate`] (nominal modal parameters, periodic over the record, closed-form
//! FRFs), the frames from the EPSA renderer of [`crate::imaging`] (the studies' camera).
//!
//! **Cantilever** (the default): CSV columns `t_s,base_acc,tip_acc` (m/s^2), camera 120 fps,
//! 0.1266 mm/px, the rig's white disk ([`vibcam_model::cantilever::TARGET`]).
//! **Grandstand**: CSV columns `t_s,force_n,tip_acc` (N, m/s^2; the FRFs are accelerances,
//! (m/s^2)/N), camera 50 fps, 0.05 mm/px, the platform's painted disk.
//!
//! Frame `k` is at `t = k / fps`, its exposure centred on it. A positive tip displacement moves the
//! disk **up** in the image (the `--axis y` convention of `analyze`).

pub mod camera_view;
pub mod cluttered;
pub mod field;
pub mod hammer;
pub mod release;
pub mod scene;
pub mod speckle;
pub mod targets;

use crate::imaging::{BlurRenderer, DiskTarget, TargetPath};
use crate::study::Preset;
use anyhow::Context as _;
use std::path::{Path, PathBuf};
use vibcam_model::{self as model, cantilever, grandstand, Acquisition, Rig};
use vibcam_readers::bad_input;

/// Everything a synthetic recording depends on.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingSpec {
    /// Seed of the excitation and noise streams (ChaCha8).
    pub seed: u64,
    /// Camera exposure, ms (centred on the frame time), >= 0 and shorter than the record.
    pub exposure_ms: f64,
    /// Frame rate, sample rate, fine time base and length.
    pub acquisition: Acquisition,
    /// Scale, mm per pixel.
    pub mm_per_px: f64,
    /// The target the camera films.
    pub target: DiskTarget,
    /// Threshold of the binary centroid, grey levels.
    pub threshold: u16,
    /// Structure, excitation and transducers.
    pub rig: Rig,
    /// Sensor read noise added to every frame before quantisation: Gaussian, std in grey
    /// levels (0 = none), from its own seeded stream.
    pub read_noise: f64,
    /// Also write every frame into `frames.mkv`, a lossless FFV1/Matroska video.
    pub video: bool,
    /// Frame the structure with a textured wall and a phone, in colour JPEG frames
    /// ([`cluttered`]).
    pub cluttered: bool,
}

impl RecordingSpec {
    /// The cantilever rig with its nominal parameters ([`cantilever::Rig::nominal`]): 10 s,
    /// 1200 frames at 120 fps, 2048 Hz accelerometers.
    pub fn cantilever(seed: u64, exposure_ms: f64) -> Self {
        RecordingSpec {
            seed,
            exposure_ms,
            acquisition: crate::study::cantilever::ACQUISITION,
            mm_per_px: cantilever::MM_PER_PX,
            target: cantilever::TARGET,
            threshold: cantilever::THRESHOLD,
            rig: Rig::Cantilever(cantilever::Rig::nominal()),
            read_noise: 0.0,
            video: false,
            cluttered: false,
        }
    }

    /// The grandstand with the mean modal parameters ([`grandstand::DecayTest::nominal`]): 100 s
    /// at 50 Hz, one frame per sample, 1 kHz fine time base.
    pub fn grandstand(seed: u64, exposure_ms: f64) -> Self {
        RecordingSpec {
            seed,
            exposure_ms,
            acquisition: Acquisition {
                fps: grandstand::FS_HZ,
                fs: grandstand::FS_HZ,
                fine_per_sample: grandstand::FINE,
                frames: grandstand::N,
            },
            mm_per_px: 1.0 / grandstand::PX_PER_MM,
            target: grandstand::TARGET,
            threshold: grandstand::THRESHOLD,
            rig: Rig::Grandstand(grandstand::DecayTest::nominal(seed)),
            read_noise: 0.0,
            video: false,
            cluttered: false,
        }
    }

    /// Transducer samples covered by the frames.
    pub fn samples(&self) -> usize {
        self.acquisition.samples()
    }

    /// Closed-form FRF from the input to the tip acceleration ([`Rig::frf`]).
    pub fn frf(&self, f_hz: f64) -> num_complex::Complex64 {
        self.rig.frf(f_hz)
    }

    /// Natural frequencies of the modes, Hz.
    pub fn natural_frequencies(&self) -> Vec<f64> {
        self.rig.natural_frequencies()
    }

    fn validate(&self) -> anyhow::Result<()> {
        self.acquisition.validate()?;
        let record_ms = 1000.0 * self.acquisition.frames as f64 / self.acquisition.fps;
        if !(self.exposure_ms >= 0.0 && self.exposure_ms < record_ms) {
            return Err(bad_input(format!(
                "exposure {} ms must be >= 0 and shorter than the record ({record_ms} ms)",
                self.exposure_ms,
            )));
        }
        if !(self.read_noise.is_finite() && (0.0..=64.0).contains(&self.read_noise)) {
            return Err(bad_input(format!(
                "read noise {} grey levels: must be between 0 and 64",
                self.read_noise
            )));
        }
        Ok(())
    }
}

/// Where a recording's frames go: `frames/frame_00000.png` ... and, with
/// [`RecordingSpec::video`], the same frames into `frames.mkv` (FFV1, lossless: the video's
/// frames are the PNGs' pixels bit for bit; a cluttered scene's JPEGs and colour video both hold
/// the composed colour frame, the video losslessly). Read noise is added here, to the float image,
/// before rounding to 8 bits.
/// What a [`FrameSink`] needs to know of the camera and the recording.
pub(crate) struct SinkCamera {
    /// Frame rate, fps (of the video).
    pub fps: f64,
    /// Also write `frames.mkv`.
    pub video: bool,
    /// Read noise, grey levels (0 = none).
    pub read_noise: f64,
    /// Seed of the recording (the read noise has a stream of its own).
    pub seed: u64,
    /// Compose a cluttered colour scene around the frames.
    pub cluttered: bool,
}

pub(crate) struct FrameSink {
    /// The frames directory being written (in the staging directory).
    frames_to: PathBuf,
    /// The frames directory as it will be named.
    frames_dir: PathBuf,
    video: Option<(vibcam_readers::frames::video::Ffv1Writer, PathBuf)>,
    noise: Option<(f64, rand_chacha::ChaCha8Rng)>,
    size: (usize, usize),
    px: Vec<u8>,
    clutter: Option<cluttered::Clutter>,
}

impl FrameSink {
    /// Opens the sink for frames of `size` (width, height) of `spec`'s recording written into
    /// `write_to` for the directory `dir`.
    pub fn create(
        spec: &RecordingSpec,
        (write_to, dir): (&Path, &Path),
        size: (usize, usize),
    ) -> anyhow::Result<FrameSink> {
        let camera = SinkCamera {
            fps: spec.acquisition.fps,
            video: spec.video,
            read_noise: spec.read_noise,
            seed: spec.seed,
            cluttered: spec.cluttered,
        };
        FrameSink::open(&camera, (write_to, dir), size)
    }

    /// Opens the sink for frames of `size` (width, height) of a recording by `camera`, written
    /// into `write_to` for the directory `dir`.
    pub fn open(
        camera: &SinkCamera,
        (write_to, dir): (&Path, &Path),
        size: (usize, usize),
    ) -> anyhow::Result<FrameSink> {
        use rand::SeedableRng as _;
        let frames_dir = dir.join("frames");
        let frames_to = write_to.join("frames");
        std::fs::create_dir_all(&frames_to)
            .with_context(|| format!("cannot create {}", frames_dir.display()))?;
        let clutter = camera
            .cluttered
            .then(|| cluttered::Clutter::new(size, camera.seed));
        let video = if camera.video {
            use vibcam_readers::frames::video::{Ffv1Writer, Pixels};
            let (file, fps) = (write_to.join("frames.mkv"), camera.fps);
            let w = match &clutter {
                // the colour frames the JPEGs hold, losslessly
                Some(c) => Ffv1Writer::create(&file, c.outer().0, c.outer().1, fps, Pixels::Rgb8),
                None => Ffv1Writer::create(&file, size.0, size.1, fps, Pixels::Grey8),
            }
            .map_err(|e| e.into_anyhow())?;
            Some((w, dir.join("frames.mkv")))
        } else {
            None
        };
        let noise = (camera.read_noise > 0.0).then(|| {
            // a stream of its own: the same seed gives the same motion with or without noise
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(camera.seed);
            rng.set_stream(0x006e_6f69_7365);
            (camera.read_noise, rng)
        });
        Ok(FrameSink {
            frames_to,
            frames_dir,
            video,
            noise,
            size,
            px: vec![0; size.0 * size.1],
            clutter,
        })
    }

    /// Writes frame `k` from its float image (8-bit scale, `width * height`): read noise,
    /// rounding to nearest and clamping, then the PNG and the video frame.
    pub fn put(&mut self, k: usize, img: &[f32]) -> anyhow::Result<()> {
        use rand_distr::Distribution as _;
        for (o, &v) in self.px.iter_mut().zip(img) {
            let v = match &mut self.noise {
                Some((sigma, rng)) => {
                    let z: f64 = rand_distr::StandardNormal.sample(rng);
                    (v as f64 + *sigma * z) as f32
                }
                None => v,
            };
            // as BlurRenderer::render rounds: without noise the pixels are the same
            *o = (v + 0.5).clamp(0.0, 255.0) as u8;
        }
        match &self.clutter {
            Some(c) => {
                let img = c.compose(&self.px);
                cluttered::write_jpeg(&img, &self.frames_to.join(format!("frame_{k:05}.jpg")))?;
                if let Some((w, _)) = &mut self.video {
                    w.write_frame_rgb(img.as_raw())
                        .map_err(|e| e.into_anyhow())?;
                }
            }
            None => {
                let png = self.frames_to.join(format!("frame_{k:05}.png"));
                save_grey_png(&png, self.size, &self.px)?;
                if let Some((w, _)) = &mut self.video {
                    w.write_frame(&self.px).map_err(|e| e.into_anyhow())?;
                }
            }
        }
        Ok(())
    }

    /// Closes the video; returns the frames directory and the video's path (as they will be
    /// named).
    pub fn finish(self) -> anyhow::Result<(PathBuf, Option<PathBuf>)> {
        let video = match self.video {
            Some((w, path)) => {
                w.finish().map_err(|e| e.into_anyhow())?;
                Some(path)
            }
            None => None,
        };
        Ok((self.frames_dir, video))
    }
}

/// The camera's view of a simulated run: the periodic tip path in pixels (positive down) and a
/// renderer sized for it. Returns the path and the renderer.
pub fn camera_path(spec: &RecordingSpec, run: &model::SyntheticRun) -> (TargetPath, BlurRenderer) {
    let fine_hz = spec.acquisition.fps * run.fine_per_frame as f64;
    let pad = TargetPath::pad_for(spec.exposure_ms, fine_hz);
    let period_px: Vec<f64> = run.tip_mm.iter().map(|mm| -mm / spec.mm_per_px).collect();
    let path = TargetPath::periodic(&period_px, pad, run.fine_per_frame, fine_hz);
    let renderer = BlurRenderer::for_path(&spec.target, &path.path_px, 1);
    (path, renderer)
}

/// Files of a written recording.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordingFiles {
    /// The frames directory (`frame_00000.png` ...).
    pub frames_dir: PathBuf,
    /// The same frames as a lossless video (`frames.mkv`), when asked for.
    pub video: Option<PathBuf>,
    /// `accel.csv` (`t_s,base_acc,tip_acc` or `t_s,force_n,tip_acc`).
    pub accel_csv: PathBuf,
    /// `recording.toml` (the parameters).
    pub toml: PathBuf,
    /// `README.txt` (the analyze command).
    pub readme: PathBuf,
    /// The exact `host-harness analyze` arguments for this recording (without the program).
    pub analyze_args: Vec<String>,
    /// Frame size, px (width, height).
    pub frame_size: (usize, usize),
    /// Number of frames written.
    pub frame_count: usize,
}

pub use vibcam_report::export::recording::{ModeRow, RecordingToml, TargetShape};

/// The parameters of a recording of `spec` with frames of `frame_size` (one target).
pub fn toml_of(spec: &RecordingSpec, frame_size: (usize, usize)) -> RecordingToml {
    let mut t = RecordingToml {
        preset: match spec.rig {
            Rig::Cantilever(_) => "cantilever",
            Rig::Grandstand(_) => "grandstand",
        },
        seed: spec.seed,
        exposure_ms: spec.exposure_ms,
        fps: spec.acquisition.fps,
        fs: spec.acquisition.fs,
        frames: spec.acquisition.frames,
        samples: spec.samples(),
        mm_per_px: spec.mm_per_px,
        radius_px: spec.target.radius_px,
        level: spec.target.level,
        edge_sigma_px: spec.target.edge_sigma_px,
        texture: spec.target.texture.name(),
        threshold: spec.threshold,
        frame_size: [frame_size.0, frame_size.1],
        read_noise: spec.read_noise,
        band_hz: None,
        tip_pp_mm: None,
        accel_noise_g: None,
        accel_tilt_gain: None,
        beam_length_m: None,
        f0_n: None,
        alpha: None,
        t0_s: None,
        process_noise_n: None,
        force_snr: None,
        accel_snr: None,
        targets: None,
        target_xi: None,
        target_x_px: None,
        modes: Vec::new(),
        target_shapes: Vec::new(),
    };
    match &spec.rig {
        Rig::Cantilever(r) => {
            t.band_hz = Some([r.band_hz.0, r.band_hz.1]);
            t.tip_pp_mm = Some(r.tip_pp_mm);
            t.accel_noise_g = Some(r.accel_noise_g);
            if r.accel_tilt_gain != 0.0 {
                t.accel_tilt_gain = Some(r.accel_tilt_gain);
                t.beam_length_m = Some(r.beam_length_m);
            }
            t.modes = r
                .modes
                .iter()
                .map(|m| mode_row(m.f_hz, m.zeta, Some(m.g_phi), None))
                .collect();
        }
        Rig::Grandstand(g) => {
            t.f0_n = Some(g.f0_n);
            t.alpha = Some(g.alpha);
            t.t0_s = Some(g.t0_s);
            t.process_noise_n = Some(g.process_noise_n);
            t.force_snr = Some(g.force_snr);
            t.accel_snr = Some(g.accel_snr);
            t.modes = g
                .modes
                .iter()
                .map(|m| mode_row(m.f_hz, m.zeta, None, Some(m.mass_kg)))
                .collect();
        }
    }
    t
}

/// A mode of `recording.toml`: frequency, damping ratio, and the cantilever's tip gain or the
/// grandstand's modal mass.
fn mode_row(f_hz: f64, zeta: f64, g_phi: Option<f64>, mass_kg: Option<f64>) -> ModeRow {
    ModeRow {
        f_hz,
        zeta,
        g_phi,
        mass_kg,
    }
}

/// `recording.toml` of a one-target recording of `spec` ([`RecordingToml`]).
pub fn recording_toml(spec: &RecordingSpec, frame_size: (usize, usize)) -> anyhow::Result<String> {
    toml_of(spec, frame_size).to_text()
}

/// Writes the recording of `spec` (with `targets`: K targets along the cantilever,
/// [`targets::write_targets_recording`]) into the new directory `dir`, staged and moved into
/// place (`force`: replacing an earlier `render --recording` output there).
pub fn write_recording_dir(
    spec: &RecordingSpec,
    targets: Option<usize>,
    dir: &Path,
    force: bool,
) -> anyhow::Result<RecordingFiles> {
    let out = vibcam_report::outdir::Staged::new(dir, force, "render --recording", &[])?;
    let files = match targets {
        None => write_recording_into(spec, out.dir(), dir)?,
        Some(k) => targets::write_targets_recording(spec, k, (out.dir(), dir))?,
    };
    out.commit()?;
    Ok(files)
}

/// The analyze arguments for a recording written in `dir`.
pub fn analyze_args(spec: &RecordingSpec, dir: &Path) -> Vec<String> {
    let d = dir.display();
    let mut v: Vec<String> = vec![
        "analyze".into(),
        "--frames".into(),
        format!("{d}/frames"),
        "--fps".into(),
        spec.acquisition.fps.to_string(),
        "--accel".into(),
        format!("{d}/accel.csv"),
        "--fs".into(),
        spec.acquisition.fs.to_string(),
        "--input-col".into(),
        spec.rig.input_col().into(),
        "--output-col".into(),
        "tip_acc".into(),
        "--time-col".into(),
        "t_s".into(),
        "--threshold".into(),
        spec.threshold.to_string(),
        "--mm-per-px".into(),
        spec.mm_per_px.to_string(),
        "--exposure-ms".into(),
        spec.exposure_ms.to_string(),
    ];
    if let Rig::Cantilever(_) = spec.rig {
        // the synthetic record is one period of a steady state: a rectangular window has no
        // leakage and gives the model's peaks (analyze's default Hann segment, made for a
        // real record, widens them: mode 1 at 7.3 Hz with |H1| 121 against the model's 68)
        v.push("--window".into());
        v.push("rect".into());
    }
    if let Rig::Grandstand(_) = spec.rig {
        // the grandstand's estimator and bands (method.md §3.1)
        for a in [
            "--window",
            "hamming",
            "--nperseg",
            "1111",
            "--noverlap",
            "555",
            "--nfft",
            "5000",
            "--bands",
            "1.5-2.25,2.25-2.9",
        ] {
            v.push(a.into());
        }
    }
    v.push("--out".into());
    v.push(format!("{d}/analysis"));
    v
}

/// Simulates one run of `preset` with its nominal modal parameters (seeded excitation and
/// noise) and writes it to `dir`: `frames/frame_00000.png` ..., `accel.csv`
/// (`t_s,base_acc,tip_acc` in m/s^2 for the cantilever, `t_s,force_n,tip_acc` for the
/// grandstand), `recording.toml` and `README.txt` with the exact analyze command.
pub fn write_synthetic_recording(
    preset: Preset,
    seed: u64,
    exposure_ms: f64,
    (write_to, dir): (&Path, &Path),
) -> anyhow::Result<RecordingFiles> {
    let spec = match preset {
        Preset::Cantilever => RecordingSpec::cantilever(seed, exposure_ms),
        Preset::Grandstand => RecordingSpec::grandstand(seed, exposure_ms),
    };
    write_recording_into(&spec, write_to, dir)
}

/// The README.txt paragraph on the recording's video, when it has one: the PNGs' frames bit
/// for bit, or (`colour`, a cluttered scene) the colour frames before JPEG compression.
fn video_readme(video: Option<&Path>, colour: bool) -> String {
    let what = if colour {
        "The same colour frames, losslessly (the JPEGs are lossy: luma within a few grey levels),"
    } else {
        "The same frames, bit for bit,"
    };
    video.map_or(String::new(), |v| {
        format!(
            "\n{what} are in {} (FFV1 in Matroska): `analyze --frames {}` analyses the video.\n",
            v.display(),
            v.display()
        )
    })
}

/// Writes the 8-bit grey frame `px` (`width * height` pixels, row 0 first) as a PNG at `path`.
pub fn save_grey_png(path: &Path, (w, h): (usize, usize), px: &[u8]) -> anyhow::Result<()> {
    image::GrayImage::from_raw(w as u32, h as u32, px.to_vec())
        .context("frame buffer size")?
        .save(path)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes the recording of `spec` to `dir` (see [`write_synthetic_recording`]).
pub fn write_recording(spec: &RecordingSpec, dir: &Path) -> anyhow::Result<RecordingFiles> {
    write_recording_into(spec, dir, dir)
}

/// Writes the recording of `spec` into `write_to` (a staging directory) for the directory
/// `dir` it will be moved to: the paths returned, in `README.txt` and in the analyze command
/// are `dir`'s.
pub fn write_recording_into(
    spec: &RecordingSpec,
    write_to: &Path,
    dir: &Path,
) -> anyhow::Result<RecordingFiles> {
    use std::fmt::Write as _;
    spec.validate()?;
    let run = model::simulate(&spec.rig, &spec.acquisition, spec.seed)?;
    let (path, mut renderer) = camera_path(spec, &run);
    let (w, h) = (renderer.width(), renderer.height());
    let mut sink = FrameSink::create(spec, (write_to, dir), (w, h))?;
    let mut img = vec![0f32; w * h];
    for k in 0..spec.acquisition.frames {
        let (a, b) = path.frame_window(k, spec.exposure_ms);
        renderer.render_float(a, b, &mut img);
        sink.put(k, &img)?;
    }
    let (frames_dir, video) = sink.finish()?;
    let csv = vibcam_report::export::recording::accel_csv(
        spec.rig.input_col(),
        (&run.input, &run.tip_acc),
        spec.acquisition.fs,
    );
    let accel_csv = dir.join("accel.csv");
    std::fs::write(write_to.join("accel.csv"), csv)
        .with_context(|| format!("cannot write {}", accel_csv.display()))?;
    let toml = dir.join("recording.toml");
    std::fs::write(
        write_to.join("recording.toml"),
        recording_toml(spec, (w, h))?,
    )
    .with_context(|| format!("cannot write {}", toml.display()))?;
    let args = analyze_args(spec, dir);
    let (what, unit) = match spec.rig {
        Rig::Cantilever(_) => ("cantilever", "|tip/base|"),
        Rig::Grandstand(_) => ("grandstand", "|accelerance| (m/s^2)/N"),
    };
    let mut readme = format!(
        "Synthetic {what} recording ({} frames at {} fps, exposure {} ms, {} transducer \
         samples at {} Hz, seed {}).\n\nAnalyse it with:\n\n  host-harness {}\n\n\
         Expected: modes near",
        spec.acquisition.frames,
        spec.acquisition.fps,
        spec.exposure_ms,
        spec.samples(),
        spec.acquisition.fs,
        spec.seed,
        args.join(" ")
    );
    for f in spec.natural_frequencies() {
        let a = spec.frf(f).norm();
        let a = if a < 0.01 {
            format!("{a:.4e}")
        } else {
            format!("{a:.2}")
        };
        let _ = write!(readme, " {f} Hz ({unit} = {a})");
    }
    readme.push_str(
        " for both systems (one record is one noisy estimate); see recording.toml for all \
         parameters.\n",
    );
    readme.push_str(&video_readme(video.as_deref(), false));
    let readme_path = dir.join("README.txt");
    std::fs::write(write_to.join("README.txt"), readme)
        .with_context(|| format!("cannot write {}", readme_path.display()))?;
    Ok(RecordingFiles {
        frames_dir,
        video,
        accel_csv,
        toml,
        readme: readme_path,
        analyze_args: args,
        frame_size: (w, h),
        frame_count: spec.acquisition.frames,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rendered_disk_is_centred_on_the_displacement() {
        // a sharp frame's intensity centroid is the tip position (the EPSA shift is exact for
        // the band-limited targets), for both rigs
        for mut s in [
            RecordingSpec::cantilever(3, 0.0),
            RecordingSpec::grandstand(3, 0.0),
        ] {
            s.acquisition.frames = 15;
            s.acquisition.fs = s.acquisition.fps * 16.0;
            s.acquisition.fine_per_sample = 1;
            let run = model::simulate(&s.rig, &s.acquisition, 3).unwrap();
            let (path, mut r) = camera_path(&s, &run);
            let (w, h) = (r.width(), r.height());
            let mut img = vec![0.0f32; w * h];
            for k in 0..15 {
                let (a, b) = path.frame_window(k, 0.0);
                r.render_float(a, b, &mut img);
                let (mut m, mut sy) = (0.0, 0.0);
                for (i, v) in img.iter().enumerate() {
                    m += f64::from(*v);
                    sy += f64::from(*v) * (i / w) as f64;
                }
                let want = r.rest_y() - run.tip_mm[k * run.fine_per_frame] / s.mm_per_px;
                // The grandstand's 1.5 px Gaussian edge is band-limited (1.5e-5 of DC at Nyquist),
                // so the DFT shift is exact to f32 rounding; the cantilever's 0.5 px edge is not
                // (0.29 at Nyquist): the shift is then a periodic band-limited interpolation of
                // the sampled disk, which moves the intensity centroid by up to ~2e-3 px.
                let tol = if s.target.edge_sigma_px >= 1.0 {
                    1e-4
                } else {
                    5e-3
                };
                assert!(
                    (sy / m - want).abs() < tol,
                    "frame {k}: {} vs {want}",
                    sy / m
                );
            }
        }
    }
}

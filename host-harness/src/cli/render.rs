//! `host-harness render`: what the camera saw. PNG frames of the simulated target at chosen
//! times, sharp and blurred, or (`--recording DIR`) a complete synthetic recording (frames +
//! accelerometer CSV) that `host-harness analyze` can read.

use crate::bad_input;
use crate::recording::scene::Scene;
use crate::recording::RecordingSpec;
use crate::study::Preset;
use std::path::PathBuf;

/// Arguments of `host-harness render`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario whose camera is rendered.
    #[arg(long, default_value = "grandstand", value_parser = super::args::choice(&Preset::ALL, Preset::name))]
    pub preset: Preset,
    /// Seed of the simulated run (the study's run 0 of this seed).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Exposure time of the blurred frames, ms (centred on the frame time). Default 100 for
    /// single frames; a recording (--recording) needs it given, at most the frame period
    /// unless --allow-long-exposure.
    #[arg(long, value_name = "MS")]
    pub exposure_ms: Option<f64>,
    /// With --recording: allow an exposure longer than the frame period (no real camera does
    /// that; the paper's simulation does).
    #[arg(long, requires = "recording")]
    pub allow_long_exposure: bool,
    /// Frame times in seconds, comma separated (default: a few instants of the response).
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    pub times: Option<Vec<f64>>,
    /// Output directory of the PNG frames.
    #[arg(long, default_value = "out/render")]
    pub out: PathBuf,
    /// Instead of single frames, write a complete synthetic recording (frames/, accel.csv,
    /// recording.toml, README.txt with the `analyze` command) into this directory.
    #[arg(long, value_name = "DIR")]
    pub recording: Option<PathBuf>,
    /// Replace the output directory if it is an earlier output of the same `render` command
    /// (its manifest lists every file in it: nothing was added, not even an analysis), as a
    /// whole.
    #[arg(long)]
    pub force: bool,
    /// With --recording and the cantilever: K targets (2-16) along the beam, target k at
    /// k/K of its length (the last at the tip), each moving with the mode shapes there; the true
    /// shapes go into recording.toml.
    #[arg(long, value_name = "K", requires = "recording", value_parser = super::args::int_range(2..=16))]
    pub targets: Option<usize>,
    /// With --recording: also write the frames as a lossless video, `frames.mkv` (FFV1 in
    /// Matroska, bit-identical to the PNGs; with --scene cluttered the colour frames before
    /// JPEG compression; needs the `ffmpeg` program).
    #[arg(long, requires = "recording")]
    pub video: bool,
    /// With --recording: sensor read noise added to every frame before rounding to 8 bits,
    /// Gaussian, std in grey levels (0 = none).
    #[arg(
        long,
        value_name = "SIGMA",
        default_value_t = 0.0,
        requires = "recording"
    )]
    pub read_noise: f64,
    /// With --recording --targets: `cluttered` frames the structure with a textured wall as
    /// bright as the tags and a phone beside it, in colour JPEG frames, and writes points.csv
    /// (a window per target for `analyze --points`); `plain` (default): grey PNG frames of the
    /// targets on black.
    #[arg(long, value_enum, default_value_t = SceneArg::Plain, requires = "recording")]
    pub scene: SceneArg,
    /// With --recording --scene cluttered: `release` films a model structure of 28 alike tags
    /// on four storeys in front of a white brick wall, pulled and released (23 fps, jumps of
    /// up to 120 px between frames), with points.csv (windows and storeys as `group`) and
    /// truth.csv (and with --video the colour frames in frames.mkv); it takes no --preset,
    /// --targets, --exposure-ms, --read-noise or --texture (its own).
    /// `rig` (default): the preset's excitation.
    #[arg(long, value_enum, default_value_t = MotionArg::Rig, requires = "recording")]
    pub motion: MotionArg,
    /// With --recording: what is painted on the targets: `plain` (default) or `speckle` (dark
    /// dots on the disk: a texture for `--tracker lk`; docs/method.md §2.11).
    #[arg(long, value_enum, default_value_t = TextureArg::Plain, requires = "recording")]
    pub texture: TextureArg,
}

/// How the structure of a recording moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MotionArg {
    /// The preset's excitation.
    Rig,
    /// Pulled and released by hand (with --scene cluttered).
    Release,
}

/// What is painted on the targets of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TextureArg {
    /// A uniform disk.
    Plain,
    /// Dark speckle dots on the disk.
    Speckle,
}

/// The scene around the targets of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum SceneArg {
    /// The targets on black.
    Plain,
    /// A wall, a phone and colour JPEG frames around them.
    Cluttered,
}

/// Runs `host-harness render`.
pub fn run(args: Args) -> anyhow::Result<()> {
    if args.motion == MotionArg::Release {
        return render_release(&args);
    }
    if args.scene == SceneArg::Cluttered && args.targets.is_none() {
        return Err(bad_input(
            "--scene cluttered: needs --targets K (or --motion release, its own structure)",
        ));
    }
    let exposure_ms = args.exposure_ms.unwrap_or(100.0);
    if !(exposure_ms.is_finite() && exposure_ms >= 0.0) {
        return Err(bad_input(format!(
            "--exposure-ms {exposure_ms}: must be a non-negative number"
        )));
    }
    let record_ms = crate::study::StudyConfig::preset(args.preset).record_ms();
    if exposure_ms > record_ms {
        return Err(bad_input(format!(
            "--exposure-ms {exposure_ms}: longer than the simulated record ({record_ms} ms)"
        )));
    }
    if let Some(dir) = &args.recording {
        let mut spec = match args.preset {
            Preset::Cantilever => RecordingSpec::cantilever(args.seed, exposure_ms),
            Preset::Grandstand => RecordingSpec::grandstand(args.seed, exposure_ms),
        };
        check_recording_exposure(&args, spec.acquisition.fps)?;
        spec.read_noise = args.read_noise;
        spec.video = args.video;
        spec.cluttered = args.scene == SceneArg::Cluttered;
        spec.target.texture = match args.texture {
            TextureArg::Plain => crate::model::Texture::Plain,
            TextureArg::Speckle => crate::model::Texture::Speckle,
        };
        if args.targets.is_some() && args.preset != Preset::Cantilever {
            return Err(bad_input("--targets: only with --preset cantilever"));
        }
        let files = crate::recording::write_recording_dir(&spec, args.targets, dir, args.force)?;
        return super::stdout(&format!(
            "wrote a synthetic {} recording in {}: {} frames of {} x {} px in {}, {}, {}; see {}\n",
            args.preset.name(),
            dir.display(),
            files.frame_count,
            files.frame_size.0,
            files.frame_size.1,
            match &files.video {
                Some(v) => format!("{} and {}", files.frames_dir.display(), v.display()),
                None => files.frames_dir.display().to_string(),
            },
            files.accel_csv.display(),
            files.toml.display(),
            dir.join("README.txt").display()
        ));
    }
    let scene = Scene::of(args.preset, args.seed, args.times.clone(), exposure_ms)?;
    let written = scene.write_frames(&args.out, args.force, exposure_ms)?;
    let mut list = String::new();
    for p in &written {
        let name = p.file_name().unwrap_or_default();
        list.push_str(&format!("{}\n", args.out.join(name).display()));
    }
    super::stdout(&list)?;
    eprintln!("wrote {} frames in {}", written.len(), args.out.display());
    Ok(())
}

/// A recording's exposure: given, and at most the frame period unless asked.
fn check_recording_exposure(args: &Args, fps: f64) -> anyhow::Result<()> {
    let period_ms = 1000.0 / fps;
    match args.exposure_ms {
        None => Err(bad_input(format!(
            "--recording needs --exposure-ms: the camera records at {fps} fps, a frame period \
             of {period_ms:.3} ms, the longest exposure it can have"
        ))),
        Some(e) if e > period_ms && !args.allow_long_exposure => Err(bad_input(format!(
            "--exposure-ms {e}: longer than the frame period ({period_ms:.3} ms at {fps} fps), \
             which no camera does; --allow-long-exposure to simulate it anyway"
        ))),
        Some(_) => Ok(()),
    }
}

/// `render --recording DIR --scene cluttered --motion release`.
fn render_release(args: &Args) -> anyhow::Result<()> {
    let Some(dir) = &args.recording else {
        return Err(bad_input("--motion release: needs --recording DIR"));
    };
    if args.scene != SceneArg::Cluttered {
        return Err(bad_input(
            "--motion release: needs --scene cluttered (the structure in front of a wall)",
        ));
    }
    if args.targets.is_some()
        || args.exposure_ms.is_some()
        || args.read_noise != 0.0
        || args.texture != TextureArg::Plain
    {
        return Err(bad_input(
            "--motion release: its scene is fixed (28 tags, 23 fps, 2 ms): no --targets, \
             --exposure-ms, --read-noise or --texture",
        ));
    }
    let n = crate::recording::release::write_release_dir(dir, args.force, args.video)?;
    super::stdout(&format!(
        "wrote a pull-and-release recording in {}: {n} colour frames of {} x {} px at {} fps, \
         points.csv, truth.csv; see {}\n",
        dir.display(),
        crate::recording::release::SIZE.0,
        crate::recording::release::SIZE.1,
        crate::recording::release::FPS,
        dir.join("README.txt").display()
    ))
}

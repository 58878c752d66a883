//! The files of a synthetic impact hammer test (`simulate-hammer`): the force as a DAQ records
//! it and the points' displacements as a camera records them, from one trigger, each at its own
//! rate, with noise; and the true modes ([`vibcam_model::hammer`]).

use rand::SeedableRng as _;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution as _, Normal};
use std::fmt::Write as _;
use std::path::Path;
use vibcam_model::hammer::{HammerTest, Hit, THREE_MODE_POINTS};
use vibcam_report::outdir::Staged;

/// What to write.
#[derive(Debug, Clone, PartialEq)]
pub struct HammerRecording {
    /// Record length, s.
    pub seconds: f64,
    /// The DAQ's rate (the force), Hz.
    pub daq_hz: f64,
    /// The camera's rate (the displacements), Hz.
    pub camera_hz: f64,
    /// The hits' peak forces, N, one every 3 s from 0.2 s; pulses 0.6 ms wide.
    pub peaks_n: Vec<f64>,
    /// A rebound 4 ms after the second hit, of 40 % of its peak.
    pub double_hit: bool,
    /// The force channel clipped at this level, N.
    pub clip_n: Option<f64>,
    /// The force's noise, N (standard deviation).
    pub force_noise_n: f64,
    /// The displacements' noise, mm (standard deviation).
    pub camera_noise_mm: f64,
    /// Random seed.
    pub seed: u64,
    /// A roving hammer's hit points (1-based, of the five): one record each, every one with
    /// the same hits; empty: one record, hit at point 2.
    pub hit_points: Vec<usize>,
}

impl HammerRecording {
    /// The test: [`HammerTest::three_modes`] with this recording's hits.
    pub fn test(&self) -> HammerTest {
        let mut hits = Hit::every_3_s(&self.peaks_n);
        if self.double_hit && hits.len() > 1 {
            hits.push(Hit {
                t_s: hits[1].t_s + 0.004,
                width_s: 0.0006,
                peak_n: 0.4 * hits[1].peak_n,
            });
        }
        HammerTest::three_modes(hits)
    }
}

/// The force of `test` at the DAQ's rate as `force.csv` holds it (`t_s,force_n`), noise and
/// clipping included.
fn force_csv(test: &HammerTest, r: &HammerRecording, noise: &mut dyn FnMut() -> f64) -> String {
    let n = (r.seconds * r.daq_hz).round() as usize;
    let mut s = String::from("t_s,force_n\n");
    for k in 0..n {
        let t = k as f64 / r.daq_hz;
        let mut f = test.force(t) + r.force_noise_n * noise();
        if let Some(c) = r.clip_n {
            f = f.min(c);
        }
        let _ = writeln!(s, "{t},{f:.5}");
    }
    s
}

/// The five points' displacements of `test` at the camera's rate as `camera.csv` holds them
/// (`t_s,p1..p5`, mm), noise included.
fn camera_csv(test: &HammerTest, r: &HammerRecording, noise: &mut dyn FnMut() -> f64) -> String {
    let m = (r.seconds * r.camera_hz).round() as usize;
    let mut s = String::from("t_s");
    for o in 0..THREE_MODE_POINTS {
        let _ = write!(s, ",p{}", o + 1);
    }
    s.push('\n');
    for k in 0..m {
        let t = k as f64 / r.camera_hz;
        let _ = write!(s, "{t}");
        for o in 0..THREE_MODE_POINTS {
            let x = 1e3 * test.displacement(o, t) + r.camera_noise_mm * noise();
            let _ = write!(s, ",{x:.7}");
        }
        s.push('\n');
    }
    s
}

/// Writes `force.csv` (`t_s,force_n`), `camera.csv` (`t_s,p1..p5`, mm), `truth.csv`
/// (`mode,f_hz,damping,point,shape`) and `README.txt` (the `ema` command) into `out`, staged
/// (complete or absent). With hit points (a roving hammer), `force_P.csv` and `camera_P.csv`
/// for each point `P` hit instead of the first two.
pub fn write_hammer_recording(out: &Path, force: bool, r: &HammerRecording) -> anyhow::Result<()> {
    let test = r.test();
    let dir = Staged::new(out, force, "simulate-hammer", &[])?;
    let mut rng = ChaCha8Rng::seed_from_u64(r.seed);
    let unit = Normal::new(0.0, 1.0).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut noise = || unit.sample(&mut rng);
    let command = if r.hit_points.is_empty() {
        dir.write("force.csv", force_csv(&test, r, &mut noise))?;
        dir.write("camera.csv", camera_csv(&test, r, &mut noise))?;
        "hit at point 2.\nforce.csv: the force at {daq} Hz (N); camera.csv: the displacements at \
         {camera} Hz (mm), from the same trigger.\n\nhost-harness ema --response camera.csv \
         --excitation force.csv --excitation-col force_n --impact --f-max-hz 200\n"
            .to_string()
    } else {
        let mut roving = String::new();
        for &p in &r.hit_points {
            let at = HammerTest {
                drive: p - 1,
                ..test.clone()
            };
            dir.write(&format!("force_{p}.csv"), force_csv(&at, r, &mut noise))?;
            dir.write(&format!("camera_{p}.csv"), camera_csv(&at, r, &mut noise))?;
            let _ = write!(roving, " --roving {p}=camera_{p}.csv,force_{p}.csv");
        }
        format!(
            "hit by a roving hammer at points {:?}, one record each.\nforce_P.csv: the force \
             at point P at {{daq}} Hz (N); camera_P.csv: the displacements then at {{camera}} Hz \
             (mm), from the same trigger.\n\nhost-harness ema{roving} --excitation-col \
             force_n --impact --f-max-hz 200\n",
            r.hit_points
        )
    };
    let mut s = String::from("mode,f_hz,damping,point,shape\n");
    for (i, md) in test.modes.iter().enumerate() {
        for (o, v) in md.shape.iter().enumerate() {
            let _ = writeln!(s, "{},{},{},{},{v}", i + 1, md.f_hz, md.damping, o + 1);
        }
    }
    dir.write("truth.csv", s)?;
    dir.write(
        "README.txt",
        format!(
            "A synthetic impact hammer test: three modes (truth.csv), five points, {}",
            command
                .replace("{daq}", &r.daq_hz.to_string())
                .replace("{camera}", &r.camera_hz.to_string())
        ),
    )?;
    dir.commit()
}

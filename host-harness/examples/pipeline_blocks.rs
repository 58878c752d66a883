//! How much does block-wise streaming change the vision H1 of the cantilever rig, compared
//! with upsampling the whole 10 s record at once (what `study --preset cantilever` and
//! `analyze` do)? Two block-wise methods, both with 1 s blocks of 120 frames -> 2048 samples:
//!
//! * the firmware pipeline (`firmware_core::pipeline::VisionH1`): blocks every half second,
//!   end-matched, central half kept;
//! * whole blocks, each upsampled on its own and kept entire (method.md §2.2 applied per block).
//!
//! Same Welch settings for all (2048-point Hann segments, 50 % overlap, on the span the
//! pipeline covers), noise-free camera (the exact tip displacement at the frame instants), the
//! rig's base acceleration as the reference channel. Prints the ratio of the picked peak
//! amplitudes to the whole-record path's (mean, min, max over the runs) per mode.
//!
//! `cargo run --release -p host-harness --example pipeline_blocks [runs]`

use firmware_core::peaks;
use firmware_core::pipeline::{scratch_capacity, PipelineConfig, VisionH1};
use firmware_core::spectrum::{Detrend, WelchConfig, WelchH1, Window};
use firmware_core::upsample::{self, Upsampler};
use host_harness::recording::RecordingSpec;

const N: usize = 1200;
const M: usize = 20480;
const SEG: usize = 2048;
const SC: usize = scratch_capacity(120, SEG, SEG);
type Pipe = VisionH1<121, 2816, SEG, SC>;
type Welch = WelchH1<SEG, SEG, 0>;

fn welch_cfg() -> WelchConfig {
    WelchConfig {
        fs_hz: 2048.0,
        nperseg: SEG,
        noverlap: SEG / 2,
        nfft: SEG,
        window: Window::Hann,
        detrend: Detrend::Constant,
    }
}

fn err(e: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("{e}")
}

/// H1 of `y` over `x` (equal lengths) with the common Welch settings.
fn welch(x: &[f32], y: &[f32]) -> anyhow::Result<Box<Welch>> {
    let mut w = Box::new(Welch::try_new(welch_cfg()).map_err(err)?);
    w.push(x, y).map_err(err)?;
    Ok(w)
}

fn main() -> anyhow::Result<()> {
    let runs: u64 = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(20);
    let bands = [(5.0f32, 15.0f32), (25.0, 45.0)];
    // ratios[method][mode]
    let mut ratios = vec![vec![Vec::new(); 2]; 2];
    for seed in 0..runs {
        let spec = RecordingSpec::cantilever(seed, 0.0);
        let sim = host_harness::model::simulate(&spec.rig, &spec.acquisition, spec.seed)?;
        let base: Vec<f32> = sim.input.iter().map(|v| *v as f32).collect();
        let frames: Vec<f32> = (0..N)
            .map(|k| sim.tip_mm[k * sim.fine_per_frame] as f32)
            .collect();
        // whole record (exact here: the simulated record is periodic over its 10 s)
        let mut up = Box::new(
            Upsampler::<M, { upsample::scratch_capacity(N, M) }>::try_new(N, M).map_err(err)?,
        );
        let mut whole = vec![0.0f32; M];
        up.process_acceleration(&frames, &mut whole, 120.0, 1e-3)
            .map_err(err)?;
        // whole 1 s blocks
        let mut up1 = Upsampler::<SEG, { upsample::scratch_capacity(120, SEG) }>::try_new(120, SEG)
            .map_err(err)?;
        let mut blocks = vec![0.0f32; M];
        for (blk, out) in frames.chunks(120).zip(blocks.chunks_mut(SEG)) {
            up1.process_acceleration(blk, out, 120.0, 1e-3)
                .map_err(err)?;
        }
        // the pipeline, fed as the data would arrive; its record starts at sample 512
        let mut p = Box::new(
            Pipe::try_new(PipelineConfig::one_second_blocks(120, SEG, Some(1e-3))).map_err(err)?,
        );
        let mut next = 0;
        for (j, v) in frames.iter().enumerate() {
            p.push_frame(*v).map_err(err)?;
            let until = (j + 1) * SEG / 120;
            p.push_adc(&base[next..until]).map_err(err)?;
            next = until;
        }
        // the pipeline covers 512 .. 512 + 19 blocks x 1024 samples; compare on that span
        let span = 512..512 + 1024 * p.blocks() as usize;
        let reference = welch(&base[span.clone()], &whole[span.clone()])?;
        let old = welch(&base[span.clone()], &blocks[span])?;
        let pw = p.welch();
        for (b, &band) in bands.iter().enumerate() {
            let pick = |h1: &dyn Fn(usize) -> Option<firmware_core::Complex32>| {
                peaks::pick_with(SEG / 2 + 1, 1.0, band, false, h1)
            };
            let r = pick(&|k| reference.accumulator().h1(k));
            let s = pick(&|k| pw.h1(k));
            let o = pick(&|k| old.accumulator().h1(k));
            if let (Some(r), Some(s), Some(o)) = (r, s, o) {
                ratios[0][b].push((s.amplitude / r.amplitude) as f64);
                ratios[1][b].push((o.amplitude / r.amplitude) as f64);
            }
        }
    }
    println!("{runs} cantilever runs, noise-free camera, 2048-point Hann segments, 50 % overlap");
    println!("peak amplitude / whole-record peak amplitude: mean [min, max]");
    let names = ["pipeline (overlapped, end-matched)", "whole blocks"];
    for (name, per_mode) in names.iter().zip(&ratios) {
        for (b, r) in per_mode.iter().enumerate() {
            let mean = r.iter().sum::<f64>() / r.len().max(1) as f64;
            let min = r.iter().cloned().fold(f64::INFINITY, f64::min);
            let max = r.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            println!("{name}, mode {}: {mean:.4} [{min:.4}, {max:.4}]", b + 1);
        }
    }
    Ok(())
}

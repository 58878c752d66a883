//! firmware-core on a Cortex-M4F (QEMU `mps2-an386`): the measurement chain's kernels run on
//! the target, their results are checked against independent references computed here (naive
//! loops, closed forms), and the instruction counts of the hot paths are bracketed by calls of
//! [`bench_mark`] for the `libmarks.so` QEMU plugin (see `bench.sh`).
//!
//! Exit code (semihosting): 0 only if every check passed.
//!
//! Checks:
//! * centroid of a 320 x 240 frame held in flash (one disk, 8- and 16-bit, binary and weighted)
//!   against a naive double loop and against the disk's centre (exact by symmetry);
//! * streaming Welch H1 (nperseg = nfft = 2048, Hann, 50 % overlap) of a 2048 Hz input/output
//!   pair through a resonator with a known closed-form FRF: peak frequency and amplitude;
//! * Fourier upsampling of a 120 fps record (1 s) to 2048 Hz, displacement and acceleration,
//!   against the analytic band-limited signal;
//! * the complete vision channel in static RAM (`firmware_core::pipeline::VisionH1`: 120 fps
//!   frames and 2048 Hz ADC samples in, interleaved as they would arrive, upsampled to
//!   acceleration, 2048-point streaming H1 out) against a known transfer (H1 = 2);
//! * the camera/ADC sync plan for 2048 Hz / 120 fps.
//!
//! Benchmarks (each between two `bench_mark` calls; the label is printed before the pair):
//! centroid per mode and depth, one Welch segment pair for nperseg 1024/2048/4096, upsampling
//! 120 -> 2048 and 1200 -> 20480, one second of the complete pipeline.
#![no_std]
#![no_main]

use core::f32::consts::PI;
use core::hint::black_box;
use core::panic::PanicInfo;

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use firmware_core::centroid::track::{TrackConfig, Tracker};
use firmware_core::centroid::{
    self, Centroid, CentroidConfig, Flags, Frame, FrameError, Mode, Pixel,
};
use firmware_core::heapless::spsc::{Consumer, Producer, Queue};
use firmware_core::lk::{Interpolation, LkConfig, LkTracker, Smoothing};
use firmware_core::pipeline::{PipelineConfig, VisionH1};
use firmware_core::spectrum::cross::{pick_peaks, CrossSpectra};
use firmware_core::spectrum::{Detrend, WelchConfig, WelchH1, Window};
use firmware_core::sync::{SyncConfig, SyncPlan};
use firmware_core::upsample::{self, Upsampler};
use firmware_core::{peaks, Complex32};

// ---------------------------------------------------------------------------------------------
// Instruction-count markers

/// Marker for the `libmarks.so` plugin: it prints the instructions executed between
/// consecutive calls.
#[inline(never)]
#[unsafe(no_mangle)]
pub extern "C" fn bench_mark() {
    // SAFETY: a `nop` has no effect; it only keeps the function from being merged or removed.
    unsafe { core::arch::asm!("nop") }
}

/// Runs `f` between two markers, after printing `label` (bench.sh pairs labels and segments).
#[inline(always)]
fn measured<R>(label: &str, f: impl FnOnce() -> R) -> R {
    hprintln!("bench: {}", label);
    bench_mark();
    let r = f();
    bench_mark();
    black_box(r)
}

// ---------------------------------------------------------------------------------------------
// Printing without core's float formatting (its `flt2dec` keeps panic paths; see panic-check)

/// An `f32` printed with 6 decimals through integer formatting.
struct Fx(f32);
impl core::fmt::Display for Fx {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let v = self.0;
        if !v.is_finite() || libm::fabsf(v) >= 1.8e13 {
            return f.write_str(if v.is_nan() { "NaN" } else { "out-of-range" });
        }
        let sign = if v < 0.0 { "-" } else { "" };
        let scaled = libm::round(libm::fabs(f64::from(v)) * 1e6) as u64;
        write!(
            f,
            "{}{}.{:06}",
            sign,
            scaled / 1_000_000,
            scaled % 1_000_000
        )
    }
}

/// An optional centroid `(x, y)`.
struct Pos(Option<(f32, f32)>);
impl core::fmt::Display for Pos {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.0 {
            Some((x, y)) => write!(f, "({}, {})", Fx(x), Fx(y)),
            None => f.write_str("none"),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The frame in flash

const W: usize = 320;
const H: usize = 240;
/// Disk centre times two (half-pixel units) and radius: centre (171.5, 97.0), radius 20 px.
const CX2: i32 = 343;
const CY2: i32 = 194;
const R: i32 = 20;
const BACKGROUND: u16 = 10;
const LEVEL: u16 = 200;
const THRESHOLD: u16 = 100;

const fn inside(x: usize, y: usize) -> bool {
    let dx = 2 * x as i32 - CX2;
    let dy = 2 * y as i32 - CY2;
    dx * dx + dy * dy <= 4 * R * R
}

/// Rows of background below the frame in the 8-bit canvas: a frame read from the canvas at an
/// offset of `dy` rows and `dx` columns shows the disk moved by `(-dx, -dy)` (the moving
/// target of the tracking window, without a second frame in flash).
const PAD_ROWS: usize = 16;
const CANVAS: usize = W * (H + PAD_ROWS);

const fn disk_u8() -> [u8; CANVAS] {
    let mut f = [BACKGROUND as u8; CANVAS];
    let mut i = 0;
    while i < W * H {
        if inside(i % W, i / W) {
            f[i] = LEVEL as u8;
        }
        i += 1;
    }
    f
}

const fn disk_u16() -> [u16; W * H] {
    let mut f = [BACKGROUND * 64; W * H];
    let mut i = 0;
    while i < W * H {
        if inside(i % W, i / W) {
            f[i] = LEVEL * 64;
        }
        i += 1;
    }
    f
}

/// Worst case for the block skip of the 8-bit kernel: a bright pixel in every 5 (no 64-pixel
/// block without a pixel above the threshold).
const fn dense_u8() -> [u8; W * H] {
    let mut f = [BACKGROUND as u8; W * H];
    let mut i = 0;
    while i < W * H {
        if ((i % W) * 7 + (i / W) * 13).is_multiple_of(5) {
            f[i] = LEVEL as u8;
        }
        i += 1;
    }
    f
}

/// Dense 8-bit frame in flash (76 800 B).
static DENSE_U8: [u8; W * H] = dense_u8();
/// 8-bit frame in flash (76 800 B; its first `W * H` pixels) and 16 rows of background below
/// it (5 120 B, for the moving views of [`moved`]).
static FRAME_U8: [u8; CANVAS] = disk_u8();

/// The 8-bit frame with the disk moved by `(-dx, -dy)` pixels (`dx < W`, `dy < PAD_ROWS`):
/// centre `(171.5 - dx, 97 - dy)`.
fn moved(dx: usize, dy: usize) -> &'static [u8] {
    let off = dy * W + dx;
    FRAME_U8.get(off..off + W * H).unwrap_or(&[])
}
/// 16-bit frame in flash (153 600 B), same scene times 64.
static FRAME_U16: [u16; W * H] = disk_u16();

/// Naive reference: (sum of weights, sum of x * w, sum of y * w) over pixels above `t`.
fn naive_moments(px: impl Iterator<Item = u16>, t: u16, weighted: bool) -> (u64, u64, u64) {
    let (mut w, mut sx, mut sy) = (0u64, 0u64, 0u64);
    for (i, p) in px.enumerate() {
        if p > t {
            let wi = if weighted { u64::from(p - t) } else { 1 };
            w += wi;
            sx += wi * (i % W) as u64;
            sy += wi * (i / W) as u64;
        }
    }
    (w, sx, sy)
}

// ---------------------------------------------------------------------------------------------
// Signals

/// Small deterministic generator (PCG-style LCG), uniform in [-1, 1).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32 / (1u64 << 23) as f32) - 1.0
    }
}

const FS: f32 = 2048.0;
const F0: f32 = 180.0;
const ZETA: f32 = 0.02;

/// Resonator `y[n] = x[n] + a1 y[n-1] + a2 y[n-2]` with poles at `exp((-zeta +- i sqrt(1 -
/// zeta^2)) w0 / fs)`: a sampled single-degree-of-freedom resonance at F0.
struct Resonator {
    a1: f32,
    a2: f32,
    y1: f32,
    y2: f32,
}
impl Resonator {
    fn new() -> Self {
        let w0 = 2.0 * PI * F0 / FS;
        let r = libm::expf(-ZETA * w0);
        let th = w0 * libm::sqrtf(1.0 - ZETA * ZETA);
        Resonator {
            a1: 2.0 * r * libm::cosf(th),
            a2: -r * r,
            y1: 0.0,
            y2: 0.0,
        }
    }
    fn step(&mut self, x: f32) -> f32 {
        let y = x + self.a1 * self.y1 + self.a2 * self.y2;
        self.y2 = self.y1;
        self.y1 = y;
        y
    }
    /// Closed-form frequency response at `f` Hz: 1 / (1 - a1 z^-1 - a2 z^-2), z = e^{i w}.
    fn response(&self, f: f32) -> Complex32 {
        let w = 2.0 * PI * f / FS;
        let z1 = Complex32::new(libm::cosf(w), -libm::sinf(w));
        let z2 = z1 * z1;
        let d = Complex32::new(1.0, 0.0) - z1 * self.a1 - z2 * self.a2;
        Complex32::new(1.0, 0.0) / d
    }
}

/// Camera-side test signal (mm): two sinusoids periodic in 1 s, below the 60 Hz Nyquist limit.
fn camera_signal(t: f32) -> f32 {
    3.0 * libm::sinf(2.0 * PI * 7.0 * t + 0.3) + 1.5 * libm::cosf(2.0 * PI * 32.0 * t)
}
/// Its second derivative (mm/s^2).
fn camera_signal_acc(t: f32) -> f32 {
    let (w1, w2) = (2.0 * PI * 7.0, 2.0 * PI * 32.0);
    -3.0 * w1 * w1 * libm::sinf(w1 * t + 0.3) - 1.5 * w2 * w2 * libm::cosf(w2 * t)
}

/// Largest `|v[j] - signal(j / FS)|`: a record at the ADC rate against its closed form.
fn max_error_at_fs(v: &[f32], signal: fn(f32) -> f32) -> f32 {
    v.iter()
        .enumerate()
        .map(|(j, v)| libm::fabsf(v - signal(j as f32 / FS)))
        .fold(0.0f32, f32::max)
}

// ---------------------------------------------------------------------------------------------
// The complete 2048-point pipeline, in static RAM

const NSEG: usize = 2048;
const CAM_N: usize = 120;
const UP_SCRATCH: usize = upsample::scratch_capacity(CAM_N, NSEG);

/// The vision channel: one-second blocks, 120 fps -> 2048 Hz, camera in mm, ADC in m/s^2;
/// its Welch setting is `welch_2048()`.
const PIPELINE: PipelineConfig = PipelineConfig::one_second_blocks(CAM_N, NSEG, Some(1e-3));
/// ADC samples the ADC may run ahead of the camera beyond the least (116 ms of processing
/// latency).
const LATENCY: usize = 238;

/// Everything a camera firmware needs for vision-channel H1 at 2048 Hz from a 120 fps camera:
/// frames and ADC samples in, upsampled acceleration, 2048-point Welch H1 out. Every capacity
/// comes from the settings.
type Pipeline = VisionH1<
    { PIPELINE.camera_capacity() },
    { PIPELINE.history_capacity(LATENCY) },
    { PIPELINE.work_capacity() },
    { PIPELINE.scratch_capacity() },
>;

/// 2048-point Hann segments with 50 % overlap at 2048 Hz (1 Hz bins).
fn welch_2048() -> WelchConfig {
    WelchConfig {
        fs_hz: FS,
        nperseg: NSEG,
        noverlap: NSEG / 2,
        nfft: NSEG,
        window: Window::Hann,
        detrend: Detrend::Constant,
    }
}

/// Base acceleration seen by the ADC (m/s^2) at time `t`: the second derivative of
/// `camera_signal / 2` (the camera sees twice the ADC's motion, so H1 = 2).
fn adc_signal(t: f32) -> f32 {
    0.5e-3 * camera_signal_acc(t)
}

// ---------------------------------------------------------------------------------------------
// Checks

struct Report {
    failed: u32,
}
impl Report {
    fn check(&mut self, name: &str, ok: bool) {
        if ok {
            hprintln!("ok   {}", name);
        } else {
            hprintln!("FAIL {}", name);
            self.failed += 1;
        }
    }
}

/// The whole-frame centroid of a `W x H` frame (8- or 16-bit).
fn whole<P: Pixel>(cfg: &CentroidConfig, px: &[P]) -> Result<Centroid, FrameError> {
    Frame::new(px, W, H, W).and_then(|f| centroid::centroid(cfg, &f))
}

/// Whether the centroid of the disk frame `px` (`bits`: its pixel type, for the log) in `mode`
/// equals the naive loop's, and the disk centre, exactly.
fn disk_centroid_ok<P: Pixel>(px: &[P], threshold: u16, mode: Mode, bits: &str) -> bool {
    let cfg = CentroidConfig {
        mode,
        ..CentroidConfig::binary(threshold)
    };
    let Ok(c) = whole(&cfg, px) else {
        return false;
    };
    let weighted = mode == Mode::Weighted;
    let (w, sx, sy) = naive_moments(px.iter().map(|&p| p.into()), threshold, weighted);
    let pos = c.position();
    hprintln!(
        "centroid {} {:?}: {} (naive weight {})",
        bits,
        mode,
        Pos(pos),
        w
    );
    let want = (sx as f64 / w as f64, sy as f64 / w as f64);
    pos.is_some_and(|(x, y)| x as f64 == want.0 && y as f64 == want.1 && x == 171.5 && y == 97.0)
}

fn check_centroids(rep: &mut Report) {
    let f8 = black_box(moved(0, 0));
    let f16 = black_box(&FRAME_U16);
    for mode in [Mode::Binary, Mode::Weighted] {
        rep.check(
            "centroid 8-bit vs naive loop and disk centre",
            disk_centroid_ok(f8, THRESHOLD, mode, "u8 "),
        );
        rep.check(
            "centroid 16-bit vs naive loop and disk centre",
            disk_centroid_ok(f16, THRESHOLD * 64, mode, "u16"),
        );
    }
}

fn check_dense(rep: &mut Report) {
    let f = black_box(&DENSE_U8);
    for (mode, weighted) in [(Mode::Binary, false), (Mode::Weighted, true)] {
        let cfg = CentroidConfig {
            mode,
            ..CentroidConfig::binary(THRESHOLD)
        };
        let (w, sx, sy) = naive_moments(f.iter().map(|&p| u16::from(p)), THRESHOLD, weighted);
        let want = ((sx as f64 / w as f64) as f32, (sy as f64 / w as f64) as f32);
        let got = whole(&cfg, f).ok();
        let pos = got.and_then(|c| c.position());
        hprintln!(
            "centroid u8 dense {:?}: {} (naive {}, weight {})",
            mode,
            Pos(pos),
            Pos(Some(want)),
            w
        );
        rep.check(
            "centroid 8-bit dense frame vs naive loop",
            pos.is_some_and(|(x, y)| {
                libm::fabsf(x - want.0) < 1e-4 && libm::fabsf(y - want.1) < 1e-4
            }) && (weighted || got.is_some_and(|c| c.pixels() == w)),
        );
    }
}

/// Streaming H1 of a 2048 Hz input/output pair through a resonator with a closed-form FRF.
/// The estimator lives on the stack here; the static pipeline below holds its own.
#[inline(never)]
fn check_h1(rep: &mut Report) {
    let Ok(mut welch) = WelchH1::<NSEG, NSEG, 0>::try_new(welch_2048()) else {
        rep.check("Welch configuration", false);
        return;
    };
    let mut res = Resonator::new();
    let mut rng = Lcg(2016);
    let (mut xs, mut ys) = ([0.0f32; 256], [0.0f32; 256]);
    // 16 s of input/output, pushed in DMA-sized chunks of 256 samples
    let mut ok = true;
    for _ in 0..16 * 8 {
        for (x, y) in xs.iter_mut().zip(ys.iter_mut()) {
            *x = rng.next();
            *y = res.step(*x);
        }
        ok &= welch.push(&xs, &ys).is_ok();
    }
    rep.check("Welch push", ok && welch.accumulator().segments() == 31);
    let df = welch.accumulator().df_hz();
    let band = (100.0, 300.0);
    let got = peaks::pick_with(welch.accumulator().bins(), df, band, false, |k| {
        welch.accumulator().h1(k)
    });
    let want = peaks::pick_with(welch.accumulator().bins(), df, band, false, |k| {
        Some(res.response(k as f32 * df))
    });
    match (got, want) {
        (Some(g), Some(w)) => {
            hprintln!(
                "H1 peak: {} Hz, |H1| {} (closed form: {} Hz, {})",
                Fx(g.f_hz),
                Fx(g.amplitude),
                Fx(w.f_hz),
                Fx(w.amplitude)
            );
            rep.check("H1 resonance frequency = closed form", g.bin == w.bin);
            rep.check(
                "H1 resonance amplitude within 2 % of closed form",
                libm::fabsf(g.amplitude / w.amplitude - 1.0) < 0.02,
            );
        }
        _ => rep.check("H1 peaks found", false),
    }
}

#[inline(never)]
fn check_upsampling(rep: &mut Report) {
    let Ok(mut up) = Upsampler::<NSEG, UP_SCRATCH>::try_new(CAM_N, NSEG) else {
        rep.check("upsampler configuration", false);
        return;
    };
    let mut camera = [0.0f32; CAM_N];
    let mut vision = [0.0f32; NSEG];
    for (j, v) in camera.iter_mut().enumerate() {
        *v = camera_signal(j as f32 / 120.0);
    }
    // displacement
    let ok = up.process(&camera, &mut vision).is_ok();
    let err = max_error_at_fs(&vision, camera_signal);
    hprintln!(
        "upsample 120 -> 2048: max error {} mm (amplitude 4.5)",
        Fx(err)
    );
    rep.check(
        "upsampled displacement within 1e-4 of analytic",
        ok && err < 4.5e-4,
    );
    // acceleration (fused -omega^2), mm -> mm/s^2
    let ok = up
        .process_acceleration(&camera, &mut vision, 120.0, 1.0)
        .is_ok();
    let peak = 1.5 * (2.0 * PI * 32.0) * (2.0 * PI * 32.0);
    let err = max_error_at_fs(&vision, camera_signal_acc);
    hprintln!(
        "upsample acceleration: max error {} mm/s^2 (peak {})",
        Fx(err),
        Fx(peak)
    );
    rep.check(
        "upsampled acceleration within 1e-4 of analytic",
        ok && err < 1e-4 * peak,
    );
}

/// Feeds `seconds` of frames and ADC samples as they would arrive (after frame `j` the ADC has
/// delivered every sample up to the frame's end) and returns false on any refused push.
fn feed_pipeline(p: &mut Pipeline, first_second: usize, seconds: usize) -> bool {
    let mut ok = true;
    let mut adc = [0.0f32; 32];
    let start = first_second * CAM_N;
    let mut next_adc = first_second * NSEG;
    for j in start..start + seconds * CAM_N {
        let t = j as f32 / 120.0;
        ok &= p.push_frame(camera_signal(t)).is_ok();
        // ADC samples up to the end of frame j, in chunks of up to 32
        let until = (j + 1) * NSEG / CAM_N;
        while next_adc < until {
            let k = (until - next_adc).min(adc.len());
            for (i, v) in adc.iter_mut().take(k).enumerate() {
                *v = adc_signal((next_adc + i) as f32 / FS);
            }
            ok &= p.push_adc(adc.get(..k).unwrap_or(&[])).is_ok();
            next_adc += k;
        }
    }
    ok
}

fn check_pipeline(rep: &mut Report, p: &mut Pipeline) {
    p.reset();
    let ok = feed_pipeline(p, 0, 8);
    let w = p.welch();
    hprintln!("pipeline: {} blocks, {} segments", p.blocks(), w.segments());
    // 8 s = 960 frames: blocks start every 60 frames and need the frame after them, the
    // last at frame 780: 14 blocks, 14 x 1024 samples of vision record,
    // (14336 - 2048) / 1024 + 1 = 13 segments
    rep.check(
        "pipeline: 8 s of frames and ADC samples accepted, 14 blocks, 13 segments",
        ok && p.blocks() == 14 && w.segments() == 13,
    );
    // H1 = vision / ADC = 2 at the two tones (7 and 32 Hz; 1 Hz bins), coherence 1
    for k in [7usize, 32] {
        let h = w.h1(k).unwrap_or_default();
        let c = w.coherence(k).unwrap_or(0.0);
        hprintln!(
            "pipeline H1 at {} Hz: {} {} i, coherence {}",
            k,
            Fx(h.re),
            Fx(h.im),
            Fx(c)
        );
        rep.check(
            "pipeline H1 = 2 within 1e-3, coherence > 0.9999",
            libm::fabsf(h.re - 2.0) < 1e-3 && libm::fabsf(h.im) < 1e-3 && c > 0.9999,
        );
    }
}

/// `cos` and `sin` of a growing angle by a rotation recurrence in `f64`, started by the
/// series of a small step: mcu-demo/c/main.c's `rotor`, expression for expression, so that both
/// demos make the same test signal to the last bit (IEEE arithmetic, no fused operations).
struct Rotor {
    c: f64,
    s: f64,
    dc: f64,
    ds: f64,
}

impl Rotor {
    fn new(step: f64) -> Rotor {
        let x2 = step * step;
        let dc =
            1.0 - x2 / 2.0 + x2 * x2 / 24.0 - x2 * x2 * x2 / 720.0 + x2 * x2 * x2 * x2 / 40320.0;
        let ds = step
            * (1.0 - x2 / 6.0 + x2 * x2 / 120.0 - x2 * x2 * x2 / 5040.0
                + x2 * x2 * x2 * x2 / 362880.0);
        Rotor {
            c: 1.0,
            s: 0.0,
            dc,
            ds,
        }
    }

    fn step(&mut self) {
        let c = self.c * self.dc - self.s * self.ds;
        self.s = self.s * self.dc + self.c * self.ds;
        self.c = c;
    }
}

/// The C demo's pipeline scenario (mcu-demo/c/main.c), made and pushed alike: a 7 Hz motion,
/// ADC acceleration `5 sin(wt)` m/s^2 and camera displacement `-5 cos(wt) / w^2` in mm, whose
/// acceleration it is: H1 = 1 at 7 Hz. Six seconds, each second's ADC samples up to a frame's
/// end pushed before the frame. Both demos print the same line (mcu-demo/c/same_figures.sh
/// compares them): firmware-core from Rust and through the C ABI, bit for bit.
#[inline(never)]
fn check_pipeline_as_c(rep: &mut Report, p: &mut Pipeline) {
    p.reset();
    let w = 2.0 * core::f64::consts::PI * 7.0;
    let (mut adc_r, mut cam_r) = (Rotor::new(w / 2048.0), Rotor::new(w / 120.0));
    let mut adc = [0.0f32; NSEG];
    let mut cam = [0.0f32; CAM_N];
    let (mut ok, mut sent) = (true, 0usize);
    for second in 0..6usize {
        for v in adc.iter_mut() {
            *v = (5.0 * adc_r.s) as f32;
            adc_r.step();
        }
        for v in cam.iter_mut() {
            *v = (-5.0 * cam_r.c / (w * w) * 1e3) as f32;
            cam_r.step();
        }
        let mut done = 0;
        for (k, v) in cam.iter().enumerate() {
            let upto = ((120 * second + k + 1) * 2048).div_ceil(120) - 2048 * second;
            ok &= p.push_adc(adc.get(done..upto).unwrap_or(&[])).is_ok();
            ok &= p.push_frame(*v).is_ok();
            done = upto;
        }
        sent += done;
    }
    let wl = p.welch();
    let h = wl.h1(7).unwrap_or_default();
    let pk = peaks::pick_with(wl.bins(), wl.df_hz(), (6.5, 7.5), false, |k| wl.h1(k));
    match pk {
        Some(pk) => hprintln!(
            "pipeline: H1(7 Hz) = {} + {}i after {} segments; peak {} Hz, |H1| {}",
            Fx(h.re),
            Fx(h.im),
            wl.segments(),
            Fx(pk.f_hz),
            Fx(pk.amplitude)
        ),
        None => hprintln!("pipeline: no peak in 6.5-7.5 Hz"),
    }
    // the same values as bits: the comparison with the C demo is exact, not to six decimals
    hprintln!(
        "pipeline: H1(7 Hz) bits {:08x} {:08x}, |H1| bits {:08x}",
        h.re.to_bits(),
        h.im.to_bits(),
        pk.map_or(0, |pk| pk.amplitude.to_bits())
    );
    rep.check(
        "pipeline, the C demo's 7 Hz motion: H1 = i within 0.02, its peak |H1| = 1 within 0.02",
        ok && sent == 6 * NSEG
            && libm::fabsf(h.re) < 0.02
            && libm::fabsf(h.im - 1.0) < 0.02
            && pk.is_some_and(|pk| libm::fabsf(pk.amplitude - 1.0) < 0.02),
    );
}

fn check_sync(rep: &mut Report) {
    let ok = SyncPlan::try_new(SyncConfig::new(2048, 120, 1_000_000).with_exposure_ticks(61))
        .is_ok_and(|p| (p.tick_hz(), p.adc_div(), p.camera_div()) == (30_720, 15, 256));
    rep.check(
        "sync plan 2048 Hz / 120 fps: 30720 Hz, dividers 15 and 256",
        ok,
    );
}

// ---------------------------------------------------------------------------------------------
// Benchmarks (results are not checked here; the checks above use the same code)

fn bench_centroids() {
    let f8 = black_box(moved(0, 0));
    let f16 = black_box(&FRAME_U16);
    let b = CentroidConfig::binary(THRESHOLD);
    let b16 = CentroidConfig::binary(THRESHOLD * 64);
    let w = CentroidConfig::weighted(THRESHOLD);
    let w16 = CentroidConfig::weighted(THRESHOLD * 64);
    measured("centroid binary u8 76800", || whole(&b, f8)).ok();
    measured("centroid binary u8 row-kernel 76800", || {
        let mut s = 0u32;
        for row in f8.chunks_exact(W) {
            s = s.wrapping_add(centroid::row_binary_u8(black_box(row), 100).pixels);
        }
        s
    });
    let d8 = black_box(&DENSE_U8);
    measured("centroid binary u8 dense 76800", || whole(&b, d8)).ok();
    measured("centroid weighted u8 76800", || whole(&w, f8)).ok();
    measured("centroid weighted u8 dense 76800", || whole(&w, d8)).ok();
    measured("centroid binary u16 76800", || whole(&b16, f16)).ok();
    measured("centroid weighted u16 76800", || whole(&w16, f16)).ok();
}

/// One segment pair through a fresh estimator (noverlap 0: `N` samples = one segment).
#[inline(never)]
fn bench_welch<const N: usize>(x: &mut [f32; N], y: &mut [f32; N]) {
    let cfg = WelchConfig {
        fs_hz: FS,
        nperseg: N,
        noverlap: 0,
        nfft: N,
        window: Window::Hann,
        detrend: Detrend::Constant,
    };
    let mut rng = Lcg(N as u64);
    let mut res = Resonator::new();
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        *a = rng.next();
        *b = res.step(*a);
    }
    if let Ok(mut w) = WelchH1::<N, N, 0>::try_new(cfg) {
        match N {
            1024 => measured("welch segment pair 1024", || w.push(x, y)),
            2048 => measured("welch segment pair 2048", || w.push(x, y)),
            _ => measured("welch segment pair 4096", || w.push(x, y)),
        }
        .ok();
        black_box(w.accumulator().h1(1));
    }
}

/// Frame `i` of `K` targets at 120 fps moving in two modes (7 and 23 Hz, shapes `sin` and
/// `cos` along the targets) plus a little noise: what the cross spectra should decompose.
fn two_mode_frame<const K: usize>(i: usize, rng: &mut Lcg) -> [f32; K] {
    let t = i as f32 / 120.0;
    let (a, b) = (
        libm::sinf(2.0 * PI * 7.0 * t),
        0.3 * libm::sinf(2.0 * PI * 23.0 * t + 0.4),
    );
    core::array::from_fn(|k| {
        let x = (k as f32 + 1.0) / K as f32;
        a * libm::sinf(0.5 * PI * x) + b * libm::cosf(PI * x) + 0.01 * rng.next()
    })
}

/// Output-only FDD on the camera with `K` targets at 120 fps, segments of 512: the peaks of
/// the first singular value at the two modes' lines, their vectors the modes' shapes; the cost
/// of 256 frames (one segment added) and of the decomposition of all 257 lines with the peaks.
#[inline(never)]
fn check_and_bench_cross<const K: usize, const TRI: usize>(rep: &mut Report) {
    let Ok(mut cs) = CrossSpectra::<K, 512, 257, TRI, 0>::try_new(120.0) else {
        rep.check("cross spectra: capacities", false);
        return;
    };
    hprintln!(
        "ram: cross spectra of {} targets, segments of 512: {} B",
        K,
        core::mem::size_of::<CrossSpectra<K, 512, 257, TRI, 0>>()
    );
    let mut rng = Lcg(K as u64);
    for i in 0..512 * 4 {
        cs.push(&two_mode_frame::<K>(i, &mut rng));
    }
    // the measured frames are made first: the count is the library's work, not the test
    // signal's sines
    let mut batch = [[0.0f32; K]; 256];
    for (n, f) in batch.iter_mut().enumerate() {
        *f = two_mode_frame::<K>(2048 + n, &mut rng);
    }
    let frames = |cs: &mut CrossSpectra<K, 512, 257, TRI, 0>, batch: &[[f32; K]; 256]| {
        for f in batch {
            cs.push(f);
        }
    };
    match K {
        4 => measured(
            "cross spectra 4 targets: 256 frames (one segment of 512 added)",
            || frames(&mut cs, &batch),
        ),
        _ => measured(
            "cross spectra 8 targets: 256 frames (one segment of 512 added)",
            || frames(&mut cs, &batch),
        ),
    }
    let mut s1 = [0.0f32; 257];
    let mut sorted = [0.0f32; 257];
    let mut peaks = [0usize; 8];
    let decompose = |cs: &CrossSpectra<K, 512, 257, TRI, 0>,
                     s1: &mut [f32; 257],
                     sorted: &mut [f32; 257],
                     peaks: &mut [usize; 8]| {
        for (l, v) in s1.iter_mut().enumerate() {
            *v = cs.first_singular(l, 30).0;
        }
        pick_peaks(
            &s1[..],
            (2, 255),
            (6.0, 10.0),
            &mut sorted[..],
            &mut peaks[..],
        )
    };
    let n = match K {
        4 => measured(
            "fdd 4 targets: first singular value of 257 lines, peaks",
            || decompose(&cs, &mut s1, &mut sorted, &mut peaks),
        ),
        _ => measured(
            "fdd 8 targets: first singular value of 257 lines, peaks",
            || decompose(&cs, &mut s1, &mut sorted, &mut peaks),
        ),
    };
    // 7 Hz and 23 Hz are lines 29.9 and 98.1 of 120 / 512 Hz
    let lines = &peaks[..n.min(8)];
    let near = |f: f32| lines.iter().any(|&l| libm::fabsf(cs.freq(l) - f) <= 0.25);
    let mut ok = n == 2 && near(7.0) && near(23.0);
    for (&l, f) in lines.iter().zip([7.0f32, 23.0]) {
        let v = cs.first_singular(l, 30).1;
        let mut dot = Complex32::new(0.0, 0.0);
        let (mut vv, mut ss) = (0.0f32, 0.0f32);
        for (k, c) in v.iter().enumerate() {
            let x = (k as f32 + 1.0) / K as f32;
            let shape = if f < 10.0 {
                libm::sinf(0.5 * PI * x)
            } else {
                libm::cosf(PI * x)
            };
            dot += c.conj() * shape;
            vv += c.norm_sqr();
            ss += shape * shape;
        }
        let mac = dot.norm_sqr() / (vv * ss);
        ok &= mac > 0.999;
        hprintln!(
            "fdd {} targets: peak at line {} ({} mHz), MAC x1e6 {}",
            K,
            l,
            (cs.freq(l) * 1000.0) as u32,
            (mac * 1e6) as u32
        );
    }
    rep.check(
        "fdd on the camera: two peaks at the modes' lines, shapes MAC > 0.999",
        ok,
    );
}

#[inline(never)]
fn bench_upsample_20480() {
    const N: usize = 1200;
    const M: usize = 20480;
    let mut input = [0.0f32; N];
    let mut output = [0.0f32; M];
    for (j, v) in input.iter_mut().enumerate() {
        *v = camera_signal(j as f32 / 120.0);
    }
    if let Ok(mut up) = Upsampler::<M, { upsample::scratch_capacity(N, M) }>::try_new(N, M) {
        measured("upsample 1200 -> 20480", || up.process(&input, &mut output)).ok();
    }
    black_box(&output);
}

/// One second of the pipeline in steady state (after two seconds): 120 frames and 2048 ADC
/// samples pushed interleaved as they arrive; one block upsampled, two segments accumulated.
/// The signals are computed before the measurement.
#[inline(never)]
fn bench_pipeline(p: &mut Pipeline) {
    p.reset();
    let ok = feed_pipeline(p, 0, 2);
    let mut frames = [0.0f32; CAM_N];
    let mut adc = [0.0f32; NSEG];
    for (j, v) in frames.iter_mut().enumerate() {
        *v = camera_signal((2 * CAM_N + j) as f32 / 120.0);
    }
    for (i, v) in adc.iter_mut().enumerate() {
        *v = adc_signal((2 * NSEG + i) as f32 / FS);
    }
    let ok2 = measured("pipeline one second (120 frames, 2048 ADC samples)", || {
        let mut ok = true;
        let mut next = 0;
        for (j, v) in frames.iter().enumerate() {
            ok &= p.push_frame(*v).is_ok();
            let until = (j + 1) * NSEG / CAM_N;
            ok &= p.push_adc(adc.get(next..until).unwrap_or(&[])).is_ok();
            next = until;
        }
        ok
    });
    black_box((ok, ok2, p.welch().segments()));
}

#[inline(never)]
fn bench_upsample_2048() {
    let mut input = [0.0f32; CAM_N];
    let mut output = [0.0f32; NSEG];
    for (j, v) in input.iter_mut().enumerate() {
        *v = camera_signal(j as f32 / 120.0);
    }
    if let Ok(mut up) = Upsampler::<NSEG, UP_SCRATCH>::try_new(CAM_N, NSEG) {
        measured("upsample 120 -> 2048", || up.process(&input, &mut output)).ok();
    }
    black_box(&output);
}

// ---------------------------------------------------------------------------------------------
// Tracking window (method.md §2.9) and a driver-shaped scenario

/// Pixels added around the last bounding box: more than the target moves between frames.
const MARGIN: u32 = 4;
const TRACK: TrackConfig = TrackConfig::new(CentroidConfig::binary(THRESHOLD), 320, 240, MARGIN);
/// The target's path for the tracking check and benchmark: `(dx, dy)` offsets into the canvas
/// (the disk at `(171.5 - dx, 97 - dy)`), up to 3 px per frame in each direction.
const PATH: [(usize, usize); 8] = [
    (0, 0),
    (2, 1),
    (5, 3),
    (7, 6),
    (8, 9),
    (6, 12),
    (3, 14),
    (1, 12),
];

/// Full-frame centroid of a frame (the reference of the tracking window).
fn full_frame(px: &[u8]) -> Option<Centroid> {
    whole(&TRACK.centroid, px).ok()
}

/// One frame in memory through the tracker: only the window's rows are read.
#[inline(never)]
fn track_frame(t: &mut Tracker, px: &[u8]) -> Centroid {
    match Frame::new(px, W, H, W) {
        Ok(f) => t.process(&f),
        Err(_) => Centroid::default(),
    }
}

/// The disk moving along `PATH` and back: every tracked centroid equals the full-frame one and
/// the disk's centre; after the first frame only the window is processed.
fn check_tracking(rep: &mut Report) {
    let Ok(mut t) = Tracker::try_new(TRACK) else {
        rep.check("tracker configuration", false);
        return;
    };
    let mut same = true;
    let mut windowed = 0;
    for (k, &(dx, dy)) in PATH.iter().chain(PATH.iter().rev()).enumerate() {
        let px = black_box(moved(dx, dy));
        windowed += usize::from(t.window().is_some());
        let got = track_frame(&mut t, px);
        let want = full_frame(px);
        let centre = (171.5 - dx as f32, 97.0 - dy as f32);
        same &= want == Some(got) && got.position() == Some(centre);
        if k < 3 {
            hprintln!(
                "tracking frame {}: {} (window rows {:?})",
                k,
                Pos(got.position()),
                t.rows()
            );
        }
    }
    rep.check(
        "tracking window: 16 frames of a moving disk, centroid = full frame = disk centre",
        same && windowed == 15,
    );
}

/// One frame of the moving disk through the tracking window, in steady state (the window of
/// the previous frame; the target moved by (-2, -3) px since).
#[inline(never)]
fn bench_tracking() {
    let Ok(mut t) = Tracker::try_new(TRACK) else {
        return;
    };
    track_frame(&mut t, black_box(moved(5, 3)));
    track_frame(&mut t, black_box(moved(3, 0)));
    let px = black_box(moved(5, 3));
    let c = measured(
        "centroid tracking window, binary u8, one 320 x 240 frame, target moved by (2, 3) px",
        || track_frame(&mut t, px),
    );
    black_box(c);
}

/// A line handed over by the line interrupt: which DMA line buffer holds which row.
#[derive(Debug, Clone, Copy)]
struct Line {
    row: u16,
    slot: u8,
}

/// DMA line buffers (a ring) and the line queue's capacity (heapless 0.8: `N - 1` lines).
const DMA_LINES: usize = 8;

/// Frames of the driver scenario: 3 s at 120 fps.
const DRIVER_FRAMES: usize = 360;
/// Image scale of the driver scenario, mm per pixel.
const MM_PER_PX: f32 = 0.1;
/// Vertical motion of the target (px): 8 + 5 sin(2 pi 8 t), rounded to whole rows (the canvas
/// moves by whole pixels; at most 3 rows from one frame to the next, below the margin).
fn driver_dy(t: f32) -> f32 {
    8.0 + AMPLITUDE_PX * libm::sinf(2.0 * PI * 8.0 * t)
}
/// Amplitude of the driver scenario's motion, px.
const AMPLITUDE_PX: f32 = 5.0;

/// The "line interrupt": the camera DMA has written `row` of frame `frame` into the next line
/// buffer; hand it to the main loop, or count an overrun when the queue is full.
fn line_interrupt(
    irq: &mut Producer<'_, Line, DMA_LINES>,
    dma: &mut [[u8; W]; DMA_LINES],
    sensor: &[u8],
    row: usize,
    overruns: &mut u32,
) {
    let slot = row % DMA_LINES;
    if let (Some(buf), Some(src)) = (dma.get_mut(slot), sensor.get(row * W..row * W + W)) {
        // element copy: no length-mismatch panic path (the panic-check build)
        for (d, v) in buf.iter_mut().zip(src) {
            *d = *v;
        }
    }
    if irq
        .enqueue(Line {
            row: row as u16,
            slot: slot as u8,
        })
        .is_err()
    {
        *overruns += 1;
    }
}

/// The main loop's share of the lines: every queued line through the tracker; the line
/// buffer is released (dequeued) only after it was read.
fn drain(
    main: &mut Consumer<'_, Line, DMA_LINES>,
    dma: &[[u8; W]; DMA_LINES],
    t: &mut Tracker,
    rows: &mut usize,
) {
    while let Some(line) = main.peek().copied() {
        if let Some(buf) = dma.get(usize::from(line.slot)) {
            t.push_row(buf);
        }
        *rows = usize::from(line.row) + 1;
        main.dequeue();
    }
}

/// A driver-shaped run: the line interrupt pushes each row of a moving disk through an spsc
/// queue, the main loop centroids with the tracking window and feeds the centroids (mm) and
/// the ADC's samples (the exact acceleration of the motion, m/s^2) into the pipeline. Checks:
/// every tracked centroid equals the full-frame one; no overrun, no refused push; H1 at the
/// motion's 8 Hz within 5 % of 1 (the camera sees whole-pixel steps of a sinusoid) with
/// coherence > 0.99.
#[inline(never)]
fn check_driver(rep: &mut Report, p: &mut Pipeline) {
    let Ok(mut tracker) = Tracker::try_new(TRACK) else {
        rep.check("tracker configuration", false);
        return;
    };
    p.reset();
    let mut dma = [[0u8; W]; DMA_LINES];
    let mut queue: Queue<Line, DMA_LINES> = Queue::new();
    let (mut irq, mut main) = queue.split();
    let (mut overruns, mut same, mut pushed) = (0u32, true, true);
    let mut adc = [0.0f32; 32];
    let mut next_adc = 0usize;
    let w = 2.0 * PI * 8.0;
    for j in 0..DRIVER_FRAMES {
        let dy = libm::roundf(driver_dy(j as f32 / 120.0)) as usize;
        let sensor = moved(0, dy);
        let mut rows = 0;
        for row in 0..H {
            line_interrupt(&mut irq, &mut dma, sensor, row, &mut overruns);
            // the main loop gets the CPU every few lines
            if row % 4 == 3 {
                drain(&mut main, &dma, &mut tracker, &mut rows);
            }
        }
        drain(&mut main, &dma, &mut tracker, &mut rows);
        let c = tracker.finish_frame();
        same &= rows == H && full_frame(sensor) == Some(c);
        // displacement up (mm): the image y grows down
        let up_mm = -c.cy * MM_PER_PX;
        pushed &= p.push_frame(up_mm).is_ok();
        // the ADC DMA's samples up to the end of the frame, in chunks of up to 32
        let until = (j + 1) * NSEG / CAM_N;
        while next_adc < until {
            let k = (until - next_adc).min(adc.len());
            for (i, v) in adc.iter_mut().take(k).enumerate() {
                // up = 0.1 mm/px * (5 sin(w t) - 97 + 8): acceleration in m/s^2
                let t = (next_adc + i) as f32 / FS;
                *v = -1e-3 * MM_PER_PX * AMPLITUDE_PX * w * w * libm::sinf(w * t);
            }
            pushed &= p.push_adc(adc.get(..k).unwrap_or(&[])).is_ok();
            next_adc += k;
        }
    }
    let wel = p.welch();
    let h = wel.h1(8).unwrap_or_default();
    let coh = wel.coherence(8).unwrap_or(0.0);
    hprintln!(
        "driver: {} frames, {} overruns, {} segments, H1 at 8 Hz {} {} i, coherence {}",
        DRIVER_FRAMES,
        overruns,
        wel.segments(),
        Fx(h.re),
        Fx(h.im),
        Fx(coh)
    );
    rep.check(
        "driver: line interrupt -> spsc queue -> tracking window = full frame, no overrun",
        same && overruns == 0,
    );
    rep.check(
        "driver: pipeline fed without refusal, H1(8 Hz) = 1 within 5 %, coherence > 0.99",
        pushed
            && wel.segments() == 3
            && libm::fabsf(h.re - 1.0) < 0.05
            && libm::fabsf(h.im) < 0.05
            && coh > 0.99,
    );
}

// ---------------------------------------------------------------------------------------------

// ---------------------------------------------------------------------------------------------
// Lucas-Kanade tracking of a textured window

/// The speckle scene of the LK checks: 96 x 80 px.
const SW: usize = 96;
const SH: usize = 80;
/// One LK window of 31 x 31 px (rows up to 31, plus 7 for the interpolation's support).
type Lk = LkTracker<{ 39 * 39 }, 38>;

/// A speckle pattern (Gaussian spots of sigma 2 px around (44, 40)) displaced by `(dx, dy)`,
/// 8-bit, into `out`.
fn speckle(out: &mut [u8; SW * SH], dx: f32, dy: f32) {
    const SPOTS: [(f32, f32, f32); 6] = [
        (40.0, 35.0, 1.0),
        (47.0, 38.0, 0.7),
        (43.0, 44.0, 0.9),
        (52.0, 33.0, 0.6),
        (36.0, 42.0, 0.8),
        (50.0, 46.0, 0.5),
    ];
    for (i, o) in out.iter_mut().enumerate() {
        let (x, y) = ((i % SW) as f32, (i / SW) as f32);
        let mut v = 40.0;
        for (sx, sy, a) in SPOTS {
            let (ex, ey) = (x - sx - dx, y - sy - dy);
            v += 200.0 * a * libm::expf(-(ex * ex + ey * ey) / 8.0);
        }
        *o = (v + 0.5).clamp(0.0, 255.0) as u8;
    }
}

/// An LK tracker with `cfg`, its template at (29, 25) in the undisplaced scene.
fn lk_at(cfg: LkConfig, scene: &mut [u8; SW * SH]) -> Option<Lk> {
    let mut t = Lk::try_new(cfg).ok()?;
    speckle(scene, 0.0, 0.0);
    let f = Frame::new(&scene[..], SW, SH, SW).ok()?;
    t.set_template(&f, 29, 25).ok()?;
    Some(t)
}

/// Lucas-Kanade on the target: a sub-pixel shift and a jump caught by the coarse search; a
/// jump from rest longer than half the template, which the motion so far does not explain, is
/// lost (flagged ambiguous) rather than taken.
fn check_lk(rep: &mut Report) {
    let mut scene = [0u8; SW * SH];
    let mut ok = true;
    for (dx, dy, search) in [(0.3f32, -0.7f32, 0u16), (12.4, -9.3, 24), (20.4, -12.3, 24)] {
        let mut cfg = LkConfig::new(31, 31);
        cfg.search = search;
        let Some(mut t) = lk_at(cfg, &mut scene) else {
            rep.check("lk: template", false);
            return;
        };
        speckle(&mut scene, dx, dy);
        let r = Frame::new(&scene[..], SW, SH, SW).map(|f| t.track(&f));
        let got = r.ok().and_then(|r| r.displacement());
        // integers only: float formatting would bring core's panicking formatter in
        let milli = |v: f32| (v * 1000.0) as i32;
        let (gx, gy) = got.map_or((i32::MIN, i32::MIN), |(x, y)| (milli(x), milli(y)));
        hprintln!(
            "lk: shift ({}, {}) mpx measured ({}, {}) mpx",
            milli(dx),
            milli(dy),
            gx,
            gy
        );
        ok &= if dx > 16.0 {
            // more than half the 31 px template from rest
            r.is_ok_and(|r| r.displacement().is_none() && r.flags.contains(Flags::AMBIGUOUS))
        } else {
            got.is_some_and(|(x, y)| libm::fabsf(x - dx) < 0.02 && libm::fabsf(y - dy) < 0.02)
        };
    }
    rep.check(
        "lk: sub-pixel shift and a 12 px jump within 0.02 px, a 20 px jump from rest lost",
        ok,
    );
    hprintln!(
        "ram: lk tracker of a 31 x 31 window {} B (LkTracker<1521, 38>: the spline's padded template)",
        core::mem::size_of::<Lk>()
    );
}

/// One frame of LK in steady state: the refinement from a start 0.4 px away (up to 3
/// iterations), per interpolation and smoothing; and one coarse search of +-8 px.
#[inline(never)]
fn bench_lk() {
    let mut scene = [0u8; SW * SH];
    for (label, interpolation, smoothing) in [
        (
            "lk refinement 31 x 31, 3 iterations, spline + [1 2 1] smoothing",
            Interpolation::Spline,
            Smoothing::Binomial3,
        ),
        (
            "lk refinement 31 x 31, 3 iterations, spline + [1 4 6 4 1] smoothing",
            Interpolation::Spline,
            Smoothing::Binomial5,
        ),
        (
            "lk refinement 31 x 31, 3 iterations, bicubic + [1 4 6 4 1] smoothing",
            Interpolation::Bicubic,
            Smoothing::Binomial5,
        ),
        (
            "lk refinement 31 x 31, 3 iterations, bicubic + [1 2 1] smoothing",
            Interpolation::Bicubic,
            Smoothing::Binomial3,
        ),
        (
            "lk refinement 31 x 31, 3 iterations, bilinear + [1 2 1] smoothing",
            Interpolation::Bilinear,
            Smoothing::Binomial3,
        ),
        (
            "lk refinement 31 x 31, 3 iterations, bilinear, no smoothing",
            Interpolation::Bilinear,
            Smoothing::None,
        ),
    ] {
        let mut cfg = LkConfig::new(31, 31);
        cfg.search = 0;
        cfg.max_iterations = 3;
        cfg.interpolation = interpolation;
        cfg.smoothing = smoothing;
        let Some(mut t) = lk_at(cfg, &mut scene) else {
            return;
        };
        speckle(&mut scene, 0.4, -0.3);
        let Ok(f) = Frame::new(&scene[..], SW, SH, SW) else {
            return;
        };
        let r = measured(label, || t.track(black_box(&f)));
        black_box(r);
    }
    // taking a template (the spline's prefilter and moments): once per target, or per refresh
    let cfg = LkConfig::new(31, 31);
    let Ok(mut t) = Lk::try_new(cfg) else {
        return;
    };
    speckle(&mut scene, 0.0, 0.0);
    let Ok(f) = Frame::new(&scene[..], SW, SH, SW) else {
        return;
    };
    let r = measured(
        "lk template 31 x 31, spline + [1 2 1] (once per target)",
        || t.set_template(black_box(&f), 29, 25),
    );
    black_box(r.is_ok());
    // the coarse search: a jump the refinement alone does not catch
    let mut cfg = LkConfig::new(31, 31);
    cfg.search = 8;
    cfg.max_iterations = 3;
    cfg.accept_score = 1.0;
    let Some(mut t) = lk_at(cfg, &mut scene) else {
        return;
    };
    speckle(&mut scene, 6.4, -5.3);
    let Ok(f) = Frame::new(&scene[..], SW, SH, SW) else {
        return;
    };
    let r = measured(
        "lk coarse search +-8 px (289 offsets of 31 x 31) and refinement",
        || t.track(black_box(&f)),
    );
    black_box(r);
}

#[entry]
fn main() -> ! {
    hprintln!("mcu-demo: firmware-core on Cortex-M4F (QEMU mps2-an386)");
    let mut rep = Report { failed: 0 };

    // The pipeline in static RAM: `new()` is all zero bytes (`.bss`: no flash image, no
    // stack copy, unlike `cortex_m::singleton!`, which moves its value in); the settings are
    // set in place.
    static mut PIPE: Pipeline = Pipeline::new();
    // SAFETY: the only reference to PIPE, taken once at the start of `main` (which never
    // returns), before any interrupt could run; no interrupt handler touches PIPE.
    let p: &'static mut Pipeline = unsafe { &mut *core::ptr::addr_of_mut!(PIPE) };
    if p.configure(PIPELINE).is_err() {
        hprintln!("FAIL pipeline configuration");
        debug::exit(debug::EXIT_FAILURE);
        loop {
            cortex_m::asm::wfi();
        }
    }
    hprintln!(
        "ram: pipeline {} B (VisionH1<{}, {}, {}, {}>: frames + ADC in, 2048-point H1 out)",
        core::mem::size_of::<Pipeline>(),
        PIPELINE.camera_capacity(),
        PIPELINE.history_capacity(LATENCY),
        PIPELINE.work_capacity(),
        PIPELINE.scratch_capacity()
    );

    check_centroids(&mut rep);
    check_dense(&mut rep);
    check_h1(&mut rep);
    check_upsampling(&mut rep);
    check_pipeline(&mut rep, p);
    check_pipeline_as_c(&mut rep, p);
    check_sync(&mut rep);
    check_tracking(&mut rep);
    check_lk(&mut rep);
    check_driver(&mut rep, p);

    // benchmarks
    measured("empty", || ());
    bench_centroids();
    bench_tracking();
    bench_lk();
    bench_welch::<1024>(&mut [0.0; 1024], &mut [0.0; 1024]);
    bench_welch::<2048>(&mut [0.0; 2048], &mut [0.0; 2048]);
    bench_welch::<4096>(&mut [0.0; 4096], &mut [0.0; 4096]);
    bench_upsample_2048();
    // one second (120 frames, 2048 ADC samples, one block, two segments) in steady state
    bench_pipeline(p);
    bench_upsample_20480();
    check_and_bench_cross::<4, 10>(&mut rep);
    check_and_bench_cross::<8, 36>(&mut rep);

    if rep.failed == 0 {
        hprintln!("mcu-demo: all checks passed");
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        hprintln!("mcu-demo: {} check(s) FAILED", rep.failed);
        debug::exit(debug::EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::wfi();
    }
}

#[cfg(not(feature = "panic-check"))]
#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}

#[cfg(feature = "panic-check")]
#[panic_handler]
fn panic(_info: &PanicInfo) -> ! {
    extern "C" {
        /// Deliberately undefined: referencing it makes the link fail if a panic path survives.
        fn mcu_demo_panic_path_survived_optimisation() -> !;
    }
    // SAFETY: never runs; the symbol does not exist, so an image that could call it never links.
    unsafe { mcu_demo_panic_path_survived_optimisation() }
}

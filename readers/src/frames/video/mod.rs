//! Video files (AVI, MKV, MP4, MOV: whatever FFmpeg reads) as a stream of grey frames, one
//! buffer at a time, with the container's timestamps checked against the expected frame rate;
//! and a writer of lossless FFV1/Matroska videos from grey frames, for synthetic recordings and
//! tests.
//!
//! # Why the `ffmpeg` program, as a subprocess
//!
//! Frames are decoded by running the `ffmpeg` program with its output piped to us as raw grey
//! pixels (`-f rawvideo -pix_fmt gray|gray16le ...`), the way imageio-ffmpeg does; frame size,
//! pixel format and timestamps come from `ffprobe`. A binding crate (`ffmpeg-next`/`-sys`) would
//! tie the build to the system's FFmpeg development headers and library versions (the bindings
//! follow FFmpeg's major versions, and a Debian upgrade breaks the link), need `clang` for
//! bindgen, and put a C decoder inside our process. The subprocess needs nothing at build time,
//! works with any FFmpeg of the last years (Debian: `apt-get install ffmpeg`, which CI does),
//! and costs one pipe copy per frame, small beside decoding. If `ffmpeg` or `ffprobe` is missing
//! the error says so and how to install it.
//!
//! # Grey conversion
//!
//! Frames are luma (Y'), converted by FFmpeg's scaler: grey sources pass unchanged (bit for bit);
//! YUV sources give their Y plane, expanded to full range (0..=255) when the stream is
//! limited-range ("TV", FFmpeg's assumption when the file does not say); RGB sources give
//! `Y' = 0.299 R + 0.587 G + 0.114 B` (BT.601). Sources of 8 bits or fewer per component are
//! read as 8-bit frames (`u8`); deeper sources (10, 12, 16 bits...) as 16-bit buffers (`u16`)
//! holding the source's own bit depth ([`VideoInfo::bits`]: a 12-bit camera gives 0..=4095), so
//! a threshold means the same grey level as in the camera's own TIFF export. Pixels are taken on
//! the coded grid: no autorotation, no aspect-ratio resampling.
//!
//! # Timestamps
//!
//! Before decoding, `ffprobe` lists the video stream's packet timestamps (presentation order;
//! packets the demuxer marks as discard are skipped). With `T = 1 / expected_fps` and `t_i` the
//! time of frame `i` after the first, every interval `t_i - t_{i-1}` and every `t_i - i T` must
//! be within one tick of the stream's time base (plus 2 µs for ffprobe's printed rounding) of
//! `T` and `0`: a dropped frame (a gap of two periods), a variable frame rate, or a container
//! rate other than `expected_fps` is an error naming the first irregular frame (0-based index).
//! [`VideoFrames::open_retimed`] (the CLI's `--retime`) accepts timestamps regular at another
//! constant rate as a retiming (a phone's 240 fps slow motion stored as 30 fps, a high-speed
//! camera's AVI export at 25 fps): frames are then `1 / expected_fps` apart, and
//! [`VideoInfo::container_fps`] keeps the container's own rate so callers can name both.
//! Without it a near miss (29.97 fps read as 30) or a wrong rate is an error, as a retiming
//! cannot be told from a mistake by the numbers alone.
//!
//! # Memory and errors
//!
//! [`VideoFrames`] reads one frame into the caller's buffer per call and reuses its own byte
//! buffer: memory is one frame, whatever the video's length. A stream that ends early (a
//! truncated file), a decoding error (FFmpeg runs with `-xerror` and `-err_detect explode`, so a
//! damaged frame stops it rather than being concealed), or more frames than timestamps is an
//! error naming the file and the frame index.

use crate::frames::GreyFrame;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

mod probe;
mod reader;
mod writer;

pub use probe::rate_text;
pub use reader::VideoFrames;
pub use writer::{Ffv1Writer, Pixels};

/// Properties of an opened video.
#[derive(Debug, Clone, PartialEq)]
pub struct VideoInfo {
    /// The file.
    pub path: PathBuf,
    /// Codec name as FFmpeg reports it (`ffv1`, `h264`, ...).
    pub codec: String,
    /// The source's pixel format (`gray`, `yuv420p`, `gray12le`, ...).
    pub pix_fmt: String,
    /// Frame width, px.
    pub width: usize,
    /// Frame height, px.
    pub height: usize,
    /// Bits per grey value delivered: 8 (`u8` frames) or 9..=16 (`u16` frames).
    pub bits: u32,
    /// Number of frames (from the container's timestamps).
    pub frames: usize,
    /// The expected (checked) frame rate, Hz.
    pub fps: f64,
    /// The container's own constant rate, Hz, when `fps` retimes it
    /// ([`VideoFrames::open_retimed`]); `None` when they agree.
    pub container_fps: Option<f64>,
    /// Frame times, seconds after the first frame: the container's, scaled to `fps` when it
    /// retimes them.
    pub times_s: Vec<f64>,
}

/// Checks `path`'s timestamps against `fps` without decoding (ffprobe only), as
/// [`VideoFrames::open_retimed`] (`retime`) or [`VideoFrames::open`] would: `Ok(Some(rate))`
/// when `fps` retimes the container's constant `rate`, `Ok(None)` when they agree.
pub fn check_rate(path: &Path, fps: f64, retime: bool) -> Result<Option<f64>, VideoError> {
    let stream = probe::probe_stream(path, "ffprobe")?;
    let times_s = probe::probe_times(path, "ffprobe")?;
    let rate = probe::check_times(path, &times_s, fps, stream.time_base_s, retime)?;
    probe::check_complete(path, &times_s, rate.unwrap_or(fps), &stream)?;
    Ok(rate)
}

/// The container's own mean frame rate, Hz, from its timestamps (ffprobe only): what a video
/// is read at when only its frames matter, not the rate the camera captured them at.
pub fn container_rate(path: &Path) -> Result<Option<f64>, VideoError> {
    let times_s = probe::probe_times(path, "ffprobe")?;
    Ok(match (times_s.first(), times_s.last()) {
        (Some(a), Some(b)) if times_s.len() > 1 && b > a => {
            Some((times_s.len() - 1) as f64 / (b - a))
        }
        _ => None,
    })
}

/// The frame just read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameInfo {
    /// 0-based frame index.
    pub index: usize,
    /// Container time, seconds after the first frame.
    pub time_s: f64,
}

/// What can go wrong reading or writing a video. Each names the file, and the frame where one is
/// concerned (0-based).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum VideoError {
    /// `ffmpeg` or `ffprobe` could not be started.
    #[error("cannot run `{program}` ({source}) for {path}: install FFmpeg (Debian: apt-get install ffmpeg)")]
    ProgramMissing {
        /// The program.
        program: String,
        /// The file it was started for.
        path: PathBuf,
        /// The error from the operating system.
        source: std::io::Error,
    },
    /// `ffprobe` could not read the file (missing, not a video, corrupt header).
    #[error("{path}: cannot read it as a video: {stderr}")]
    Unreadable {
        /// The file.
        path: PathBuf,
        /// What ffprobe said.
        stderr: String,
    },
    /// No video stream in the file, or one without a usable frame size or pixel format.
    #[error("{path}: no usable video stream ({what})")]
    NoVideoStream {
        /// The file.
        path: PathBuf,
        /// What is missing.
        what: String,
    },
    /// The expected frame rate is not a positive number.
    #[error("{path}: the expected frame rate {fps} is not a positive number")]
    BadFps {
        /// The file.
        path: PathBuf,
        /// The rate given.
        fps: f64,
    },
    /// A packet has no presentation timestamp, or the demuxer marks it corrupt.
    #[error("{path}: frame {frame}: {what}")]
    BadPacket {
        /// The file.
        path: PathBuf,
        /// Frame (packet) index.
        frame: usize,
        /// What is wrong.
        what: String,
    },
    /// The stream's time base is too coarse to check timestamps at the expected rate.
    #[error("{path}: the stream's time base ({time_base_s} s) is too coarse to check frame times at {fps} fps; is that the video's frame rate?")]
    CoarseTimeBase {
        /// The file.
        path: PathBuf,
        /// Time base, s.
        time_base_s: f64,
        /// Expected rate, Hz.
        fps: f64,
    },
    /// The first frame whose timestamp is not where the expected frame rate puts it.
    #[error("{path}: frame {frame} is at {time_s:.6} s after the first, expected {expected_s:.6} s at {fps} fps: {what}")]
    IrregularTimestamps {
        /// The file.
        path: PathBuf,
        /// First irregular frame (0-based).
        frame: usize,
        /// Its container time after the first frame, s.
        time_s: f64,
        /// Where the expected rate puts it, s.
        expected_s: f64,
        /// Expected rate, Hz.
        fps: f64,
        /// Dropped frame, variable rate or other rate.
        what: String,
    },
    /// The container declares more frames (its frame count, or its duration) than it has
    /// timestamps for: the file is truncated, or frames are lost.
    #[error("{path}: frames from {frame} on are missing: {what} (truncated or damaged file)")]
    MissingFrames {
        /// The file.
        path: PathBuf,
        /// First missing frame (the number of frames found).
        frame: usize,
        /// What the container declares.
        what: String,
    },
    /// The decoder's output ended inside a frame or before the last frame.
    #[error("{path}: frame {frame} of {frames}: the decoded stream ended ({got} of {needed} bytes of this frame; truncated or damaged file){stderr}")]
    Truncated {
        /// The file.
        path: PathBuf,
        /// The frame being read.
        frame: usize,
        /// Frames the container lists.
        frames: usize,
        /// Bytes of the frame received.
        got: usize,
        /// Bytes a frame has.
        needed: usize,
        /// What ffmpeg said, if anything (prefixed by "; ffmpeg: ").
        stderr: String,
    },
    /// ffmpeg reports damaged data or fails, or gives more frames than the container lists.
    #[error("{path}: frame {frame}: {what}")]
    DecodeFailed {
        /// The file.
        path: PathBuf,
        /// Frames read when it was noticed.
        frame: usize,
        /// What happened.
        what: String,
    },
    /// A buffer of the wrong bit depth was passed.
    #[error("{path}: the video has {bits}-bit frames; read them with {use_fn}")]
    WrongDepth {
        /// The file.
        path: PathBuf,
        /// The video's depth.
        bits: u32,
        /// The method to call instead.
        use_fn: &'static str,
    },
    /// A frame to write has the wrong size, or the writer's settings are impossible.
    #[error("{path}: {what}")]
    BadFrame {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
    /// Reading from or writing to the ffmpeg process failed.
    #[error("{path}: I/O with ffmpeg failed: {source}{stderr}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The error.
        source: std::io::Error,
        /// What ffmpeg said, if anything.
        stderr: String,
    },
}

impl VideoError {
    /// Whether the error comes from the input (the file or the expected rate) rather than from
    /// the machine (FFmpeg missing, a pipe failing).
    pub fn is_bad_input(&self) -> bool {
        !matches!(
            self,
            VideoError::ProgramMissing { .. } | VideoError::Io { .. }
        )
    }

    /// As an [`anyhow::Error`], carrying [`crate::BadInput`] when [`Self::is_bad_input`] (so the
    /// binary exits with code 2).
    pub fn into_anyhow(self) -> anyhow::Error {
        if self.is_bad_input() {
            crate::bad_input(self.to_string())
        } else {
            anyhow::Error::new(self)
        }
    }
}

/// Starts `cmd`, which runs `program` on `path`: a program that cannot be started is a
/// [`VideoError::ProgramMissing`] naming both.
fn spawn(cmd: &mut Command, program: &str, path: &Path) -> Result<Child, VideoError> {
    cmd.spawn()
        .map_err(|source| program_missing(program, path, source))
}

/// Starts `cmd` as a reader of `path`: no input, its output and its messages piped.
fn spawn_reader(cmd: &mut Command, program: &str, path: &Path) -> Result<Child, VideoError> {
    let cmd = cmd.stdin(Stdio::null()).stdout(Stdio::piped());
    spawn(cmd.stderr(Stdio::piped()), program, path)
}

fn program_missing(program: &str, path: &Path, source: std::io::Error) -> VideoError {
    VideoError::ProgramMissing {
        program: program.into(),
        path: path.into(),
        source,
    }
}

/// Keeps the last few kB of a child's stderr, read on a thread so the child never blocks on it.
fn collect_stderr(mut pipe: impl Read + Send + 'static) -> JoinHandle<String> {
    std::thread::spawn(move || {
        const KEEP: usize = 4000;
        let mut all = Vec::new();
        let mut chunk = [0u8; 4096];
        loop {
            match pipe.read(&mut chunk) {
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    all.extend_from_slice(&chunk[..n]);
                    if all.len() > 2 * KEEP {
                        all.drain(..all.len() - KEEP);
                    }
                }
            }
        }
        let start = all.len().saturating_sub(KEEP);
        String::from_utf8_lossy(&all[start..]).into_owned()
    })
}
/// A file path as an FFmpeg argument: a relative name that starts with `-` (`-y.mkv`) would be
/// read as an option, so it is given as `./-y.mkv`.
pub(crate) fn file_arg(path: &Path) -> PathBuf {
    if path.is_relative() && path.as_os_str().to_string_lossy().starts_with('-') {
        Path::new(".").join(path)
    } else {
        path.to_path_buf()
    }
}

#[cfg(test)]
mod tests {
    use super::probe::{check_times, component_bits};
    use super::writer::rate_string;
    use super::*;

    fn have_ffmpeg() -> bool {
        let ok = |p: &str| {
            Command::new(p)
                .arg("-version")
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success())
        };
        let have = ok("ffmpeg") && ok("ffprobe");
        if !have {
            println!("SKIPPED: ffmpeg/ffprobe not installed (Debian: apt-get install ffmpeg)");
        }
        have
    }

    /// A temporary directory for a test that needs ffmpeg, `None` (the test is skipped) without.
    fn ffmpeg_tempdir() -> Option<tempfile::TempDir> {
        have_ffmpeg().then(|| tempfile::tempdir().unwrap())
    }

    const W: usize = 33;
    const H: usize = 17;
    const N: usize = 24;

    /// Frame `k`: a gradient that moves with `k`, every value 0..=255 used somewhere.
    fn frame(k: usize) -> Vec<u8> {
        (0..W * H).map(|i| ((i * 7 + k * 13) % 256) as u8).collect()
    }

    fn raw_file(dir: &Path) -> PathBuf {
        let p = dir.join("frames.gray");
        let all: Vec<u8> = (0..N).flat_map(frame).collect();
        std::fs::write(&p, all).unwrap();
        p
    }

    /// Runs the ffmpeg CLI to make the test video `dir/name` from the raw frames at 120 fps.
    fn encode(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
        let raw = raw_file(dir);
        let out = dir.join(name);
        let status = Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "gray"])
            .args(["-s", &format!("{W}x{H}"), "-framerate", "120", "-i"])
            .arg(raw)
            .args(extra)
            .arg(&out)
            .status()
            .unwrap();
        assert!(status.success(), "ffmpeg {extra:?} {}", out.display());
        out
    }

    /// An FFV1 test video whose frames or timestamps the filter `vf` changed (timestamps passed
    /// through as they are), with the encoder options `extra`.
    fn retimed(dir: &Path, name: &str, vf: &str, extra: &[&str]) -> PathBuf {
        let passthrough = ["-vf", vf, "-vsync", "passthrough"];
        encode(
            dir,
            name,
            &[&passthrough[..], extra, &["-c:v", "ffv1"]].concat(),
        )
    }

    /// Opening `path` at `fps` fails on irregular timestamps from `frame` on.
    fn irregular_at(path: &Path, fps: f64, frame: usize) -> VideoError {
        let e = VideoFrames::open(path, fps).unwrap_err();
        assert!(
            matches!(e, VideoError::IrregularTimestamps { frame: f, .. } if f == frame),
            "{e}"
        );
        e
    }

    /// Reading the `what` file `path` to its end fails, naming the file and a frame.
    fn assert_read_fails(path: &Path, what: &str) {
        match read_all(path, 120.0) {
            Ok(frames) => panic!("{what} file read as {} frames", frames.len()),
            Err(e) => {
                println!("{what}: {e}");
                let name = path.file_name().unwrap().to_string_lossy();
                assert!(e.to_string().contains(&*name), "{e}");
                assert!(e.to_string().contains("frame"), "{e}");
            }
        }
    }

    /// Writes the test frames with [`Ffv1Writer`] to `dir/name` at 120 fps.
    fn write_ffv1(dir: &Path, name: &str) -> PathBuf {
        let path = dir.join(name);
        let mut w = Ffv1Writer::create(&path, W, H, 120.0, Pixels::Grey8).unwrap();
        for k in 0..N {
            w.write_frame(&frame(k)).unwrap();
        }
        assert_eq!(w.finish().unwrap(), N);
        path
    }

    fn read_all(path: &Path, fps: f64) -> Result<Vec<Vec<u8>>, VideoError> {
        let mut v = VideoFrames::open(path, fps)?;
        let mut out = Vec::new();
        let mut buf = Vec::new();
        while let Some(info) = v.next_frame_u8(&mut buf)? {
            assert_eq!(info.index, out.len());
            out.push(buf.clone());
        }
        Ok(out)
    }

    #[test]
    fn ffv1_round_trip_is_bit_identical() {
        let Some(dir) = ffmpeg_tempdir() else {
            return;
        };
        let path = write_ffv1(dir.path(), "a.mkv");
        let mut v = VideoFrames::open(&path, 120.0).unwrap();
        let info = v.info().clone();
        assert_eq!(
            (info.width, info.height, info.bits, info.frames),
            (W, H, 8, N)
        );
        assert_eq!(
            (info.codec.as_str(), info.pix_fmt.as_str()),
            ("ffv1", "gray")
        );
        let mut frame_buf = GreyFrame::U8 {
            width: 0,
            height: 0,
            data: Vec::new(),
        };
        let mut k = 0;
        let mut first_ptr = None;
        while let Some(fi) = v.next_frame(&mut frame_buf).unwrap() {
            let GreyFrame::U8 {
                width,
                height,
                data,
            } = &frame_buf
            else {
                panic!("8-bit video gives U8 frames")
            };
            assert_eq!((*width, *height), (W, H));
            assert_eq!(data, &frame(k), "frame {k}");
            // Matroska keeps milliseconds: the container time is k / 120 s to half a ms.
            assert!(
                (fi.time_s - k as f64 / 120.0).abs() <= 0.0005 + 1e-9,
                "{fi:?}"
            );
            // One buffer, reused (memory stays one frame).
            let ptr = data.as_ptr();
            if k > 0 {
                assert_eq!(Some(ptr), first_ptr);
            }
            first_ptr = Some(ptr);
            k += 1;
        }
        assert_eq!(k, N);
        assert!(v.next_frame(&mut frame_buf).unwrap().is_none());
    }

    #[test]
    fn sixteen_bit_round_trip_is_bit_identical() {
        let Some(dir) = ffmpeg_tempdir() else {
            return;
        };
        let path = dir.path().join("b.mkv");
        let f16 = |k: usize| -> Vec<u16> {
            (0..W * H)
                .map(|i| ((i * 2477 + k * 40_503) % 65_536) as u16)
                .collect()
        };
        let mut w = Ffv1Writer::create(&path, W, H, 120.0, Pixels::Grey16).unwrap();
        for k in 0..5 {
            w.write_frame_u16(&f16(k)).unwrap();
        }
        w.finish().unwrap();
        let mut v = VideoFrames::open(&path, 120.0).unwrap();
        assert_eq!(v.info().bits, 16);
        let mut buf = Vec::new();
        assert!(matches!(
            v.next_frame_u8(&mut Vec::new()),
            Err(VideoError::WrongDepth { bits: 16, .. })
        ));
        for k in 0..5 {
            assert!(v.next_frame_u16(&mut buf).unwrap().is_some());
            assert_eq!(buf, f16(k));
        }
        assert!(v.next_frame_u16(&mut buf).unwrap().is_none());
    }

    #[test]
    fn avi_mov_and_mp4_containers() {
        let Some(dir) = ffmpeg_tempdir() else {
            return;
        };
        let want: Vec<Vec<u8>> = (0..N).map(frame).collect();
        // Lossless codecs: bit-identical.
        for (name, codec) in [("c.avi", "ffv1"), ("c.mov", "png")] {
            let path = encode(dir.path(), name, &["-c:v", codec, "-pix_fmt", "gray"]);
            assert_eq!(read_all(&path, 120.0).unwrap(), want, "{name}");
        }
        // H.264 in MP4 as cameras write it: limited-range YUV 4:2:0 (here losslessly coded,
        // qp 0). Its Y plane is expanded back to full range, so the grey values come back to
        // within the rounding of the two range conversions: one level.
        // (x264 needs even sizes: the top-left 32x16 pixels.)
        let mp4 = encode(
            dir.path(),
            "c.mp4",
            &[
                "-vf",
                "crop=32:16:0:0,scale=in_range=full:out_range=limited,format=yuv420p",
                "-color_range",
                "tv",
                "-c:v",
                "libx264",
                "-qp",
                "0",
            ],
        );
        let got = read_all(&mp4, 120.0).unwrap();
        assert_eq!(got.len(), N);
        let cropped: Vec<u8> = want
            .iter()
            .flat_map(|f| f.chunks(W).take(16).flat_map(|row| row[..32].to_vec()))
            .collect();
        assert_eq!(got.iter().map(Vec::len).sum::<usize>(), cropped.len());
        let worst = got
            .iter()
            .flatten()
            .zip(&cropped)
            .map(|(a, b)| (*a as i32 - *b as i32).abs())
            .max()
            .unwrap();
        assert!(worst <= 1, "worst grey difference {worst}");
    }

    #[test]
    fn dropped_frame_is_named() {
        let Some(dir) = ffmpeg_tempdir() else {
            return;
        };
        // Frame 5 removed, the others keep their timestamps: a gap of two periods.
        let path = retimed(dir.path(), "drop.mkv", "select='not(eq(n\\,5))'", &[]);
        let e = irregular_at(&path, 120.0, 5);
        let msg = e.to_string();
        assert!(
            msg.contains("drop.mkv: frame 5") && msg.contains("dropped frame"),
            "{msg}"
        );
        assert!(e.is_bad_input());
    }

    #[test]
    fn variable_frame_rate_and_wrong_rate_are_named() {
        let Some(dir) = ffmpeg_tempdir() else {
            return;
        };
        // From frame 7 on, every frame 0.4 period late (a 3.3 ms jitter at 120 fps).
        let setpts = "settb=1/1200,setpts='10*N+4*gte(N\\,7)'";
        let path = retimed(dir.path(), "vfr.mkv", setpts, &["-enc_time_base", "1/1200"]);
        let e = irregular_at(&path, 120.0, 7);
        assert!(e.to_string().contains("variable frame rate"), "{e}");
        // A regular 120 fps file read as 100 fps: the first interval is already wrong.
        let good = write_ffv1(dir.path(), "good.mkv");
        irregular_at(&good, 100.0, 1);
        // 119.88 fps (NTSC-style) read as 120: intervals pass one by one, the drift does not.
        let ntsc = dir.path().join("ntsc.mkv");
        let mut w = Ffv1Writer::create(&ntsc, W, H, 120_000.0 / 1001.0, Pixels::Grey8).unwrap();
        for _ in 0..200 {
            w.write_frame(&frame(0)).unwrap();
        }
        w.finish().unwrap();
        let e = VideoFrames::open(&ntsc, 120.0).unwrap_err();
        assert!(
            e.to_string()
                .contains("frame rate is 119.8801 fps (120000/1001), constant"),
            "{e}"
        );
        assert!(VideoFrames::open(&ntsc, 120_000.0 / 1001.0).is_ok());
    }

    #[test]
    fn truncated_and_damaged_files_name_the_frame() {
        let Some(dir) = ffmpeg_tempdir() else {
            return;
        };
        let path = write_ffv1(dir.path(), "full.mkv");
        let bytes = std::fs::read(&path).unwrap();
        // Cut in the middle of the frames.
        let cut = dir.path().join("cut.mkv");
        std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).unwrap();
        assert_read_fails(&cut, "truncated");
        // AVI keeps its frame count in the header.
        let avi = encode(
            dir.path(),
            "full.avi",
            &["-c:v", "ffv1", "-pix_fmt", "gray"],
        );
        let avi_bytes = std::fs::read(&avi).unwrap();
        let cut_avi = dir.path().join("cut.avi");
        std::fs::write(&cut_avi, &avi_bytes[..avi_bytes.len() / 2]).unwrap();
        let e = read_all(&cut_avi, 120.0).unwrap_err();
        println!("truncated AVI: {e}");
        assert!(e.to_string().contains("cut.avi"), "{e}");
        assert!(
            matches!(
                e,
                VideoError::MissingFrames { .. } | VideoError::Truncated { .. }
            ),
            "{e}"
        );
        // Damaged bytes inside a frame (slice CRCs catch it).
        let mut bad = bytes.clone();
        let mid = bytes.len() / 2;
        for b in &mut bad[mid..mid + 16] {
            *b ^= 0x5a;
        }
        let damaged = dir.path().join("damaged.mkv");
        std::fs::write(&damaged, &bad).unwrap();
        assert_read_fails(&damaged, "damaged");
        // Not a video, and no file at all.
        let text = dir.path().join("notes.mkv");
        std::fs::write(&text, "not a video").unwrap();
        let e = VideoFrames::open(&text, 120.0).unwrap_err();
        assert!(matches!(e, VideoError::Unreadable { .. }), "{e}");
        assert!(e.to_string().contains("notes.mkv"));
        let e = VideoFrames::open(&dir.path().join("missing.avi"), 120.0).unwrap_err();
        assert!(e.to_string().contains("missing.avi"), "{e}");
    }

    #[test]
    fn missing_ffmpeg_says_how_to_install_it() {
        let e = VideoFrames::open_with(
            Path::new("x.mkv"),
            120.0,
            false,
            "ffprobe-not-here",
            "ffmpeg",
        )
        .unwrap_err();
        assert!(matches!(e, VideoError::ProgramMissing { .. }));
        assert!(!e.is_bad_input());
        let msg = e.to_string();
        assert!(
            msg.contains("ffprobe-not-here") && msg.contains("x.mkv"),
            "{msg}"
        );
        assert!(msg.contains("apt-get install ffmpeg"), "{msg}");
    }

    #[test]
    fn bits_from_pixel_format_names() {
        for (f, b) in [
            ("gray", 8),
            ("yuv420p", 8),
            ("nv12", 8),
            ("rgb24", 8),
            ("rgb565le", 8),
            ("gray12le", 12),
            ("gray16be", 16),
            ("yuv420p10le", 10),
            ("p010le", 10),
            ("rgb48le", 16),
            ("rgba64be", 16),
        ] {
            assert_eq!(component_bits(f), b, "{f}");
        }
    }

    #[test]
    fn rates_as_ffmpeg_reads_them() {
        assert_eq!(rate_string(120.0), "120/1");
        assert_eq!(rate_string(120_000.0 / 1001.0), "120000/1001");
        assert_eq!(rate_string(2.5), "5/2");
        assert_eq!(
            rate_string(std::f64::consts::PI),
            format!("{}", std::f64::consts::PI)
        );
    }

    #[test]
    fn timestamp_check_closed_cases() {
        let p = Path::new("t.mkv");
        let regular: Vec<f64> = (0..100).map(|i| i as f64 / 120.0).collect();
        assert!(check_times(p, &regular, 120.0, 1e-3, false).is_ok());
        // Millisecond rounding (Matroska) stays within one tick.
        let ms: Vec<f64> = regular.iter().map(|t| (t * 1e3).round() / 1e3).collect();
        assert!(check_times(p, &ms, 120.0, 1e-3, false).is_ok());
        let mut dropped = regular.clone();
        dropped.remove(40);
        let e = check_times(p, &dropped, 120.0, 1e-3, false).unwrap_err();
        assert!(matches!(
            e,
            VideoError::IrregularTimestamps { frame: 40, .. }
        ));
        // AVI counts frames (time base 1/fps): exact, and a 0.1 ms error is already irregular.
        assert!(check_times(p, &regular, 120.0, 1.0 / 120.0, false).is_ok());
        let mut late = regular.clone();
        late[60] += 1e-4;
        assert!(check_times(p, &late, 120.0, 1.0 / 120.0, false).is_err());
        // A slow-motion file (240 fps stored as 30) read at 240: an error naming the
        // container's rate and --retime, and with it a retiming that returns that rate; a
        // retiming still needs regular timestamps (a dropped frame stays one).
        let slow: Vec<f64> = (0..100).map(|i| i as f64 / 30.0).collect();
        match check_times(p, &slow, 240.0, 1e-3, false) {
            Err(e @ VideoError::IrregularTimestamps { .. }) => {
                let text = e.to_string();
                assert!(text.contains("30.0000 fps (30/1), constant"), "{text}");
                assert!(text.contains("$retime"), "{text}");
            }
            other => panic!("{other:?}"),
        }
        let rate = check_times(p, &slow, 240.0, 1e-3, true).unwrap().unwrap();
        assert!((rate - 30.0).abs() < 1e-9, "{rate}");
        assert_eq!(check_times(p, &slow, 30.0, 1e-3, true).unwrap(), None);
        let mut slow_dropped = slow.clone();
        slow_dropped.remove(50);
        assert!(check_times(p, &slow_dropped, 240.0, 1e-3, true).is_err());
        // A time base of 1/50 s cannot resolve 120 fps.
        assert!(matches!(
            check_times(p, &regular, 120.0, 0.02, false),
            Err(VideoError::CoarseTimeBase { .. })
        ));
    }
}

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
//! The timestamps (8 bytes a frame) are the only per-frame data kept for the whole video.
//!
//! # Memory and errors
//!
//! [`VideoFrames`] reads one frame into the caller's buffer per call and reuses its own byte
//! buffer: memory is one frame, whatever the video's length. A stream that ends early (a
//! truncated file), a decoding error (FFmpeg runs with `-xerror` and `-err_detect explode`, so a
//! damaged frame stops it rather than being concealed), or more frames than timestamps is an
//! error naming the file and the frame index.

use crate::analysis::GreyFrame;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

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
    /// Frame times from the container, seconds after the first frame.
    pub times_s: Vec<f64>,
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

/// A video opened for reading, frame by frame (see the module documentation).
#[derive(Debug)]
pub struct VideoFrames {
    info: VideoInfo,
    child: Child,
    stdout: ChildStdout,
    stderr: Option<JoinHandle<String>>,
    /// What ffmpeg has said so far (its stderr, as it arrives).
    said: Arc<Mutex<String>>,
    next: usize,
    bytes: Vec<u8>,
    finished: bool,
}

impl VideoFrames {
    /// Opens `path`, reads its stream properties and timestamps with `ffprobe`, checks the
    /// timestamps against `expected_fps`, and starts decoding.
    pub fn open(path: &Path, expected_fps: f64) -> Result<Self, VideoError> {
        Self::open_with(path, expected_fps, "ffprobe", "ffmpeg")
    }

    fn open_with(
        path: &Path,
        expected_fps: f64,
        ffprobe: &str,
        ffmpeg: &str,
    ) -> Result<Self, VideoError> {
        if !(expected_fps.is_finite() && expected_fps > 0.0) {
            return Err(VideoError::BadFps {
                path: path.into(),
                fps: expected_fps,
            });
        }
        let stream = probe_stream(path, ffprobe)?;
        let times_s = probe_times(path, ffprobe)?;
        check_times(path, &times_s, expected_fps, stream.time_base_s)?;
        check_complete(path, &times_s, expected_fps, &stream)?;
        let out_fmt = match stream.bits {
            8 => "gray".to_string(),
            b @ (9 | 10 | 12 | 14 | 16) => format!("gray{b}le"),
            _ => "gray16le".to_string(),
        };
        let bits = match stream.bits {
            8 => 8,
            b @ (9 | 10 | 12 | 14 | 16) => b,
            _ => 16,
        };
        let mut child = Command::new(ffmpeg)
            .args(["-nostdin", "-v", "warning", "-xerror", "-noautorotate"])
            .args(["-err_detect", "explode", "-i"])
            .arg(path)
            .args(["-map", "0:v:0", "-vsync", "passthrough", "-f", "rawvideo"])
            .args(["-pix_fmt", &out_fmt, "-"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| VideoError::ProgramMissing {
                program: ffmpeg.into(),
                path: path.into(),
                source,
            })?;
        let stdout = child.stdout.take().expect("stdout is piped");
        let said = Arc::new(Mutex::new(String::new()));
        let stderr = child
            .stderr
            .take()
            .map(|pipe| collect_stderr_into(pipe, Arc::clone(&said)));
        let bytes_per = if bits == 8 { 1 } else { 2 };
        Ok(VideoFrames {
            info: VideoInfo {
                path: path.into(),
                codec: stream.codec,
                pix_fmt: stream.pix_fmt,
                width: stream.width,
                height: stream.height,
                bits,
                frames: times_s.len(),
                fps: expected_fps,
                times_s,
            },
            child,
            stdout,
            stderr,
            said,
            next: 0,
            bytes: vec![0; stream.width * stream.height * bytes_per],
            finished: false,
        })
    }

    /// The video's properties.
    pub fn info(&self) -> &VideoInfo {
        &self.info
    }

    /// Reads the next frame into `frame` (reusing its buffer when the variant matches: `U8` for
    /// 8-bit videos, `U16` otherwise). `Ok(None)` after the last frame.
    pub fn next_frame(&mut self, frame: &mut GreyFrame) -> Result<Option<FrameInfo>, VideoError> {
        let (w, h) = (self.info.width, self.info.height);
        if self.info.bits == 8 {
            if !matches!(frame, GreyFrame::U8 { .. }) {
                *frame = GreyFrame::U8 {
                    width: w,
                    height: h,
                    data: Vec::new(),
                };
            }
            let GreyFrame::U8 {
                width,
                height,
                data,
            } = frame
            else {
                unreachable!("set to U8 above")
            };
            (*width, *height) = (w, h);
            self.next_frame_u8(data)
        } else {
            if !matches!(frame, GreyFrame::U16 { .. }) {
                *frame = GreyFrame::U16 {
                    width: w,
                    height: h,
                    data: Vec::new(),
                };
            }
            let GreyFrame::U16 {
                width,
                height,
                data,
            } = frame
            else {
                unreachable!("set to U16 above")
            };
            (*width, *height) = (w, h);
            self.next_frame_u16(data)
        }
    }

    /// Reads the next frame of an 8-bit video into `buf` (`width * height` pixels, row 0
    /// first). `Ok(None)` after the last frame.
    pub fn next_frame_u8(&mut self, buf: &mut Vec<u8>) -> Result<Option<FrameInfo>, VideoError> {
        if self.info.bits != 8 {
            return Err(self.wrong_depth("next_frame_u16"));
        }
        let Some(info) = self.read_bytes()? else {
            return Ok(None);
        };
        buf.clear();
        buf.extend_from_slice(&self.bytes);
        Ok(Some(info))
    }

    /// Reads the next frame of a deeper-than-8-bit video into `buf` (values in
    /// `0..2^bits`). `Ok(None)` after the last frame.
    pub fn next_frame_u16(&mut self, buf: &mut Vec<u16>) -> Result<Option<FrameInfo>, VideoError> {
        if self.info.bits == 8 {
            return Err(self.wrong_depth("next_frame_u8"));
        }
        let Some(info) = self.read_bytes()? else {
            return Ok(None);
        };
        buf.clear();
        buf.extend(
            self.bytes
                .chunks_exact(2)
                .map(|b| u16::from_le_bytes([b[0], b[1]])),
        );
        Ok(Some(info))
    }

    /// A line of ffmpeg's stderr from the decoder (`[<codec> @ 0x...] ...`): decoders that
    /// conceal damage (FFV1's slice CRC, H.264's reference errors) say so only as a warning.
    fn decoder_complaint(&self) -> Option<String> {
        let said = self.said.lock().ok()?;
        let prefix = format!("[{} @", self.info.codec);
        let lib_prefix = format!("[lib{}", self.info.codec);
        said.lines()
            .find(|l| l.starts_with(&prefix) || l.starts_with(&lib_prefix))
            .map(|l| l.trim().to_string())
    }

    fn wrong_depth(&self, use_fn: &'static str) -> VideoError {
        VideoError::WrongDepth {
            path: self.info.path.clone(),
            bits: self.info.bits,
            use_fn,
        }
    }

    /// Reads one frame's bytes into `self.bytes`; at the end, checks ffmpeg's exit.
    fn read_bytes(&mut self) -> Result<Option<FrameInfo>, VideoError> {
        if self.finished {
            return Ok(None);
        }
        let index = self.next;
        if index == self.info.frames {
            // All frames the container lists are read: the decoder must end here, successfully.
            self.finished = true;
            let mut probe = [0u8; 1];
            let extra = read_full(&mut self.stdout, &mut probe).map_err(|e| self.io(e))?;
            if extra > 0 {
                return Err(VideoError::DecodeFailed {
                    path: self.info.path.clone(),
                    frame: index,
                    what: format!(
                        "the decoder gives more frames than the container's {} timestamps",
                        self.info.frames
                    ),
                });
            }
            let status = self.child.wait().map_err(|e| self.io(e))?;
            // The reader thread has the whole of stderr once the pipe closes.
            if let Some(h) = self.stderr.take() {
                let _text = h.join();
            }
            if let Some(line) = self.decoder_complaint() {
                return Err(VideoError::DecodeFailed {
                    path: self.info.path.clone(),
                    frame: index,
                    what: format!("the decoder reports damaged data: {line}"),
                });
            }
            if !status.success() {
                return Err(VideoError::DecodeFailed {
                    path: self.info.path.clone(),
                    frame: index,
                    what: format!("ffmpeg failed ({status}){}", self.stderr_text()),
                });
            }
            return Ok(None);
        }
        let got = read_full(&mut self.stdout, &mut self.bytes).map_err(|e| self.io(e))?;
        if got < self.bytes.len() {
            self.finished = true;
            // Let ffmpeg finish writing its complaint before reading it.
            let _status = self.child.wait();
            return Err(VideoError::Truncated {
                path: self.info.path.clone(),
                frame: index,
                frames: self.info.frames,
                got,
                needed: self.bytes.len(),
                stderr: self.stderr_text(),
            });
        }
        if let Some(line) = self.decoder_complaint() {
            self.finished = true;
            return Err(VideoError::DecodeFailed {
                path: self.info.path.clone(),
                frame: index,
                what: format!(
                    "the decoder reports damaged data in this frame or one of the next few it \
                     is ahead by: {line}"
                ),
            });
        }
        self.next += 1;
        Ok(Some(FrameInfo {
            index,
            time_s: self.info.times_s[index],
        }))
    }

    fn io(&mut self, source: std::io::Error) -> VideoError {
        VideoError::Io {
            path: self.info.path.clone(),
            source,
            stderr: self.stderr_text(),
        }
    }

    /// ffmpeg's stderr as "; ffmpeg: ..." (empty if it said nothing); complete once the
    /// process has ended (the reader thread finishes when the pipe closes).
    fn stderr_text(&mut self) -> String {
        if let Some(h) = self.stderr.take() {
            let _text = h.join();
        }
        let text = self.said.lock().map(|s| s.clone()).unwrap_or_default();
        let text = text.trim();
        if text.is_empty() {
            String::new()
        } else {
            format!("; ffmpeg: {text}")
        }
    }
}

impl Drop for VideoFrames {
    fn drop(&mut self) {
        // Stopped early (or failed): end the decoder rather than leave it blocked on the pipe.
        if let Ok(None) = self.child.try_wait() {
            let _kill = self.child.kill();
        }
        let _status = self.child.wait();
    }
}

/// Reads until `buf` is full or the stream ends; returns the bytes read.
fn read_full(r: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match r.read(&mut buf[got..]) {
            Ok(0) => break,
            Ok(n) => got += n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(got)
}

/// Appends a child's stderr to `said` (at most the first 16 kB), read on a thread so the child
/// never blocks on it; the returned text is empty.
fn collect_stderr_into(
    mut pipe: impl Read + Send + 'static,
    said: Arc<Mutex<String>>,
) -> JoinHandle<String> {
    std::thread::spawn(move || {
        const KEEP: usize = 16_000;
        let mut chunk = [0u8; 4096];
        loop {
            match pipe.read(&mut chunk) {
                Ok(0) | Err(_) => break,
                Ok(n) => {
                    if let Ok(mut s) = said.lock() {
                        if s.len() < KEEP {
                            s.push_str(&String::from_utf8_lossy(&chunk[..n]));
                        }
                    }
                }
            }
        }
        String::new()
    })
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

struct StreamProps {
    codec: String,
    pix_fmt: String,
    width: usize,
    height: usize,
    bits: u32,
    time_base_s: f64,
    /// Frame count from the container's header, where it has one (AVI, MP4, MOV).
    nb_frames: Option<usize>,
    /// Duration of the video stream, or of the file when it holds only the video stream.
    duration_s: Option<f64>,
}

fn run_probe(
    path: &Path,
    ffprobe: &str,
    entries: &str,
    format: &str,
) -> Result<String, VideoError> {
    let out = Command::new(ffprobe)
        .args([
            "-v",
            "error",
            "-select_streams",
            "v:0",
            "-show_entries",
            entries,
        ])
        .args(["-of", format])
        .arg(path)
        .stdin(Stdio::null())
        .output()
        .map_err(|source| VideoError::ProgramMissing {
            program: ffprobe.into(),
            path: path.into(),
            source,
        })?;
    if !out.status.success() {
        return Err(VideoError::Unreadable {
            path: path.into(),
            stderr: String::from_utf8_lossy(&out.stderr).trim().to_string(),
        });
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

fn probe_stream(path: &Path, ffprobe: &str) -> Result<StreamProps, VideoError> {
    let text = run_probe(
        path,
        ffprobe,
        "stream=codec_name,width,height,pix_fmt,time_base,nb_frames,duration:format=duration,nb_streams",
        "json",
    )?;
    let missing = |what: &str| VideoError::NoVideoStream {
        path: path.into(),
        what: what.into(),
    };
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|_| missing("ffprobe's answer is not JSON"))?;
    let stream = &json["streams"][0];
    if !stream.is_object() {
        return Err(missing("no video stream"));
    }
    // ffprobe gives numbers for sizes and strings for the rest; "N/A" or absent when unknown.
    let text_of = |v: &serde_json::Value| -> Option<String> {
        let s = match v {
            serde_json::Value::String(s) => s.clone(),
            serde_json::Value::Number(n) => n.to_string(),
            _ => return None,
        };
        (!s.is_empty() && s != "N/A" && s != "unknown").then_some(s)
    };
    let count = |v: &serde_json::Value| -> Option<usize> {
        text_of(v)?.parse().ok().filter(|&n: &usize| n > 0)
    };
    let seconds = |v: &serde_json::Value| -> Option<f64> {
        text_of(v)?
            .parse()
            .ok()
            .filter(|d: &f64| d.is_finite() && *d > 0.0)
    };
    let width = count(&stream["width"]).ok_or_else(|| missing("no frame width"))?;
    let height = count(&stream["height"]).ok_or_else(|| missing("no frame height"))?;
    let pix_fmt = text_of(&stream["pix_fmt"]).ok_or_else(|| missing("no pixel format"))?;
    let time_base_s = text_of(&stream["time_base"])
        .as_deref()
        .and_then(parse_rational)
        .ok_or_else(|| missing("no time base"))?;
    let only_stream = count(&json["format"]["nb_streams"]) == Some(1);
    let duration_s = seconds(&stream["duration"]).or_else(|| {
        only_stream
            .then(|| seconds(&json["format"]["duration"]))
            .flatten()
    });
    Ok(StreamProps {
        codec: text_of(&stream["codec_name"]).unwrap_or_else(|| "unknown".into()),
        bits: component_bits(&pix_fmt),
        pix_fmt,
        width,
        height,
        time_base_s,
        nb_frames: count(&stream["nb_frames"]),
        duration_s,
    })
}

/// `"1/1000"` -> 0.001.
fn parse_rational(s: &str) -> Option<f64> {
    let (n, d) = s.split_once('/')?;
    let (n, d): (f64, f64) = (n.trim().parse().ok()?, d.trim().parse().ok()?);
    (n > 0.0 && d > 0.0).then_some(n / d)
}

/// Bits per component of an FFmpeg pixel format, from its name: formats with a bit depth above 8
/// end in the depth and the byte order (`yuv420p10le`, `gray12le`, `p010le`; `rgb48le` and
/// `rgba64le` are 16 bits a component); all others are 8 bits or fewer (`rgb565le` too).
fn component_bits(pix_fmt: &str) -> u32 {
    let Some(stem) = pix_fmt
        .strip_suffix("le")
        .or_else(|| pix_fmt.strip_suffix("be"))
    else {
        return 8;
    };
    let digits: String = stem
        .chars()
        .rev()
        .take_while(char::is_ascii_digit)
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    match digits.parse::<u32>() {
        Ok(b @ 9..=16) => b,
        Ok(32 | 48 | 64) => 16,
        _ => 8,
    }
}

/// Packet presentation times of the video stream, sorted, relative to the first.
fn probe_times(path: &Path, ffprobe: &str) -> Result<Vec<f64>, VideoError> {
    let mut child = Command::new(ffprobe)
        .args(["-v", "error", "-select_streams", "v:0"])
        .args(["-show_entries", "packet=pts_time,flags", "-of", "csv=p=0"])
        .arg(path)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|source| VideoError::ProgramMissing {
            program: ffprobe.into(),
            path: path.into(),
            source,
        })?;
    let stderr = child.stderr.take().map(collect_stderr);
    let stdout = child.stdout.take().expect("stdout is piped");
    let mut times = Vec::new();
    let mut bad = None;
    for line in BufReader::new(stdout).lines() {
        let Ok(line) = line else { break };
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let (pts, flags) = line.split_once(',').unwrap_or((line, ""));
        if flags.contains('D') {
            continue;
        }
        let frame = times.len();
        if bad.is_some() {
            continue;
        }
        if flags.contains('C') {
            bad = Some((frame, "the demuxer marks the packet corrupt".to_string()));
            continue;
        }
        match pts.trim().parse::<f64>() {
            Ok(t) if t.is_finite() => times.push(t),
            _ => bad = Some((frame, format!("no presentation timestamp ({pts:?})"))),
        }
    }
    let status = child.wait();
    let said = stderr.and_then(|h| h.join().ok()).unwrap_or_default();
    if !matches!(status, Ok(s) if s.success()) {
        return Err(VideoError::Unreadable {
            path: path.into(),
            stderr: said.trim().to_string(),
        });
    }
    if let Some((frame, what)) = bad {
        return Err(VideoError::BadPacket {
            path: path.into(),
            frame,
            what,
        });
    }
    if times.is_empty() {
        return Err(VideoError::NoVideoStream {
            path: path.into(),
            what: "no frames".into(),
        });
    }
    times.sort_by(f64::total_cmp);
    let t0 = times[0];
    for t in &mut times {
        *t -= t0;
    }
    Ok(times)
}

/// Tolerance on frame times: ffprobe prints microseconds (2 µs on a difference), plus one tick
/// of the time base (each timestamp is rounded to the tick, a difference of two to one) unless
/// the frame period is a whole number of ticks (AVI's 1/fps, MOV's 1/15360 at 120 fps: exact).
fn time_tolerance(period: f64, time_base_s: f64) -> f64 {
    let ticks = period / time_base_s;
    if (ticks - ticks.round()).abs() < 1e-6 * ticks.max(1.0) {
        2e-6
    } else {
        time_base_s + 2e-6
    }
}

/// Checks that the container declares no more frames than it has timestamps for: its header's
/// frame count, or its duration (the video stream's, or the file's when it holds only video).
fn check_complete(
    path: &Path,
    times: &[f64],
    fps: f64,
    stream: &StreamProps,
) -> Result<(), VideoError> {
    let n = times.len();
    if let Some(declared) = stream.nb_frames {
        if declared != n {
            return Err(VideoError::MissingFrames {
                path: path.into(),
                frame: n.min(declared),
                what: format!("the container's header lists {declared} frames, it holds {n}"),
            });
        }
    } else if let Some(duration) = stream.duration_s {
        let period = 1.0 / fps;
        let covered = times[n - 1] + period;
        let tol = time_tolerance(period, stream.time_base_s);
        if duration - covered > 0.5 * period + tol {
            return Err(VideoError::MissingFrames {
                path: path.into(),
                frame: n,
                what: format!(
                    "the container declares {duration:.6} s (about {:.0} frames), its {n} frames cover {covered:.6} s",
                    duration * fps
                ),
            });
        }
    }
    Ok(())
}

/// Checks frame times (relative to the first) against `fps` (see the module documentation).
fn check_times(path: &Path, times: &[f64], fps: f64, time_base_s: f64) -> Result<(), VideoError> {
    let period = 1.0 / fps;
    let tol = time_tolerance(period, time_base_s);
    if tol >= period / 3.0 {
        return Err(VideoError::CoarseTimeBase {
            path: path.into(),
            time_base_s,
            fps,
        });
    }
    for i in 1..times.len() {
        let expected = i as f64 * period;
        let step = times[i] - times[i - 1];
        let what = if (step - period).abs() > tol {
            if step > 1.5 * period {
                format!(
                    "{:.2} frame periods after the previous frame: a dropped frame",
                    step / period
                )
            } else {
                format!(
                    "{:.3} frame periods after the previous frame: a variable frame rate",
                    step / period
                )
            }
        } else if (times[i] - expected).abs() > tol {
            format!(
                "the container's frame rate is about {:.4} fps, not {fps}",
                i as f64 / times[i]
            )
        } else {
            continue;
        };
        return Err(VideoError::IrregularTimestamps {
            path: path.into(),
            frame: i,
            time_s: times[i],
            expected_s: expected,
            fps,
            what,
        });
    }
    Ok(())
}

/// Writes a lossless FFV1 video in a Matroska container from grey frames, through an `ffmpeg`
/// subprocess fed on its standard input: intra-only (every frame a key frame), slice CRCs on (a
/// damaged frame is detected on reading), pixel format `gray` or `gray16le`.
#[derive(Debug)]
pub struct Ffv1Writer {
    path: PathBuf,
    child: Child,
    stdin: Option<ChildStdin>,
    stderr: Option<JoinHandle<String>>,
    width: usize,
    height: usize,
    sixteen: bool,
    bytes: Vec<u8>,
    frames: usize,
}

impl Ffv1Writer {
    /// Starts an 8-bit (`gray`) video of `width x height` frames at `fps` frames per second.
    pub fn create(path: &Path, width: usize, height: usize, fps: f64) -> Result<Self, VideoError> {
        Self::start(path, width, height, fps, false)
    }

    /// Starts a 16-bit (`gray16le`) video.
    pub fn create_u16(
        path: &Path,
        width: usize,
        height: usize,
        fps: f64,
    ) -> Result<Self, VideoError> {
        Self::start(path, width, height, fps, true)
    }

    fn start(
        path: &Path,
        width: usize,
        height: usize,
        fps: f64,
        sixteen: bool,
    ) -> Result<Self, VideoError> {
        if width == 0 || height == 0 || !(fps.is_finite() && fps > 0.0) {
            return Err(VideoError::BadFrame {
                path: path.into(),
                what: format!("cannot write {width}x{height} frames at {fps} fps"),
            });
        }
        let fmt = if sixteen { "gray16le" } else { "gray" };
        let mut child = Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", fmt])
            .args(["-s", &format!("{width}x{height}"), "-r", &rate_string(fps)])
            .args([
                "-i",
                "-",
                "-c:v",
                "ffv1",
                "-level",
                "3",
                "-g",
                "1",
                "-slicecrc",
                "1",
            ])
            .args(["-pix_fmt", fmt, "-f", "matroska"])
            .arg(path)
            .stdin(Stdio::piped())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|source| VideoError::ProgramMissing {
                program: "ffmpeg".into(),
                path: path.into(),
                source,
            })?;
        let stdin = child.stdin.take();
        let stderr = child.stderr.take().map(collect_stderr);
        Ok(Ffv1Writer {
            path: path.into(),
            child,
            stdin,
            stderr,
            width,
            height,
            sixteen,
            bytes: Vec::new(),
            frames: 0,
        })
    }

    /// Appends an 8-bit frame (`width * height` pixels, row 0 first).
    pub fn write_frame(&mut self, frame: &[u8]) -> Result<(), VideoError> {
        self.check(frame.len(), false)?;
        self.send_frame(|bytes| bytes.extend_from_slice(frame))
    }

    /// Appends a 16-bit frame (a writer from [`Ffv1Writer::create_u16`]).
    pub fn write_frame_u16(&mut self, frame: &[u16]) -> Result<(), VideoError> {
        self.check(frame.len(), true)?;
        self.send_frame(|bytes| bytes.extend(frame.iter().flat_map(|v| v.to_le_bytes())))
    }

    fn check(&self, len: usize, sixteen: bool) -> Result<(), VideoError> {
        if sixteen != self.sixteen || len != self.width * self.height {
            return Err(VideoError::BadFrame {
                path: self.path.clone(),
                what: format!(
                    "frame {}: {len} {}-bit pixels given, the video has {}x{} {}-bit pixels",
                    self.frames,
                    if sixteen { 16 } else { 8 },
                    self.width,
                    self.height,
                    if self.sixteen { 16 } else { 8 }
                ),
            });
        }
        Ok(())
    }

    fn send_frame(&mut self, fill: impl FnOnce(&mut Vec<u8>)) -> Result<(), VideoError> {
        self.bytes.clear();
        fill(&mut self.bytes);
        let result = match self.stdin.as_mut() {
            Some(stdin) => stdin.write_all(&self.bytes),
            None => Err(std::io::Error::other("ffmpeg's input is closed")),
        };
        if let Err(source) = result {
            self.stdin = None;
            let _status = self.child.wait();
            return Err(VideoError::Io {
                path: self.path.clone(),
                source,
                stderr: self.stderr_text(),
            });
        }
        self.frames += 1;
        Ok(())
    }

    fn stderr_text(&mut self) -> String {
        let text = self
            .stderr
            .take()
            .and_then(|h| h.join().ok())
            .unwrap_or_default();
        let text = text.trim();
        if text.is_empty() {
            String::new()
        } else {
            format!("; ffmpeg: {text}")
        }
    }

    /// Closes the input and waits for ffmpeg to write the file; returns the frames written.
    pub fn finish(mut self) -> Result<usize, VideoError> {
        drop(self.stdin.take());
        let status = self.child.wait().map_err(|source| VideoError::Io {
            path: self.path.clone(),
            source,
            stderr: String::new(),
        })?;
        if !status.success() {
            let stderr = self.stderr_text();
            return Err(VideoError::DecodeFailed {
                path: self.path.clone(),
                frame: self.frames,
                what: format!("ffmpeg could not write the video ({status}){stderr}"),
            });
        }
        Ok(self.frames)
    }
}

impl Drop for Ffv1Writer {
    fn drop(&mut self) {
        drop(self.stdin.take());
        let _status = self.child.wait();
    }
}

/// A frame rate as FFmpeg should read it: `p/q` when a denominator up to 10 010 gives it to
/// 1e-12 (`120000/1001` for 119.88...), else the
/// decimal.
fn rate_string(fps: f64) -> String {
    for q in 1..=10_010u32 {
        let p = (fps * q as f64).round();
        if p >= 1.0 && (p / q as f64 - fps).abs() <= 1e-12 * fps {
            return format!("{p}/{q}");
        }
    }
    format!("{fps}")
}

#[cfg(test)]
mod tests {
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

    /// Runs the ffmpeg CLI to make a test video from the raw frames at 120 fps.
    fn encode(raw: &Path, out: &Path, extra: &[&str]) {
        let status = Command::new("ffmpeg")
            .args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "gray"])
            .args(["-s", &format!("{W}x{H}"), "-framerate", "120", "-i"])
            .arg(raw)
            .args(extra)
            .arg(out)
            .status()
            .unwrap();
        assert!(status.success(), "ffmpeg {extra:?} {}", out.display());
    }

    fn write_ffv1(path: &Path) {
        let mut w = Ffv1Writer::create(path, W, H, 120.0).unwrap();
        for k in 0..N {
            w.write_frame(&frame(k)).unwrap();
        }
        assert_eq!(w.finish().unwrap(), N);
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
        if !have_ffmpeg() {
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.mkv");
        write_ffv1(&path);
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
        if !have_ffmpeg() {
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("b.mkv");
        let f16 = |k: usize| -> Vec<u16> {
            (0..W * H)
                .map(|i| ((i * 2477 + k * 40_503) % 65_536) as u16)
                .collect()
        };
        let mut w = Ffv1Writer::create_u16(&path, W, H, 120.0).unwrap();
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
        if !have_ffmpeg() {
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let raw = raw_file(dir.path());
        let want: Vec<Vec<u8>> = (0..N).map(frame).collect();
        // Lossless codecs: bit-identical.
        let avi = dir.path().join("c.avi");
        encode(&raw, &avi, &["-c:v", "ffv1", "-pix_fmt", "gray"]);
        assert_eq!(read_all(&avi, 120.0).unwrap(), want);
        let mov = dir.path().join("c.mov");
        encode(&raw, &mov, &["-c:v", "png", "-pix_fmt", "gray"]);
        assert_eq!(read_all(&mov, 120.0).unwrap(), want);
        // H.264 in MP4 as cameras write it: limited-range YUV 4:2:0 (here losslessly coded,
        // qp 0). Its Y plane is expanded back to full range, so the grey values come back to
        // within the rounding of the two range conversions: one level.
        // (x264 needs even sizes: the top-left 32x16 pixels.)
        let mp4 = dir.path().join("c.mp4");
        encode(
            &raw,
            &mp4,
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
        if !have_ffmpeg() {
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let raw = raw_file(dir.path());
        let path = dir.path().join("drop.mkv");
        // Frame 5 removed, the others keep their timestamps: a gap of two periods.
        encode(
            &raw,
            &path,
            &[
                "-vf",
                "select='not(eq(n\\,5))'",
                "-vsync",
                "passthrough",
                "-c:v",
                "ffv1",
            ],
        );
        let e = VideoFrames::open(&path, 120.0).unwrap_err();
        let msg = e.to_string();
        assert!(
            matches!(e, VideoError::IrregularTimestamps { frame: 5, .. }),
            "{msg}"
        );
        assert!(
            msg.contains("drop.mkv: frame 5") && msg.contains("dropped frame"),
            "{msg}"
        );
        assert!(e.is_bad_input());
    }

    #[test]
    fn variable_frame_rate_and_wrong_rate_are_named() {
        if !have_ffmpeg() {
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let raw = raw_file(dir.path());
        let path = dir.path().join("vfr.mkv");
        // From frame 7 on, every frame 0.4 period late (a 3.3 ms jitter at 120 fps).
        encode(
            &raw,
            &path,
            &[
                "-vf",
                "settb=1/1200,setpts='10*N+4*gte(N\\,7)'",
                "-vsync",
                "passthrough",
                "-enc_time_base",
                "1/1200",
                "-c:v",
                "ffv1",
            ],
        );
        let e = VideoFrames::open(&path, 120.0).unwrap_err();
        assert!(
            matches!(e, VideoError::IrregularTimestamps { frame: 7, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("variable frame rate"), "{e}");
        // A regular 120 fps file read as 100 fps: the first interval is already wrong.
        let good = dir.path().join("good.mkv");
        write_ffv1(&good);
        let e = VideoFrames::open(&good, 100.0).unwrap_err();
        assert!(
            matches!(e, VideoError::IrregularTimestamps { frame: 1, .. }),
            "{e}"
        );
        // 119.88 fps (NTSC-style) read as 120: intervals pass one by one, the drift does not.
        let ntsc = dir.path().join("ntsc.mkv");
        let mut w = Ffv1Writer::create(&ntsc, W, H, 120_000.0 / 1001.0).unwrap();
        for _ in 0..200 {
            w.write_frame(&frame(0)).unwrap();
        }
        w.finish().unwrap();
        let e = VideoFrames::open(&ntsc, 120.0).unwrap_err();
        assert!(e.to_string().contains("frame rate is about 119.8"), "{e}");
        assert!(VideoFrames::open(&ntsc, 120_000.0 / 1001.0).is_ok());
    }

    #[test]
    fn truncated_and_damaged_files_name_the_frame() {
        if !have_ffmpeg() {
            return;
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("full.mkv");
        write_ffv1(&path);
        let bytes = std::fs::read(&path).unwrap();
        // Cut in the middle of the frames.
        let cut = dir.path().join("cut.mkv");
        std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).unwrap();
        match read_all(&cut, 120.0) {
            Ok(frames) => panic!("truncated file read as {} frames", frames.len()),
            Err(e) => {
                println!("truncated: {e}");
                assert!(e.to_string().contains("cut.mkv"), "{e}");
                assert!(e.to_string().contains("frame"), "{e}");
            }
        }
        // AVI keeps its frame count in the header.
        let raw = raw_file(dir.path());
        let avi = dir.path().join("full.avi");
        encode(&raw, &avi, &["-c:v", "ffv1", "-pix_fmt", "gray"]);
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
        match read_all(&damaged, 120.0) {
            Ok(frames) => panic!("damaged file read as {} frames", frames.len()),
            Err(e) => {
                println!("damaged: {e}");
                assert!(e.to_string().contains("damaged.mkv"), "{e}");
                assert!(e.to_string().contains("frame"), "{e}");
            }
        }
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
        let e = VideoFrames::open_with(Path::new("x.mkv"), 120.0, "ffprobe-not-here", "ffmpeg")
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
        assert!(check_times(p, &regular, 120.0, 1e-3).is_ok());
        // Millisecond rounding (Matroska) stays within one tick.
        let ms: Vec<f64> = regular.iter().map(|t| (t * 1e3).round() / 1e3).collect();
        assert!(check_times(p, &ms, 120.0, 1e-3).is_ok());
        let mut dropped = regular.clone();
        dropped.remove(40);
        let e = check_times(p, &dropped, 120.0, 1e-3).unwrap_err();
        assert!(matches!(
            e,
            VideoError::IrregularTimestamps { frame: 40, .. }
        ));
        // AVI counts frames (time base 1/fps): exact, and a 0.1 ms error is already irregular.
        assert!(check_times(p, &regular, 120.0, 1.0 / 120.0).is_ok());
        let mut late = regular.clone();
        late[60] += 1e-4;
        assert!(check_times(p, &late, 120.0, 1.0 / 120.0).is_err());
        // A time base of 1/50 s cannot resolve 120 fps.
        assert!(matches!(
            check_times(p, &regular, 120.0, 0.02),
            Err(VideoError::CoarseTimeBase { .. })
        ));
    }
}

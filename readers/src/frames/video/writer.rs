//! [`Ffv1Writer`]: lossless FFV1/Matroska videos written through an `ffmpeg` subprocess.

use super::*;

/// Writes a lossless FFV1 video in a Matroska container from grey (or RGB) frames, through an
/// `ffmpeg` subprocess fed on its standard input: intra-only (every frame a key frame), slice
/// CRCs on (a damaged frame is detected on reading), pixel format `gray`, `gray16le` or, for
/// colour frames, `gbrp` (planar RGB, 8 bits: lossless; read back as its BT.601 luma).
#[derive(Debug)]
pub struct Ffv1Writer {
    path: PathBuf,
    child: Child,
    stdin: Option<ChildStdin>,
    stderr: Option<JoinHandle<String>>,
    width: usize,
    height: usize,
    kind: Pixels,
    bytes: Vec<u8>,
    frames: usize,
}

/// What a frame given to an [`Ffv1Writer`] holds per pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pixels {
    /// One 8-bit grey value.
    Grey8,
    /// One 16-bit grey value.
    Grey16,
    /// Three 8-bit values, R, G, B.
    Rgb8,
}

impl Pixels {
    /// FFmpeg's names of the raw input format and the stored one.
    fn formats(self) -> (&'static str, &'static str) {
        match self {
            Pixels::Grey8 => ("gray", "gray"),
            Pixels::Grey16 => ("gray16le", "gray16le"),
            Pixels::Rgb8 => ("rgb24", "gbrp"),
        }
    }

    /// Values per pixel.
    fn values(self) -> usize {
        match self {
            Pixels::Rgb8 => 3,
            _ => 1,
        }
    }

    fn describe(self) -> &'static str {
        match self {
            Pixels::Grey8 => "8-bit grey",
            Pixels::Grey16 => "16-bit grey",
            Pixels::Rgb8 => "8-bit RGB",
        }
    }
}

impl Ffv1Writer {
    /// Starts a video of `width x height` frames at `fps` frames per second, each pixel as
    /// `kind` says: 8-bit grey (`gray`), 16-bit grey (`gray16le`) or 8-bit RGB (stored as
    /// planar RGB); lossless in every case.
    pub fn create(
        path: &Path,
        width: usize,
        height: usize,
        fps: f64,
        kind: Pixels,
    ) -> Result<Self, VideoError> {
        check_size(path, (width, height), fps)?;
        let (input, stored) = kind.formats();
        let mut cmd = Command::new("ffmpeg");
        cmd.args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", input])
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
            .args(["-pix_fmt", stored, "-f", "matroska"]);
        Self::start(cmd, path, (width, height), kind)
    }

    /// Starts a video for a web page: VP9 in WebM (`yuv420p`, constant quality `crf`, 0 best
    /// to 63; 10 keeps a grey frame within a grey level or two), from 8-bit grey frames, an odd
    /// width or height padded by one black column or row. Not lossless: for showing, as
    /// browsers play it.
    pub fn create_webm(
        path: &Path,
        width: usize,
        height: usize,
        fps: f64,
        crf: u8,
    ) -> Result<Self, VideoError> {
        check_size(path, (width, height), fps)?;
        let mut cmd = Command::new("ffmpeg");
        cmd.args(["-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "gray"])
            .args(["-s", &format!("{width}x{height}"), "-r", &rate_string(fps)])
            .args(["-i", "-", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2"])
            .args([
                "-c:v",
                "libvpx-vp9",
                "-crf",
                &crf.min(63).to_string(),
                "-b:v",
                "0",
            ])
            // the real-time deadline: 5x faster than `good` on an HD mode video (0.95 s
            // against 4.6 s for 48 frames of 1280 x 720), PSNR 45.4 against 47.0 dB at this
            // crf, the file 1.5x larger (docs/performance.md)
            .args(["-row-mt", "1", "-deadline", "realtime", "-cpu-used", "5"])
            .args(["-pix_fmt", "yuv420p", "-f", "webm"]);
        Self::start(cmd, path, (width, height), Pixels::Grey8)
    }

    /// Spawns `cmd` writing `path` from frames on its standard input.
    fn start(
        mut cmd: Command,
        path: &Path,
        (width, height): (usize, usize),
        kind: Pixels,
    ) -> Result<Self, VideoError> {
        let mut child = spawn(
            cmd.arg(file_arg(path))
                .stdin(Stdio::piped())
                .stdout(Stdio::null())
                .stderr(Stdio::piped()),
            "ffmpeg",
            path,
        )?;
        let stdin = child.stdin.take();
        let stderr = child.stderr.take().map(collect_stderr);
        Ok(Ffv1Writer {
            path: path.into(),
            child,
            stdin,
            stderr,
            width,
            height,
            kind,
            bytes: Vec::new(),
            frames: 0,
        })
    }

    /// Appends an 8-bit frame (`width * height` pixels, row 0 first).
    pub fn write_frame(&mut self, frame: &[u8]) -> Result<(), VideoError> {
        self.check(frame.len(), Pixels::Grey8)?;
        self.send_frame(|bytes| bytes.extend_from_slice(frame))
    }

    /// Appends a colour frame (a writer of [`Pixels::Rgb8`]): `width * height`
    /// pixels of R, G, B, row 0 first.
    pub fn write_frame_rgb(&mut self, frame: &[u8]) -> Result<(), VideoError> {
        self.check(frame.len(), Pixels::Rgb8)?;
        self.send_frame(|bytes| bytes.extend_from_slice(frame))
    }

    /// Appends a 16-bit frame (a writer of [`Pixels::Grey16`]).
    pub fn write_frame_u16(&mut self, frame: &[u16]) -> Result<(), VideoError> {
        self.check(frame.len(), Pixels::Grey16)?;
        self.send_frame(|bytes| bytes.extend(frame.iter().flat_map(|v| v.to_le_bytes())))
    }

    fn check(&self, len: usize, kind: Pixels) -> Result<(), VideoError> {
        if kind != self.kind || len != self.width * self.height * kind.values() {
            return Err(VideoError::BadFrame {
                path: self.path.clone(),
                what: format!(
                    "frame {}: {len} {} values given, the video has {}x{} {} pixels",
                    self.frames,
                    kind.describe(),
                    self.width,
                    self.height,
                    self.kind.describe()
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

/// Refuses an empty frame or a rate that is not a positive number.
fn check_size(path: &Path, (width, height): (usize, usize), fps: f64) -> Result<(), VideoError> {
    if width == 0 || height == 0 || !(fps.is_finite() && fps > 0.0) {
        return Err(VideoError::BadFrame {
            path: path.into(),
            what: format!("cannot write {width}x{height} frames at {fps} fps"),
        });
    }
    Ok(())
}

/// A frame rate as FFmpeg should read it: `p/q` when a denominator up to 10 010 gives it to
/// 1e-12 (`120000/1001` for 119.88...), else the
/// decimal.
pub(super) fn rate_string(fps: f64) -> String {
    for q in 1..=10_010u32 {
        let p = (fps * q as f64).round();
        if p >= 1.0 && (p / q as f64 - fps).abs() <= 1e-12 * fps {
            return format!("{p}/{q}");
        }
    }
    format!("{fps}")
}

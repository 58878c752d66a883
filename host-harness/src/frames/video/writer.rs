//! [`Ffv1Writer`]: lossless FFV1/Matroska videos written through an `ffmpeg` subprocess.

use super::*;

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
        let mut child = spawn(
            Command::new("ffmpeg")
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
                .arg(file_arg(path))
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
pub(super) fn rate_string(fps: f64) -> String {
    for q in 1..=10_010u32 {
        let p = (fps * q as f64).round();
        if p >= 1.0 && (p / q as f64 - fps).abs() <= 1e-12 * fps {
            return format!("{p}/{q}");
        }
    }
    format!("{fps}")
}

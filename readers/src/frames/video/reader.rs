//! [`VideoFrames`]: frames decoded by an `ffmpeg` subprocess, one buffer at a time.

use super::probe::{check_complete, check_times, probe_stream, probe_times};
use super::*;

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

/// Decoder notes that are not damage: FFmpeg's MJPEG decoder says "EOI missing, emulating" for
/// every frame of many AVI files whose JPEG frames end without the end-of-image marker (the
/// image data is whole; a truncated frame is caught by the byte count and by other messages).
const BENIGN: [&str; 1] = ["EOI missing, emulating"];

impl VideoFrames {
    /// Opens `path`, reads its stream properties and timestamps with `ffprobe`, checks the
    /// timestamps against `expected_fps`, and starts decoding.
    pub fn open(path: &Path, expected_fps: f64) -> Result<Self, VideoError> {
        Self::open_with(path, expected_fps, false, "ffprobe", "ffmpeg")
    }

    /// As [`VideoFrames::open`], but a container whose timestamps are regular at another
    /// constant rate is retimed to `fps` (a slow-motion or time-lapse file: frames `1 / fps`
    /// apart, [`VideoInfo::container_fps`] its own rate) instead of refused.
    pub fn open_retimed(path: &Path, fps: f64) -> Result<Self, VideoError> {
        Self::open_with(path, fps, true, "ffprobe", "ffmpeg")
    }

    pub(super) fn open_with(
        path: &Path,
        expected_fps: f64,
        retime: bool,
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
        let mut times_s = times_s;
        let container_fps = check_times(path, &times_s, expected_fps, stream.time_base_s, retime)?;
        check_complete(
            path,
            &times_s,
            container_fps.unwrap_or(expected_fps),
            &stream,
        )?;
        if let Some(r) = container_fps {
            // retimed: frame i was captured i / expected_fps after the first
            for t in &mut times_s {
                *t *= r / expected_fps;
            }
        }
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
        let mut child = spawn_reader(
            Command::new(ffmpeg)
                .args(["-nostdin", "-v", "warning", "-xerror", "-noautorotate"])
                .args(["-err_detect", "explode", "-i"])
                .arg(file_arg(path))
                .args(["-map", "0:v:0", "-vsync", "passthrough", "-f", "rawvideo"])
                .args(["-pix_fmt", &out_fmt, "-"]),
            ffmpeg,
            path,
        )?;
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
                container_fps,
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
        let eight = self.info.bits == 8;
        if eight != matches!(frame, GreyFrame::U8 { .. }) {
            let (width, height) = (w, h);
            *frame = if eight {
                GreyFrame::U8 {
                    width,
                    height,
                    data: Vec::new(),
                }
            } else {
                GreyFrame::U16 {
                    width,
                    height,
                    data: Vec::new(),
                }
            };
        }
        match frame {
            GreyFrame::U8 {
                width,
                height,
                data,
            } => {
                (*width, *height) = (w, h);
                self.next_frame_u8(data)
            }
            GreyFrame::U16 {
                width,
                height,
                data,
            } => {
                (*width, *height) = (w, h);
                self.next_frame_u16(data)
            }
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
            .filter(|l| !BENIGN.iter().any(|b| l.contains(b)))
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

//! [`WelchH1`]: the streaming estimator, an accumulator with its own segment and transform
//! buffers, fed by chunks of any length.

#[cfg(doc)]
use super::scratch_capacity;
use super::{ConfigError, WelchAccumulator, WelchConfig, WelchError};
use crate::Complex32;
use core::fmt;

/// Streaming Welch H1 estimator with capacities `SEG` (samples per segment), `NFFT` (transform
/// length) and `SCRATCH` (DFT scratch values, see [`scratch_capacity`]): a
/// [`WelchAccumulator`] plus the two segment buffers, the transform buffer and the scratch.
///
/// Build it with [`try_new`](Self::try_new), feed it with [`push`](Self::push), read the
/// estimate from its [`accumulator`](Self::accumulator) ([`WelchAccumulator::h1`],
/// [`coherence`](WelchAccumulator::coherence), [`freq`](WelchAccumulator::freq) or the slice
/// fillers). [`reset`](Self::reset) starts a new estimate with the same settings and
/// [`configure`](Self::configure) with new ones, so one (boxed or static) instance can serve
/// many records without being moved again.
#[derive(Clone)]
pub struct WelchH1<const SEG: usize, const NFFT: usize, const SCRATCH: usize> {
    acc: WelchAccumulator<NFFT>,
    xseg: [f32; SEG],
    yseg: [f32; SEG],
    /// Samples currently held in `xseg`/`yseg`.
    fill: usize,
    work: [Complex32; NFFT],
    scratch: [Complex32; SCRATCH],
}

/// Shows the settings and counters, not the buffers (tens of thousands of values).
impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> fmt::Debug
    for WelchH1<SEG, NFFT, SCRATCH>
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("WelchH1")
            .field("capacities", &(SEG, NFFT, SCRATCH))
            .field("config", &self.acc.config)
            .field("segments", &self.acc.segments)
            .field("skipped", &self.acc.skipped)
            .field("pending", &self.fill)
            .finish_non_exhaustive()
    }
}

/// Logs the settings and counters, not the buffers.
#[cfg(feature = "defmt")]
impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> defmt::Format
    for WelchH1<SEG, NFFT, SCRATCH>
{
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "WelchH1 {{ config: {}, segments: {}, skipped: {}, pending: {} }}",
            self.acc.config,
            self.acc.segments,
            self.acc.skipped,
            self.fill
        )
    }
}

impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> WelchH1<SEG, NFFT, SCRATCH> {
    /// An unconfigured estimator ([`push`](Self::push) refuses with
    /// [`WelchError::NotConfigured`]) to build in place in a `static` (all zero bytes:
    /// `.bss`, no stack copy), then [`configure`](Self::configure).
    pub const fn new() -> Self {
        WelchH1 {
            acc: WelchAccumulator::new(),
            xseg: [0.0; SEG],
            yseg: [0.0; SEG],
            fill: 0,
            work: [Complex32::new(0.0, 0.0); NFFT],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
        }
    }

    /// Checks `config` against the capacities and builds an empty estimator.
    ///
    /// Errors: [`ConfigError::SampleRate`], [`ConfigError::SegmentLength`],
    /// [`ConfigError::Overlap`], [`ConfigError::FftLength`], [`ConfigError::Dft`],
    /// [`ConfigError::Scratch`]. `const`: a `static` initialiser builds it in place, checked
    /// at compile time.
    pub const fn try_new(config: WelchConfig) -> Result<Self, ConfigError> {
        if let Err(e) = Self::check(&config) {
            return Err(e);
        }
        let acc = const_try!(WelchAccumulator::try_new(config));
        Ok(WelchH1 {
            acc,
            xseg: [0.0; SEG],
            yseg: [0.0; SEG],
            fill: 0,
            work: [Complex32::new(0.0, 0.0); NFFT],
            scratch: [Complex32::new(0.0, 0.0); SCRATCH],
        })
    }

    /// Replaces the settings (checked as in [`try_new`](Self::try_new)) and clears the
    /// estimate. On error the estimator is left unchanged.
    pub fn configure(&mut self, config: WelchConfig) -> Result<(), ConfigError> {
        Self::check(&config)?;
        self.acc.configure(config)?;
        self.fill = 0;
        Ok(())
    }

    /// Forgets all pushed samples and accumulated segments; keeps the settings.
    pub fn reset(&mut self) {
        self.fill = 0;
        self.acc.reset();
    }

    /// [`WelchAccumulator::try_new`]'s checks plus the segment and scratch capacities, in the
    /// order the errors are documented.
    const fn check(c: &WelchConfig) -> Result<(), ConfigError> {
        if !(c.fs_hz.is_finite() && c.fs_hz > 0.0) {
            return Err(ConfigError::SampleRate);
        }
        if c.nperseg == 0 || c.nperseg > SEG {
            return Err(ConfigError::SegmentLength {
                nperseg: c.nperseg,
                capacity: SEG,
            });
        }
        let dft = const_try!(WelchAccumulator::<NFFT>::check(c));
        if dft.scratch_len() > SCRATCH {
            return Err(ConfigError::Scratch {
                needed: dft.scratch_len(),
                capacity: SCRATCH,
            });
        }
        Ok(())
    }

    /// The accumulated estimate (settings, spectra, counters).
    pub const fn accumulator(&self) -> &WelchAccumulator<NFFT> {
        &self.acc
    }

    /// Samples waiting in the segment buffer (always `< nperseg`).
    pub const fn pending(&self) -> usize {
        self.fill
    }

    /// Pushes a chunk of samples of both channels (`x[i]` and `y[i]` taken at the same time).
    /// Every time `nperseg` samples are buffered a segment is transformed and accumulated, and
    /// the last `noverlap` samples are kept for the next one. The result does not depend on how
    /// the record is cut into chunks: pushing it sample by sample, in random chunks or at once
    /// gives bit-identical spectra.
    ///
    /// Errors (nothing is consumed): [`WelchError::ChunkLengths`] if `x.len() != y.len()`,
    /// [`WelchError::NotConfigured`] before the settings are set.
    pub fn push(&mut self, x: &[f32], y: &[f32]) -> Result<(), WelchError> {
        if !self.acc.is_configured() {
            return Err(WelchError::NotConfigured);
        }
        if x.len() != y.len() {
            return Err(WelchError::ChunkLengths {
                x: x.len(),
                y: y.len(),
            });
        }
        let nperseg = self.acc.config.nperseg;
        let (mut x, mut y) = (x, y);
        while !x.is_empty() {
            let room = nperseg.saturating_sub(self.fill);
            let take = room.min(x.len());
            let (xh, xt) = x.split_at(take);
            let (yh, yt) = y.split_at(take.min(y.len()));
            if let (Some(xd), Some(yd)) = (
                self.xseg.get_mut(self.fill..self.fill + take),
                self.yseg.get_mut(self.fill..self.fill + take),
            ) {
                // element loops: no length-mismatch panic path (the lengths are equal)
                for (d, v) in xd.iter_mut().zip(xh) {
                    *d = *v;
                }
                for (d, v) in yd.iter_mut().zip(yh) {
                    *d = *v;
                }
            }
            self.fill += take;
            (x, y) = (xt, yt);
            if self.fill >= nperseg {
                if let (Some(xs), Some(ys)) =
                    (self.xseg.get_mut(..nperseg), self.yseg.get_mut(..nperseg))
                {
                    // the capacities were checked by try_new: no error case is left (a skipped,
                    // non-finite segment is counted by the accumulator)
                    self.acc
                        .accumulate(xs, ys, &mut self.work, &mut self.scratch);
                    let step = nperseg - self.acc.config.noverlap;
                    if step <= xs.len() && step <= ys.len() {
                        xs.copy_within(step.., 0);
                        ys.copy_within(step.., 0);
                    }
                }
                self.fill = self.acc.config.noverlap;
            }
            if take == 0 && self.fill < nperseg {
                // unreachable with a valid configuration; guarantees termination regardless
                break;
            }
        }
        Ok(())
    }
}

impl<const SEG: usize, const NFFT: usize, const SCRATCH: usize> Default
    for WelchH1<SEG, NFFT, SCRATCH>
{
    fn default() -> Self {
        Self::new()
    }
}

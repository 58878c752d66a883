//! Camera / ADC synchronisation from one time base (method.md §2.7).
//!
//! Camera triggers and ADC conversions are both derived from one fast tick. The tick rate is the
//! least common multiple of the two rates: for 2048 Hz and 120 fps it is 30 720 Hz, with one ADC
//! conversion every 15 ticks and one camera trigger every 256 ticks. [`SyncPlan::try_new`]
//! computes it and rejects pairs whose common tick exceeds the timer's range. [`SyncDriver`]
//! drives the camera trigger line (an `embedded-hal` 1.0 [`OutputPin`], high for the exposure,
//! so the exposure is the pulse width) from a free-running tick counter ([`TickSource`], the
//! small trait this crate defines because embedded-hal 1.0 has no timer trait), and reports
//! every frame trigger and every ADC conversion instant with its tick, so the host can align
//! both streams exactly: frame `i` starts its exposure at tick `i * camera_div`, sample `j` is
//! taken at tick `j * adc_div`, and the exposure centre is `exposure_ticks / 2` after the
//! trigger.
//!
//! ```
//! use firmware_core::sync::{SyncConfig, SyncPlan};
//! // 2048 Hz ADC, 120 fps camera, a timer up to 1 MHz, 2 ms exposure
//! let config = SyncConfig::new(2048, 120, 1_000_000);
//! let plan = SyncPlan::try_new(config.with_exposure_ticks(SyncPlan::ticks_for(2e-3, 30_720)))
//!     .unwrap();
//! assert_eq!((plan.tick_hz(), plan.adc_div(), plan.camera_div()), (30_720, 15, 256));
//! assert_eq!(plan.exposure_ticks(), 61);
//! ```

use embedded_hal::digital::OutputPin;

/// Why a synchronisation plan is impossible (a [`SyncConfig`] rejected once, by
/// [`SyncPlan::try_new`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ConfigError {
    /// A rate is zero.
    ZeroRate,
    /// The least common multiple of the two rates exceeds the timer's maximum tick rate.
    NoCommonTick {
        /// The common tick rate that would be needed, Hz (saturated at `u64::MAX`).
        needed_hz: u64,
        /// The timer's maximum tick rate, Hz.
        max_hz: u32,
    },
    /// The exposure is zero or not shorter than the frame period (in ticks).
    Exposure {
        /// Requested exposure, ticks.
        exposure_ticks: u32,
        /// Frame period, ticks.
        frame_ticks: u32,
    },
}

error_display!(ConfigError, f, {
    ConfigError::ZeroRate => write!(f, "ADC and camera rates must be non-zero"),
    ConfigError::NoCommonTick { needed_hz, max_hz } => write!(
        f,
        "the rates need a common tick of {needed_hz} Hz, above the timer's {max_hz} Hz"
    ),
    ConfigError::Exposure {
        exposure_ticks,
        frame_ticks,
    } => write!(
        f,
        "exposure of {exposure_ticks} ticks must be at least 1 and shorter than the frame period of {frame_ticks} ticks"
    ),
});

/// Settings of a [`SyncPlan`]: rates in integer Hz and the exposure in ticks of the common
/// time base. Plain data; checked once by [`SyncPlan::try_new`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SyncConfig {
    /// ADC conversion rate, Hz, >= 1.
    pub adc_hz: u32,
    /// Camera trigger (frame) rate, Hz, >= 1.
    pub camera_hz: u32,
    /// Fastest tick rate the timer can count at, Hz: the least common multiple of the two
    /// rates must not exceed it.
    pub timer_max_hz: u32,
    /// Exposure (trigger pulse width), ticks of the common time base, `1 ..= frame period - 1`
    /// (see [`SyncPlan::ticks_for`] to convert seconds).
    pub exposure_ticks: u32,
}

impl SyncConfig {
    /// ADC at `adc_hz`, camera at `camera_hz`, on a timer of at most `timer_max_hz`, with the
    /// shortest exposure (one tick); set [`exposure_ticks`](Self::exposure_ticks) after.
    pub const fn new(adc_hz: u32, camera_hz: u32, timer_max_hz: u32) -> Self {
        SyncConfig {
            adc_hz,
            camera_hz,
            timer_max_hz,
            exposure_ticks: 1,
        }
    }

    /// The same with an exposure of `exposure_ticks` ticks.
    #[must_use]
    pub const fn with_exposure_ticks(self, exposure_ticks: u32) -> Self {
        SyncConfig {
            exposure_ticks,
            ..self
        }
    }
}

/// Tick rate and dividers for one ADC rate and one camera rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SyncPlan {
    tick_hz: u32,
    adc_div: u32,
    camera_div: u32,
    exposure_ticks: u32,
}

const fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

impl SyncPlan {
    /// Plans ADC conversions at `adc_hz` and camera triggers at `camera_hz` (both integer Hz)
    /// on a timer that ticks at most at `timer_max_hz`, with an exposure (trigger pulse width)
    /// of `exposure_ticks` ticks of the common time base (`1 ..= frame period - 1`).
    pub const fn try_new(config: SyncConfig) -> Result<Self, ConfigError> {
        let SyncConfig {
            adc_hz,
            camera_hz,
            timer_max_hz,
            exposure_ticks,
        } = config;
        if adc_hz == 0 || camera_hz == 0 {
            return Err(ConfigError::ZeroRate);
        }
        let g = gcd(adc_hz as u64, camera_hz as u64);
        let lcm = adc_hz as u64 / g * camera_hz as u64;
        if lcm > timer_max_hz as u64 {
            return Err(ConfigError::NoCommonTick {
                needed_hz: lcm,
                max_hz: timer_max_hz,
            });
        }
        let tick_hz = lcm as u32;
        let camera_div = tick_hz / camera_hz;
        if exposure_ticks == 0 || exposure_ticks >= camera_div {
            return Err(ConfigError::Exposure {
                exposure_ticks,
                frame_ticks: camera_div,
            });
        }
        Ok(SyncPlan {
            tick_hz,
            adc_div: tick_hz / adc_hz,
            camera_div,
            exposure_ticks,
        })
    }

    /// Common tick rate, Hz.
    pub const fn tick_hz(&self) -> u32 {
        self.tick_hz
    }
    /// Ticks between ADC conversions.
    pub const fn adc_div(&self) -> u32 {
        self.adc_div
    }
    /// Ticks between camera triggers.
    pub const fn camera_div(&self) -> u32 {
        self.camera_div
    }
    /// Exposure (trigger pulse width), ticks.
    pub const fn exposure_ticks(&self) -> u32 {
        self.exposure_ticks
    }
    /// Exposure ticks closest to `exposure_s` seconds at the tick rate `tick_hz`.
    pub fn ticks_for(exposure_s: f32, tick_hz: u32) -> u32 {
        let t = libm::roundf(exposure_s * tick_hz as f32);
        if t.is_finite() && t > 0.0 {
            t as u32
        } else {
            0
        }
    }
}

/// A free-running tick counter of the common time base (a hardware timer's count register).
/// It may wrap at `u32::MAX`; the driver extends it to 64 bits, provided it is polled at least
/// once per wrap.
pub trait TickSource {
    /// Current tick count.
    fn now(&mut self) -> u32;
}

/// What happened at a tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// Frame `index` was triggered (start of its exposure) at `tick`.
    Frame {
        /// Frame number, from 0.
        index: u64,
        /// Tick of the trigger (exposure start).
        tick: u64,
    },
    /// ADC conversion `index` happened at `tick`.
    Sample {
        /// Sample number, from 0.
        index: u64,
        /// Tick of the conversion.
        tick: u64,
    },
}

/// Drives the camera trigger pin from a [`TickSource`] following a [`SyncPlan`], and reports
/// frame and sample instants. Tick 0 (the first `poll`'s reading is taken as tick 0) starts
/// frame 0 and sample 0.
#[derive(Debug)]
pub struct SyncDriver<P, T> {
    pin: P,
    ticks: T,
    plan: SyncPlan,
    origin: Option<u32>,
    last_raw: u32,
    high_word: u64,
    /// Next tick not yet processed.
    next: u64,
    pin_high: bool,
}

impl<P: OutputPin, T: TickSource> SyncDriver<P, T> {
    /// Takes the trigger pin and the tick source.
    pub fn new(pin: P, ticks: T, plan: SyncPlan) -> Self {
        SyncDriver {
            pin,
            ticks,
            plan,
            origin: None,
            last_raw: 0,
            high_word: 0,
            next: 0,
            pin_high: false,
        }
    }

    /// Hands the peripherals back.
    pub fn release(self) -> (P, T) {
        (self.pin, self.ticks)
    }

    /// The plan.
    pub fn plan(&self) -> &SyncPlan {
        &self.plan
    }

    /// Reads the tick source, processes every tick since the last call in order (trigger
    /// edges, frame and sample events handed to `on_event`), and returns the current tick.
    /// Call it at least once per exposure for exact pulse edges.
    pub fn poll(&mut self, mut on_event: impl FnMut(Event)) -> Result<u64, P::Error> {
        let raw = self.ticks.now();
        let origin = *self.origin.get_or_insert(raw);
        if raw < self.last_raw {
            self.high_word += 1 << 32;
        }
        self.last_raw = raw;
        let now = (self.high_word | raw as u64).wrapping_sub(origin as u64);
        let (cam, adc, exp) = (
            self.plan.camera_div as u64,
            self.plan.adc_div as u64,
            self.plan.exposure_ticks as u64,
        );
        while self.next <= now {
            // jump to the next tick where something happens
            let t = self.next;
            let phase = t % cam;
            if phase == 0 {
                if !self.pin_high {
                    self.pin.set_high()?;
                    self.pin_high = true;
                }
                on_event(Event::Frame {
                    index: t / cam,
                    tick: t,
                });
            }
            if phase >= exp && self.pin_high {
                self.pin.set_low()?;
                self.pin_high = false;
            }
            if t % adc == 0 {
                on_event(Event::Sample {
                    index: t / adc,
                    tick: t,
                });
            }
            // next interesting tick: next ADC multiple, end of exposure, or next frame
            let next_adc = (t / adc + 1) * adc;
            let next_cam = (t / cam + 1) * cam;
            let exp_end = t - phase + exp;
            let mut n = next_adc.min(next_cam);
            if exp_end > t {
                n = n.min(exp_end);
            }
            self.next = n;
        }
        Ok(now)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal_mock::eh1::digital::{Mock, State, Transaction};
    use std::vec::Vec;

    /// A tick source that advances by `step` per reading.
    struct Steps {
        t: u32,
        step: u32,
    }
    impl TickSource for Steps {
        fn now(&mut self) -> u32 {
            let t = self.t;
            self.t = self.t.wrapping_add(self.step);
            t
        }
    }

    #[test]
    fn paper_rates_give_30720_hz_with_dividers_15_and_256() {
        let exp = SyncPlan::ticks_for(0.002, 30_720);
        assert_eq!(exp, 61);
        let p = SyncPlan::try_new(SyncConfig::new(2048, 120, 100_000_000).with_exposure_ticks(exp))
            .unwrap();
        assert_eq!(
            (p.tick_hz(), p.adc_div(), p.camera_div()),
            (30_720, 15, 256)
        );
    }

    #[test]
    fn impossible_pairs_are_rejected() {
        assert_eq!(
            SyncPlan::try_new(SyncConfig::new(0, 120, 1_000_000).with_exposure_ticks(1)),
            Err(ConfigError::ZeroRate)
        );
        // coprime large rates: lcm = 999_983 * 1_000_003 > u32
        assert!(matches!(
            SyncPlan::try_new(SyncConfig::new(999_983, 1_000_003, u32::MAX).with_exposure_ticks(1)),
            Err(ConfigError::NoCommonTick { .. })
        ));
        assert!(matches!(
            SyncPlan::try_new(SyncConfig::new(2048, 120, 20_000).with_exposure_ticks(1)),
            Err(ConfigError::NoCommonTick {
                needed_hz: 30_720,
                max_hz: 20_000
            })
        ));
        assert!(matches!(
            SyncPlan::try_new(SyncConfig::new(2048, 120, 100_000).with_exposure_ticks(256)),
            Err(ConfigError::Exposure { .. })
        ));
    }

    #[test]
    fn trigger_pulses_and_stamps_for_the_first_two_frames() {
        let plan =
            SyncPlan::try_new(SyncConfig::new(2048, 120, 100_000).with_exposure_ticks(61)).unwrap();
        let pin = Mock::new(&[
            Transaction::set(State::High),
            Transaction::set(State::Low),
            Transaction::set(State::High),
            Transaction::set(State::Low),
        ]);
        // poll every tick for two frames (512 ticks)
        let mut d = SyncDriver::new(pin, Steps { t: 1000, step: 1 }, plan);
        let mut events = Vec::new();
        for _ in 0..512 {
            d.poll(|e| events.push(e)).unwrap();
        }
        let (frames, samples): (Vec<Event>, Vec<Event>) = events
            .iter()
            .copied()
            .partition(|e| matches!(e, Event::Frame { .. }));
        let ticks = |events: Vec<Event>| -> Vec<u64> {
            events
                .into_iter()
                .map(|e| match e {
                    Event::Frame { tick, .. } | Event::Sample { tick, .. } => tick,
                })
                .collect()
        };
        let (frames, samples) = (ticks(frames), ticks(samples));
        assert_eq!(frames, [0, 256]);
        assert_eq!(samples.len(), 511 / 15 + 1);
        assert!(samples.iter().enumerate().all(|(i, t)| *t == 15 * i as u64));
        let (mut pin, _) = d.release();
        pin.done();
    }

    #[test]
    fn pin_errors_are_propagated_and_the_edge_is_retried() {
        use embedded_hal_mock::eh1::MockError;
        use std::io::ErrorKind;
        let plan =
            SyncPlan::try_new(SyncConfig::new(2048, 120, 100_000).with_exposure_ticks(61)).unwrap();
        let pin = Mock::new(&[
            Transaction::set(State::High).with_error(MockError::Io(ErrorKind::NotConnected)),
            Transaction::set(State::High),
        ]);
        let mut d = SyncDriver::new(pin, Steps { t: 0, step: 1 }, plan);
        let mut events = Vec::new();
        assert_eq!(
            d.poll(|e| events.push(e)),
            Err(MockError::Io(ErrorKind::NotConnected))
        );
        // nothing was reported for the tick whose edge failed
        assert!(events.is_empty());
        assert_eq!(d.poll(|e| events.push(e)), Ok(1));
        assert_eq!(
            events,
            [
                Event::Frame { index: 0, tick: 0 },
                Event::Sample { index: 0, tick: 0 }
            ]
        );
        let (mut pin, _) = d.release();
        pin.done();
    }

    /// Records (tick, level) for every pin write; shares the tick with [`SharedTicks`].
    struct EdgePin {
        now: std::rc::Rc<core::cell::Cell<u32>>,
        edges: Vec<(u32, bool)>,
    }
    impl embedded_hal::digital::ErrorType for EdgePin {
        type Error = core::convert::Infallible;
    }
    impl OutputPin for EdgePin {
        fn set_low(&mut self) -> Result<(), Self::Error> {
            self.edges.push((self.now.get(), false));
            Ok(())
        }
        fn set_high(&mut self) -> Result<(), Self::Error> {
            self.edges.push((self.now.get(), true));
            Ok(())
        }
    }
    struct SharedTicks(std::rc::Rc<core::cell::Cell<u32>>);
    impl TickSource for SharedTicks {
        fn now(&mut self) -> u32 {
            self.0.get()
        }
    }

    #[test]
    fn pulse_edges_fall_on_the_exact_ticks_when_polled_every_tick() {
        // 2048 Hz / 120 fps, 2 ms exposure = 61 ticks: rising edges at 256 k, falling at 256 k + 61
        let plan =
            SyncPlan::try_new(SyncConfig::new(2048, 120, 100_000).with_exposure_ticks(61)).unwrap();
        let now = std::rc::Rc::new(core::cell::Cell::new(0u32));
        let pin = EdgePin {
            now: now.clone(),
            edges: Vec::new(),
        };
        let mut d = SyncDriver::new(pin, SharedTicks(now.clone()), plan);
        for t in 0..(5 * 256) {
            now.set(t);
            d.poll(|_| {}).unwrap();
        }
        let (pin, _) = d.release();
        let want: Vec<(u32, bool)> = (0..5u32)
            .flat_map(|k| [(256 * k, true), (256 * k + 61, false)])
            .collect();
        assert_eq!(pin.edges, want);
    }

    proptest::proptest! {
        #[test]
        fn counts_follow_the_rates_whatever_the_polling(
            adc in 1u32..5000, cam in 1u32..500, step in 1u32..700, polls in 1usize..400,
        ) {
            let Ok(plan) = SyncPlan::try_new(SyncConfig::new(adc, cam, 10_000_000).with_exposure_ticks(1)) else {
                return Ok(());
            };
            let mut d = SyncDriver::new(AnyPin, Steps { t: u32::MAX - 1000, step }, plan);
            let (mut frames, mut samples, mut last) = (0u64, 0u64, None::<u64>);
            let mut now = 0;
            for _ in 0..polls {
                now = d.poll(|e| {
                    let t = match e {
                        Event::Frame { index, tick } => { assert_eq!(index, frames); frames += 1; tick }
                        Event::Sample { index, tick } => { assert_eq!(index, samples); samples += 1; tick }
                    };
                    assert!(last.is_none_or(|l| t >= l));
                    last = Some(t);
                }).unwrap();
            }
            proptest::prop_assert_eq!(frames, now / plan.camera_div() as u64 + 1);
            proptest::prop_assert_eq!(samples, now / plan.adc_div() as u64 + 1);
        }
    }

    /// A pin that accepts everything (for the property test).
    struct AnyPin;
    impl embedded_hal::digital::ErrorType for AnyPin {
        type Error = core::convert::Infallible;
    }
    impl OutputPin for AnyPin {
        fn set_low(&mut self) -> Result<(), Self::Error> {
            Ok(())
        }
        fn set_high(&mut self) -> Result<(), Self::Error> {
            Ok(())
        }
    }
}

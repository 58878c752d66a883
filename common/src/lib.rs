//! What every layer of the host side shares, above the readers and below everything that
//! computes a measurement: nothing here knows of frames, models, analyses or outputs.
//!
//! | module | what |
//! |---|---|
//! | [`stats`] | means, standard deviations, percentiles, histograms |
//! | [`uncertainty`] | JCGM 101: coverage intervals, standard uncertainty of the mean, the adaptive Monte Carlo procedure |
//! | [`setting`] | errors naming the user's settings (`--gate-px` or `gate_px`), the rules several jobs share |
//! | [`lost_frames`] | the one policy for a frame without a position, and the 5 % rule |
//! | [`geometry`] | homographies: fitted to point pairs (translation, similarity, normalised DLT), a plane seen obliquely |
//! | [`testing`] | seeded noise for tests, examples and benchmarks |
//! | [`evidence`] | what supports a tracked position (score, forward-backward, the check that took it away) |
//! | [`failpoint`] | `VIBCAM_FAILPOINT`: abort at a named point, for crash tests |

pub mod evidence;
pub mod failpoint;
pub mod geometry;
pub mod lost_frames;
pub mod setting;
pub mod stats;
pub mod testing;
pub mod uncertainty;

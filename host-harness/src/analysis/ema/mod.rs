//! Experimental modal analysis of recordings: the identification itself is
//! `vibcam_identify::ema` (re-exported here under the same paths); here, what the `ema`
//! command adds to it: the responses and the force read and brought to one rate and start
//! ([`input`]), and the job as one call ([`run`]).

pub use vibcam_identify::ema::*;

pub mod input;
pub mod run;

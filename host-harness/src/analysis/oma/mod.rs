//! Output-only modal analysis of recordings: the identification itself is `vibcam_identify::oma`
//! (re-exported here under the same paths); here, what the `modal` command and `analyze` without an
//! accelerometer add to it: the displacement files read ([`input`]), the frames tracked first
//! ([`frames`]), each mode magnified into a video ([`magnified`]), the job as one call ([`run`]), and over several setups ([`multi_setup`]).

pub use vibcam_identify::oma::*;

pub mod frames;
pub mod input;
pub mod magnified;
pub mod multi_setup;
pub mod run;

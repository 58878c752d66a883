//! The simulated measurement: the camera (EPSA renderer, image effects, the firmware's
//! centroid and trackers), the Monte Carlo studies that push simulated frames and signals
//! through firmware-core, the synthetic recordings written from a model through the camera, the
//! exposure planner and the calibration of unreported imaging knobs.
//!
//! | module | what |
//! |---|---|
//! | [`imaging`] | the camera: targets, the EPSA renderer (and its fast binary-centroid path), image-formation effects, the `Camera` that ends in firmware-core's centroid, the exposure transfer of the centroid (compensation tables) |
//! | [`study`] | Monte Carlo studies: configuration, scenarios, runner (seeds, threads, shards), checkpoint, aggregation, merge |
//! | [`recording`] | synthetic recordings (frames + transducer CSV) written from a model through the camera |
//! | [`plan`] | the exposure planner: per mode, the longest exposure meeting a tolerance, the compensated residual, the lost-frame risk |
//! | [`calibrate`] | fitting unreported imaging knobs to observed figures (common random numbers) |

pub mod calibrate;
pub mod imaging;
pub mod plan;
pub mod recording;
pub mod study;

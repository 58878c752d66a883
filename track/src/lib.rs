//! Tracking real recordings: where each target is in each frame, and what the camera's own
//! motion and the scene's scale make of it. Knows nothing of spectra, modes or outputs.
//!
//! - [`tracks`]: what every tracker returns ([`tracks::Tracks`]), and the K blobs of the whole
//!   frame followed with a gate and each target's history;
//! - [`region`]: points from a region of the first frame (a polygon, a line, a brush's
//!   strokes) on a grid, kept where their texture fixes the motion (Shi-Tomasi, or one
//!   direction's gradient energy);
//! - [`points`]: chosen points, a window each: firmware-core's centroid at the window's
//!   threshold (Otsu) or its Lucas-Kanade tracker; groups from the file or found from the first
//!   frames' motion; look-alikes named;
//! - [`choose`]: `--tracker auto`, per target the blob centroid where a threshold separates
//!   it, Lucas-Kanade otherwise, with the reason;
//! - [`shared_motion`]: a group's shared offset (block templates, integral images);
//! - [`follow`]: the one tracking dispatcher ([`follow::Targets`]: the whole frame, K blobs or
//!   chosen points);
//! - [`verify`]: each position's evidence (score, forward-backward) and the record's checks
//!   (the target's own score, its group's geometry) that take away what it does not support;
//! - [`camera_motion`]: the camera's motion per frame from static references, by consensus;
//! - [`view`]: the targets tracked, the camera's motion removed, the scale from the scene (one,
//!   between two points, each target's size, the plane's homography);
//! - [`magnify`]: a mode's motion at the points spread over the image and applied, magnified,
//!   to the reference frame (the frames of a motion-magnification video).

pub mod camera_motion;
pub mod choose;
pub mod follow;
pub mod magnify;
pub mod points;
pub mod region;
pub mod shared_motion;
pub mod tracks;
pub mod verify;
pub mod view;

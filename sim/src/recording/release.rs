//! A structure pulled and released in front of a white brick wall (`render --recording DIR
//! --scene cluttered --motion release`), as a user films a quick test with an ordinary camera:
//! a model of four storeys, seven small white tags with a black dot on each (all alike), the
//! tags barely brighter than the wall, filmed in colour at 23 fps with a 2 ms exposure. The
//! top is pulled slowly sideways by 150 px and let go twice; the free vibration (3.6 Hz, 10 %
//! damping) moves the top storey by up to about 120 px between frames, the tags being 150-170
//! px apart, with a few pixels of blur. Storey `s` (0 at the top) moves `(4 - s) / 4` of the
//! top's sway and a twentieth of it vertically.
//!
//! Each frame is the exposure's average of [`SUBSAMPLES`] images at instants spread evenly over
//! it, each drawn with box-filtered (anti-aliased) edges, over the wall. `truth.csv` gives each
//! tag's centre averaged over the same instants; `points.csv` a [`WINDOW`]-px window per tag
//! and its storey as the `group` (targets that move together).

use super::cluttered::write_jpeg;
use anyhow::Context as _;
use image::{Rgb, RgbImage};
use std::path::Path;

/// Frame rate, Hz.
pub const FPS: f64 = 23.0;
/// Exposure, ms.
pub const EXPOSURE_MS: f64 = 2.0;
/// Frame size, px.
pub const SIZE: (usize, usize) = (1280, 720);
/// Storeys and tags per storey.
pub const STOREYS: usize = 4;
/// Tags per storey.
pub const PER_STOREY: usize = 7;
/// The window per tag in points.csv, px: the tag (22 px) and a pixel and a half of wall
/// around it. A window that is mostly wall matches the wall where the tag was after a jump
/// (the wall does not move): brightness constancy holds for the tag only.
pub const WINDOW: usize = 25;
/// Images averaged over each exposure.
pub const SUBSAMPLES: usize = 8;
/// Length of the record, s.
const DURATION_S: f64 = 8.0;
/// The top's pull, px.
const PULL_PX: f64 = 150.0;
/// Half-side of a tag, radius of its dot, px.
const TAG_HALF: f64 = 11.0;
const DOT_R: f64 = 4.0;

/// The top storey's sway at `t` s, px: at rest, pulled over 1.5 s, released (free decay) at
/// 2 s; pulled again from 4.5 s and released at 6 s.
fn sway(t: f64) -> f64 {
    let w = std::f64::consts::TAU * 3.6;
    let zeta = 0.1;
    let cycle = |t: f64| -> f64 {
        if t < 0.5 {
            0.0
        } else if t < 2.0 {
            PULL_PX * 0.5 * (1.0 - (std::f64::consts::PI * (t - 0.5) / 1.5).cos())
        } else {
            let u = t - 2.0;
            PULL_PX * (-zeta * w * u).exp() * (w * (1.0 - zeta * zeta).sqrt() * u).cos()
        }
    };
    // the second pull starts from what is left of the first decay (under 1 px)
    if t < 4.5 {
        cycle(t)
    } else {
        cycle(t) + cycle(t - 4.0)
    }
}

/// Storey `s`'s displacement at `t`, px (right, down).
fn storey_disp(s: usize, t: f64) -> (f64, f64) {
    let a = (STOREYS - s) as f64 / STOREYS as f64 * sway(t);
    (a, a / 20.0)
}

/// The tags' rest centres, storey by storey (top first), px: spaced 150-170 px, irregularly.
pub fn tag_centres() -> Vec<(f64, f64)> {
    const GAPS: [f64; 6] = [158.0, 151.0, 167.0, 154.0, 170.0, 162.0];
    let mut v = Vec::with_capacity(STOREYS * PER_STOREY);
    for s in 0..STOREYS {
        let y = 130.0 + 150.0 * s as f64;
        let mut x = 130.0 + 9.0 * s as f64;
        for i in 0..PER_STOREY {
            v.push((x, y));
            if i < GAPS.len() {
                x += GAPS[(i + s) % GAPS.len()];
            }
        }
    }
    v
}

/// Fraction of the pixel `[x - 1/2, x + 1/2]` inside `[lo, hi]` (box filter, 1-D).
fn cover(x: f64, lo: f64, hi: f64) -> f64 {
    ((x + 0.5).min(hi) - (x - 0.5).max(lo)).clamp(0.0, 1.0)
}

/// The wall: white bricks (60 x 24 px, running bond) with darker mortar and a fine grain.
fn wall(w: usize, h: usize) -> Vec<[f32; 3]> {
    let mut v = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let row = y / 24;
            let xs = x + if row % 2 == 1 { 30 } else { 0 };
            let mortar = y % 24 < 2 || xs % 60 < 2;
            // a fixed pseudo-random grain and a per-brick shade
            let hash = |a: usize, b: usize| {
                let mut z = (a as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (b as u64);
                z = (z ^ (z >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                ((z >> 40) as f64 / (1u64 << 24) as f64) - 0.5
            };
            let level = if mortar {
                196.0
            } else {
                222.0 + 8.0 * hash(xs / 60 + 1000, row) + 6.0 * hash(x, y)
            };
            v.push([level as f32, (level * 0.96) as f32, (level * 0.9) as f32]);
        }
    }
    v
}

/// Writes the recording into `write_to` (named `dir` in its texts): `frames/frame_NNNNN.jpg`,
/// `points.csv`, `truth.csv` and `README.txt`, with `video` also the colour frames losslessly
/// in `frames.mkv` (RGB FFV1, before the JPEG compression). Returns the frame count.
pub fn write_release_recording(
    (write_to, dir): (&Path, &Path),
    video: bool,
) -> anyhow::Result<usize> {
    let (w, h) = SIZE;
    let mut mkv = if video {
        Some(
            vibcam_readers::frames::video::Ffv1Writer::create(
                &write_to.join("frames.mkv"),
                w,
                h,
                FPS,
                vibcam_readers::frames::video::Pixels::Rgb8,
            )
            .map_err(|e| e.into_anyhow())?,
        )
    } else {
        None
    };
    let frames_dir = write_to.join("frames");
    std::fs::create_dir_all(&frames_dir)
        .with_context(|| format!("cannot create {}", dir.join("frames").display()))?;
    let back = wall(w, h);
    let centres = tag_centres();
    let n = (DURATION_S * FPS).round() as usize;
    let mut truth = String::from("frame,target,x_px,y_px\n");
    let mut img = vec![[0f32; 3]; w * h];
    for k in 0..n {
        render_frame(k, (&back, &centres), &mut img, &mut truth);
        let mut rgb = RgbImage::new(w as u32, h as u32);
        for (p, v) in rgb.pixels_mut().zip(&img) {
            *p = Rgb(v.map(|c| (c + 0.5).clamp(0.0, 255.0) as u8));
        }
        write_jpeg(&rgb, &frames_dir.join(format!("frame_{k:05}.jpg")))?;
        if let Some(v) = &mut mkv {
            v.write_frame_rgb(rgb.as_raw())
                .map_err(|e| e.into_anyhow())?;
        }
    }
    if let Some(v) = mkv {
        v.finish().map_err(|e| e.into_anyhow())?;
    }
    let mut points = String::from("target,x,y,w,h,group\n");
    for (t, &(x, y)) in centres.iter().enumerate() {
        points.push_str(&format!(
            "{},{x},{y},{WINDOW},{WINDOW},{}\n",
            t + 1,
            t / PER_STOREY + 1
        ));
    }
    let write = |name: &str, text: &str| {
        std::fs::write(write_to.join(name), text)
            .with_context(|| format!("cannot write {}", dir.join(name).display()))
    };
    write("points.csv", &points)?;
    write("truth.csv", &truth)?;
    write("README.txt", &readme(dir, n, centres.len(), video))?;
    Ok(n)
}

/// Frame `k`: the wall `back`, each storey's beam and tags (at `centres` at rest) averaged over
/// the exposure's instants, into `img`; each tag's exposure-averaged centre appended to
/// `truth`.
fn render_frame(
    k: usize,
    (back, centres): (&[[f32; 3]], &[(f64, f64)]),
    img: &mut [[f32; 3]],
    truth: &mut String,
) {
    let t0 = k as f64 / FPS;
    let instants: Vec<f64> = (0..SUBSAMPLES)
        .map(|j| t0 + EXPOSURE_MS / 1000.0 * ((j as f64 + 0.5) / SUBSAMPLES as f64 - 0.5))
        .collect();
    img.copy_from_slice(back);
    for s in 0..STOREYS {
        let disp: Vec<(f64, f64)> = instants.iter().map(|&t| storey_disp(s, t)).collect();
        let tags = &centres[s * PER_STOREY..(s + 1) * PER_STOREY];
        draw_storey(img, tags, &disp);
        for (i, &(tx, ty)) in tags.iter().enumerate() {
            let m = disp.iter().fold((0.0, 0.0), |a, d| (a.0 + d.0, a.1 + d.1));
            let n = disp.len() as f64;
            truth.push_str(&format!(
                "{k},{},{},{}\n",
                s * PER_STOREY + i + 1,
                tx + m.0 / n,
                ty + m.1 / n
            ));
        }
    }
}

/// One storey's floor beam and `tags` drawn over `img`, averaged over the storey's
/// displacements `disp` at the exposure's instants (only the band the storey can reach).
fn draw_storey(img: &mut [[f32; 3]], tags: &[(f64, f64)], disp: &[(f64, f64)]) {
    let (w, h) = SIZE;
    let (x_lo, x_hi) = (tags[0].0 - 45.0, tags[PER_STOREY - 1].0 + 45.0);
    let y = tags[0].1;
    // the band the storey can reach in this exposure
    let (dmin, dmax) = disp.iter().fold((f64::MAX, f64::MIN), |(a, b), d| {
        (a.min(d.0).min(d.1), b.max(d.0).max(d.1))
    });
    let rows = ((y - 20.0 + dmin.min(0.0)).floor().max(0.0) as usize)
        ..((y + 30.0 + dmax.max(0.0)).ceil().min(h as f64) as usize);
    let cols = ((x_lo + dmin.min(0.0)).floor().max(0.0) as usize)
        ..((x_hi + dmax.max(0.0)).ceil().min(w as f64) as usize);
    for py in rows {
        for px in cols.clone() {
            let (fx, fy) = (px as f64, py as f64);
            let mut acc = [0f64; 3];
            let under = img[py * w + px];
            for &(dx, dy) in disp {
                let (u, v) = (fx - dx, fy - dy);
                if !(y - TAG_HALF - 0.5..y + 24.5).contains(&v)
                    || !(x_lo - 0.5..x_hi + 0.5).contains(&u)
                {
                    // neither the beam nor a tag reaches the pixel here: the wall (as the sum
                    // below gives it, with nothing covering it)
                    for (o, ch) in acc.iter_mut().zip(under) {
                        *o += ch as f64 / SUBSAMPLES as f64;
                    }
                    continue;
                }
                // the floor beam under the tags (dark grey-blue), then the tags on it
                let beam = cover(u, x_lo, x_hi) * cover(v, y + 14.0, y + 24.0);
                let mut c = [
                    under[0] as f64 * (1.0 - beam) + 92.0 * beam,
                    under[1] as f64 * (1.0 - beam) + 96.0 * beam,
                    under[2] as f64 * (1.0 - beam) + 104.0 * beam,
                ];
                for &(tx, ty) in tags {
                    if (u - tx).abs() >= TAG_HALF + 0.5 {
                        // the tags are 150 px apart: at most one covers the pixel
                        continue;
                    }
                    let a = cover(u, tx - TAG_HALF, tx + TAG_HALF)
                        * cover(v, ty - TAG_HALF, ty + TAG_HALF);
                    if a > 0.0 {
                        // the dot, box-filtered by a 4 x 4 supersampling of the pixel
                        let mut dot = 0.0;
                        for i in 0..4 {
                            for j in 0..4 {
                                let ex = u - tx + (i as f64 - 1.5) / 4.0;
                                let ey = v - ty + (j as f64 - 1.5) / 4.0;
                                if ex * ex + ey * ey <= DOT_R * DOT_R {
                                    dot += 1.0 / 16.0;
                                }
                            }
                        }
                        let tag = 240.0 * (1.0 - dot) + 30.0 * dot;
                        for ch in &mut c {
                            *ch = *ch * (1.0 - a) + tag * a;
                        }
                    }
                }
                for (o, ch) in acc.iter_mut().zip(c) {
                    *o += ch / SUBSAMPLES as f64;
                }
            }
            img[py * w + px] = acc.map(|v| v as f32);
        }
    }
}

/// The recording's README: what it shows and the command that follows every tag.
fn readme(dir: &Path, n: usize, tags: usize, video: bool) -> String {
    let (w, h) = SIZE;
    let d = dir.display();
    format!(
            "A model structure pulled and released in front of a white brick wall: {} tags \
             (all alike: white, a black dot on each) on {STOREYS} storeys, {n} colour JPEG \
             frames at {FPS} fps, {EXPOSURE_MS} ms exposure, {} x {} px. The top storey jumps by \
             up to about 120 px between frames; the tags are 150-170 px apart.\n\n\
             points.csv: a {WINDOW} x {WINDOW} window per tag and its storey (`group`: targets that move \
             together). truth.csv: each tag's exposure-averaged centre per frame.\n\n\
             Follow every tag with:\n\n  host-harness track --frames {d}/frames --fps {FPS} \
             --points {d}/points.csv --tracker lk --search-px 130 --out {d}/track\n{}",
            tags,
            w,
            h,
            if video {
                format!(
                    "\nframes.mkv: the same colour frames before JPEG compression, losslessly \
                     (RGB FFV1; read as its BT.601 luma): track --frames {d}/frames.mkv\n"
                )
            } else {
                String::new()
            }
        )
}

/// Writes the recording into the new directory `dir`, staged and moved into place (`force`:
/// replacing an earlier `render --recording` output there). Returns the frame count.
pub fn write_release_dir(dir: &Path, force: bool, video: bool) -> anyhow::Result<usize> {
    let out = vibcam_report::outdir::Staged::new(dir, force, "render --recording", &[])?;
    let n = write_release_recording((out.dir(), dir), video)?;
    out.commit()?;
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_release_jumps_further_than_the_tags_are_apart_minus_a_tag() {
        // the largest jump of the top storey between two frames, and the tag spacing
        let jumps: Vec<f64> = (1..(DURATION_S * FPS) as usize)
            .map(|k| (sway(k as f64 / FPS) - sway((k - 1) as f64 / FPS)).abs())
            .collect();
        let largest = jumps.iter().fold(0.0f64, |a, b| a.max(*b));
        assert!((110.0..=130.0).contains(&largest), "{largest}");
        let c = tag_centres();
        for s in 0..STOREYS {
            for i in 1..PER_STOREY {
                let gap = c[s * PER_STOREY + i].0 - c[s * PER_STOREY + i - 1].0;
                assert!((150.0..=170.0).contains(&gap), "{gap}");
            }
        }
        // at rest at the start of each pull
        assert_eq!(sway(0.2), 0.0);
        assert!(sway(4.4).abs() < 1.0, "{}", sway(4.4));
    }
}

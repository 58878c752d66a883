//! Labels beside points that do not cover one another: each label takes the first of eight
//! places around its point (right above, right below, left above, left below, then the same
//! twice as far) whose box, with a margin, overlaps no label placed before it and stays
//! inside the picture; a label with no such place is not drawn (its point keeps it as a
//! tooltip). Boxes are estimated from the text's length as a browser measures it: 0.66 of the font size per
//! character (DejaVu Sans digits are 0.64, Arial's 0.56) and 1.2 font sizes high (ascent 0.95,
//! descent 0.25).

/// A label's box: left, top, right, bottom.
type Rect = (f64, f64, f64, f64);

/// Width of a character as a fraction of the font size.
const CHAR_WIDTH: f64 = 0.66;

/// Height of a text's box above its baseline, and below it, as fractions of the font size.
const ASCENT: f64 = 0.95;
const DESCENT: f64 = 0.25;

/// Where each label goes: the text's anchor (x, baseline y), or `None` when it has no free
/// place. `points` are the points and their labels' lengths in characters, in the order they
/// claim places; `gap` is the distance from a point to its label, `font` the font size,
/// `bounds` the picture's width and height.
pub fn place(
    points: &[((f64, f64), usize)],
    gap: f64,
    font: f64,
    bounds: (f64, f64),
) -> Vec<Option<(f64, f64)>> {
    let mut taken: Vec<Rect> = Vec::new();
    points
        .iter()
        .map(|&((x, y), chars)| {
            let w = CHAR_WIDTH * font * chars as f64;
            let spot = candidates(x, y, w, gap, (ASCENT + DESCENT) * font)
                .into_iter()
                .find(|r| {
                    r.0 >= 0.0
                        && r.1 >= 0.0
                        && r.2 <= bounds.0
                        && r.3 <= bounds.1
                        && !taken.iter().any(|t| overlap(t, &padded(r, PAD * font)))
                })?;
            taken.push(spot);
            Some((spot.0, spot.3 - DESCENT * font))
        })
        .collect()
}

/// The eight boxes a label of width `w` and height `font` may take around `(x, y)`.
fn candidates(x: f64, y: f64, w: f64, gap: f64, font: f64) -> Vec<Rect> {
    let mut out = Vec::with_capacity(8);
    for far in [1.0, 2.0] {
        let g = gap * far;
        out.extend([
            (x + g, y - g - font, x + g + w, y - g),
            (x + g, y + g, x + g + w, y + g + font),
            (x - g - w, y - g - font, x - g, y - g),
            (x - g - w, y + g, x - g, y + g + font),
        ]);
    }
    out
}

/// The space kept free around a label, as a fraction of the font size: two numbers side by
/// side ("10" "12") otherwise read as one ("1012").
const PAD: f64 = 0.3;

/// `r` grown by `d` on every side.
fn padded(r: &Rect, d: f64) -> Rect {
    (r.0 - d, r.1 - d, r.2 + d, r.3 + d)
}

/// Whether two boxes share more than an edge.
fn overlap(a: &Rect, b: &Rect) -> bool {
    a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crowded_points_get_labels_that_never_overlap() {
        // 30 points 6 px apart on a line: labels 12 px high cannot all fit
        let points: Vec<((f64, f64), usize)> = (0..30)
            .map(|i| ((20.0 + 6.0 * f64::from(i), 60.0), 2))
            .collect();
        let (font, gap) = (12.0, 3.0);
        let placed = place(&points, gap, font, (240.0, 120.0));
        let boxes: Vec<Rect> = placed
            .iter()
            .zip(&points)
            .filter_map(|(p, (_, n))| {
                let (x, base) = (*p)?;
                let top = base - ASCENT * font;
                let bottom = base + DESCENT * font;
                Some((x, top, x + CHAR_WIDTH * font * *n as f64, bottom))
            })
            .collect();
        assert!(
            boxes.len() >= 8 && boxes.len() < 30,
            "{} placed",
            boxes.len()
        );
        for (i, a) in boxes.iter().enumerate() {
            assert!(
                a.0 >= 0.0 && a.1 >= 0.0 && a.2 <= 240.0 && a.3 <= 120.0,
                "{a:?}"
            );
            for b in &boxes[i + 1..] {
                assert!(!overlap(&padded(a, 0.29 * font), b), "{a:?} {b:?}");
            }
        }
        // points far apart all keep the first place, right above
        let apart = [((10.0, 50.0), 1), ((100.0, 50.0), 1)];
        let p = place(&apart, gap, font, (240.0, 120.0));
        assert_eq!(p[0], Some((13.0, 47.0 - DESCENT * font)));
        assert!(p[1].is_some());
    }
}

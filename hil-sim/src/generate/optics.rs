//! What the lens and pixel area do to the rendered image before the sensor takes its logarithm.

/// The lens and pixel area blur the image: a 3x3 binomial filter (about 0.7 px standard deviation), edges
/// replicated at the image border. Takes the rendered linear intensity of a `ew x eh` region and writes the log
/// intensity of its `w x h` inner part starting at `inner` (the region must extend one pixel beyond the inner
/// part wherever the inner part is not at the image border).
pub fn optics_log(
    intensity: &[f32],
    ew: u32,
    eh: u32,
    inner: (u32, u32),
    (w, h): (u32, u32),
    eps: f32,
    out: &mut Vec<f32>,
) {
    let (ew, eh, w, h) = (ew as usize, eh as usize, w as usize, h as usize);
    let (ix, iy) = (inner.0 as usize, inner.1 as usize);
    // Horizontal [1 2 1] pass over the rows the vertical pass needs (row iy - 1 .. iy + h, clamped).
    let mut rows = std::mem::take(out);
    rows.clear();
    rows.reserve((h + 2) * w);
    for r in 0..h + 2 {
        let y = (iy + r).saturating_sub(1).min(eh - 1);
        let row = &intensity[y * ew..(y + 1) * ew];
        for x in ix..ix + w {
            let (l, c, rt) = (row[x.saturating_sub(1)], row[x], row[(x + 1).min(ew - 1)]);
            rows.push(l.max(0.0) + 2.0 * c.max(0.0) + rt.max(0.0));
        }
    }
    // Vertical [1 2 1] pass, in place from the top (each output row only reads rows at or below it).
    for y in 0..h {
        for x in 0..w {
            let v = (rows[y * w + x] + 2.0 * rows[(y + 1) * w + x] + rows[(y + 2) * w + x]) / 16.0;
            rows[y * w + x] = (v + eps).ln();
        }
    }
    rows.truncate(h * w);
    *out = rows;
}

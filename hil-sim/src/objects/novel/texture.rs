//! The paint of every novel object: two contrasting colours in a pattern, grain and printed-label blocks.

use super::super::texture::{
    Canvas, Colour, TEXTURE_SIZE, checker, fbm, mix, shade, stripe, text_lines,
};
use super::parts::{pick, tile};
use crate::rng::SeedRng;
use image::RgbImage;
use std::f64::consts::PI;

/// Saturated and neutral paint colours.
const PALETTE: [Colour; 12] = [
    [0.85, 0.15, 0.12],
    [0.95, 0.6, 0.1],
    [0.95, 0.85, 0.2],
    [0.2, 0.6, 0.25],
    [0.1, 0.45, 0.75],
    [0.45, 0.2, 0.65],
    [0.9, 0.4, 0.6],
    [0.1, 0.65, 0.65],
    [0.92, 0.9, 0.85],
    [0.12, 0.12, 0.14],
    [0.55, 0.35, 0.2],
    [0.55, 0.58, 0.62],
];

/// Perceived brightness of a colour, 0 to 1.
fn luminance(c: Colour) -> f32 {
    0.3 * c[0] + 0.59 * c[1] + 0.11 * c[2]
}

/// The texture atlas: two contrasting colours (the accent blended 55-85 % over the base) in one of four patterns
/// (stripes at an angle, checks, blobs, rings), grain over everything, and printed-label blocks on two regions.
pub(super) fn paint(rng: &mut SeedRng) -> RgbImage {
    let base = PALETTE[pick(rng, 0, PALETTE.len() - 1)];
    let mut accent = PALETTE[pick(rng, 0, PALETTE.len() - 1)];
    if (luminance(accent) - luminance(base)).abs() < 0.25 {
        accent = if luminance(base) > 0.5 {
            shade(accent, 0.3)
        } else {
            mix(accent, [1.0; 3], 0.7)
        };
    }
    let ink: Colour = if luminance(base) > 0.45 {
        [0.06, 0.06, 0.08]
    } else {
        [0.95, 0.95, 0.9]
    };
    let pattern = pick(rng, 0, 3);
    // How far the pattern goes from the base colour to the accent: full black-on-white stripes would fire several
    // times the events of the library's textures.
    let strength = rng.range(0.55, 0.85) as f32;
    let period = rng.range(0.07, 0.16) as f32;
    let (sa, ca) = (rng.range(0.0, PI) as f32).sin_cos();
    let cells = pick(rng, 4, 9) as f32;
    let blobs = rng.range(5.0, 10.0) as f32;
    let noise = (rng.uniform() * f64::from(u32::MAX)) as u32;
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    for k in 0..6 {
        let region = tile(k);
        let n = noise.wrapping_add(k as u32 * 7919);
        canvas.paint(&region, |s, t| {
            let m = match pattern {
                0 => stripe(s * ca + t * sa, period, 0.5),
                1 => checker(s, t, cells),
                2 => {
                    if fbm(s * blobs, t * blobs, n ^ 0x5a5a, 3) > 0.5 {
                        1.0
                    } else {
                        0.0
                    }
                }
                _ => stripe(((s - 0.5).powi(2) + (t - 0.5).powi(2)).sqrt(), period, 0.5),
            };
            let grain = fbm(s * 24.0, t * 24.0, n, 3);
            shade(mix(base, accent, m * strength), 0.75 + 0.5 * grain)
        });
    }
    for k in [0, 2] {
        let s0 = rng.range(0.05, 0.3) as f32;
        let t0 = rng.range(0.1, 0.5) as f32;
        let area = [s0, t0, s0 + 0.5, t0 + 0.3];
        let rects = text_lines(rng.range(0.0, 1e9) as u64, area, 3, 0.06);
        canvas.blocks(&tile(k), &rects, ink);
    }
    canvas.into_image()
}

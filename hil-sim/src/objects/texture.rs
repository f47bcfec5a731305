//! Procedural texture painting into an RGB atlas: noise, stripes, checkers and printed-label-like layouts.
//!
//! Colours are sRGB in `[0, 1]`. Everything is a deterministic function of its parameters and seed.

use super::builder::UvRect;
use image::{Rgb, RgbImage};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Side of every object's texture atlas, texels.
pub const TEXTURE_SIZE: u32 = 512;

/// An sRGB colour, components in `[0, 1]`.
pub type Colour = [f32; 3];

/// Linear blend of two colours, `x` in `[0, 1]`.
pub fn mix(a: Colour, b: Colour, x: f32) -> Colour {
    let x = x.clamp(0.0, 1.0);
    [
        a[0] + (b[0] - a[0]) * x,
        a[1] + (b[1] - a[1]) * x,
        a[2] + (b[2] - a[2]) * x,
    ]
}

/// Scales a colour's brightness.
pub fn shade(c: Colour, k: f32) -> Colour {
    c.map(|v| (v * k).clamp(0.0, 1.0))
}

fn hash(x: i32, y: i32, seed: u32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6_b343)
        ^ (y as u32).wrapping_mul(0xd816_3841)
        ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0x00ff_ffff) as f32 / 16_777_215.0
}

/// Smooth value noise in `[0, 1]` with unit lattice spacing.
pub fn value_noise(x: f32, y: f32, seed: u32) -> f32 {
    let (xf, yf) = (x.floor(), y.floor());
    let (xi, yi) = (xf as i32, yf as i32);
    let smooth = |t: f32| t * t * (3.0 - 2.0 * t);
    let (sx, sy) = (smooth(x - xf), smooth(y - yf));
    let top = hash(xi, yi, seed) + (hash(xi + 1, yi, seed) - hash(xi, yi, seed)) * sx;
    let bottom =
        hash(xi, yi + 1, seed) + (hash(xi + 1, yi + 1, seed) - hash(xi, yi + 1, seed)) * sx;
    top + (bottom - top) * sy
}

/// Fractal (fBm) value noise in `[0, 1]`: `octaves` octaves, each twice the frequency and half the amplitude.
pub fn fbm(x: f32, y: f32, seed: u32, octaves: u32) -> f32 {
    let (mut sum, mut amp, mut freq, mut norm) = (0.0, 0.5, 1.0, 0.0);
    for o in 0..octaves {
        sum += amp * value_noise(x * freq, y * freq, seed.wrapping_add(o * 7919));
        norm += amp;
        amp *= 0.5;
        freq *= 2.0;
    }
    sum / norm
}

/// A texture atlas being painted.
#[derive(Debug, Clone)]
pub struct Canvas {
    image: RgbImage,
}

impl Canvas {
    /// A `size x size` canvas filled with mid grey.
    pub fn new(size: u32) -> Self {
        Self {
            image: RgbImage::from_pixel(size, size, Rgb([128, 128, 128])),
        }
    }

    /// The painted image.
    pub fn into_image(self) -> RgbImage {
        self.image
    }

    /// Pixel bounds `(x0, y0, x1, y1)` (exclusive ends) of an atlas rectangle; image row 0 is `v = 1`.
    fn bounds(&self, r: &UvRect) -> (u32, u32, u32, u32) {
        let (w, h) = (self.image.width() as f32, self.image.height() as f32);
        let x0 = (r.u0 * w).floor().clamp(0.0, w) as u32;
        let x1 = (r.u1 * w).ceil().clamp(0.0, w) as u32;
        let y0 = ((1.0 - r.v1) * h).floor().clamp(0.0, h) as u32;
        let y1 = ((1.0 - r.v0) * h).ceil().clamp(0.0, h) as u32;
        (x0, y0, x1, y1)
    }

    /// Paints every pixel of `region` with `f(s, t)`, where `(s, t)` in `[0, 1]^2` are the same local coordinates
    /// that [`UvRect::map`] uses (`t` up).
    pub fn paint(&mut self, region: &UvRect, f: impl Fn(f32, f32) -> Colour) {
        let (x0, y0, x1, y1) = self.bounds(region);
        let (wf, hf) = ((x1 - x0).max(1) as f32, (y1 - y0).max(1) as f32);
        for y in y0..y1 {
            for x in x0..x1 {
                let s = (x - x0) as f32 / wf + 0.5 / wf;
                let t = 1.0 - ((y - y0) as f32 / hf + 0.5 / hf);
                let c = f(s, t);
                self.image.put_pixel(
                    x,
                    y,
                    Rgb(c.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)),
                );
            }
        }
    }

    /// Overprints solid rectangles in `region`'s local coordinates `(s0, t0, s1, t1)`.
    pub fn blocks(&mut self, region: &UvRect, rects: &[[f32; 4]], colour: Colour) {
        let (x0, y0, x1, y1) = self.bounds(region);
        let (wf, hf) = ((x1 - x0) as f32, (y1 - y0) as f32);
        let px = Rgb(colour.map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8));
        for r in rects {
            let ax = x0 + (r[0].clamp(0.0, 1.0) * wf) as u32;
            let bx = x0 + (r[2].clamp(0.0, 1.0) * wf) as u32;
            let ay = y0 + ((1.0 - r[3].clamp(0.0, 1.0)) * hf) as u32;
            let by = y0 + ((1.0 - r[1].clamp(0.0, 1.0)) * hf) as u32;
            for y in ay..by.min(y1) {
                for x in ax..bx.min(x1) {
                    self.image.put_pixel(x, y, px);
                }
            }
        }
    }
}

/// Rectangles that look like lines of printed text inside the local box `(s0, t0, s1, t1)`: `lines` rows of words of
/// random length.
pub fn text_lines(seed: u64, area: [f32; 4], lines: u32, glyph_height: f32) -> Vec<[f32; 4]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let [s0, t0, s1, t1] = area;
    let pitch = (t1 - t0) / lines.max(1) as f32;
    let mut rects = Vec::new();
    for line in 0..lines {
        let top = t1 - pitch * line as f32;
        let mut s = s0 + rng.random_range(0.0..0.05) * (s1 - s0);
        while s < s1 {
            let word = rng.random_range(0.04..0.2) * (s1 - s0);
            let end = (s + word).min(s1);
            rects.push([s, top - glyph_height.min(pitch * 0.8), end, top]);
            s = end + rng.random_range(0.02..0.05) * (s1 - s0);
        }
    }
    rects
}

/// 1 inside the "on" part of stripes of period `period` along `x` with duty cycle `duty`, else 0.
pub fn stripe(x: f32, period: f32, duty: f32) -> f32 {
    if (x / period).rem_euclid(1.0) < duty {
        1.0
    } else {
        0.0
    }
}

/// 1 on the "white" squares of a checkerboard of `n x n` cells over the unit square, else 0.
pub fn checker(s: f32, t: f32, n: f32) -> f32 {
    if ((s * n).floor() as i64 + (t * n).floor() as i64).rem_euclid(2) == 0 {
        1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_is_bounded_and_deterministic() {
        for i in 0..500 {
            let (x, y) = (i as f32 * 0.37, i as f32 * 0.11);
            let v = fbm(x, y, 3, 4);
            assert!((0.0..=1.0).contains(&v));
            assert_eq!(v, fbm(x, y, 3, 4));
        }
        assert_ne!(value_noise(0.5, 0.5, 1), value_noise(0.5, 0.5, 2));
    }

    #[test]
    fn paint_covers_the_region_only() {
        let mut c = Canvas::new(16);
        c.paint(&UvRect::new(0.0, 0.5, 0.5, 1.0), |_, _| [1.0, 0.0, 0.0]);
        let img = c.into_image();
        assert_eq!(img.get_pixel(0, 0).0, [255, 0, 0]); // top-left is v = 1
        assert_eq!(img.get_pixel(7, 7).0, [255, 0, 0]);
        assert_eq!(img.get_pixel(8, 0).0, [128, 128, 128]);
        assert_eq!(img.get_pixel(0, 8).0, [128, 128, 128]);
    }
}

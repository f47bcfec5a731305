//! Packaging: printed boxes, a food can and a squeeze bottle (cuboids and surfaces of revolution).

use super::builder::{MeshBuilder, UvRect};
use super::texture::{Canvas, Colour, TEXTURE_SIZE, checker, fbm, mix, shade, stripe, text_lines};
use image::RgbImage;
use nalgebra::{Isometry3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Segments around surfaces of revolution.
pub(super) const SEGMENTS: u32 = 64;

/// A saturated packaging colour picked by the seed.
pub(super) fn pick_colour(rng: &mut ChaCha8Rng) -> Colour {
    const PALETTE: [Colour; 8] = [
        [0.85, 0.12, 0.10],
        [0.95, 0.75, 0.10],
        [0.10, 0.35, 0.75],
        [0.10, 0.55, 0.25],
        [0.55, 0.20, 0.60],
        [0.95, 0.45, 0.10],
        [0.05, 0.60, 0.65],
        [0.75, 0.10, 0.35],
    ];
    PALETTE[rng.random_range(0..PALETTE.len())]
}

pub(super) const INK: Colour = [0.08, 0.08, 0.1];
pub(super) const PAPER: Colour = [0.93, 0.92, 0.88];

/// Paints a printed-label-like panel: tinted background, a bold band, a checker logo and lines of text.
fn label(canvas: &mut Canvas, region: &UvRect, seed: u64, base: Colour, accent: Colour) {
    let s_seed = seed as u32;
    canvas.paint(region, |s, t| {
        let grain = fbm(s * 24.0, t * 24.0, s_seed, 3);
        let band = if (0.55..0.75).contains(&t) { 1.0 } else { 0.0 };
        let logo = if (0.1..0.35).contains(&s) && (0.78..0.95).contains(&t) {
            checker(s, t, 24.0)
        } else {
            0.0
        };
        let c = mix(shade(base, 0.85 + 0.3 * grain), accent, band);
        mix(c, PAPER, logo)
    });
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let title = text_lines(rng.random(), [0.08, 0.58, 0.92, 0.72], 1, 0.1);
    canvas.blocks(region, &title, PAPER);
    let body = text_lines(rng.random(), [0.08, 0.08, 0.92, 0.48], 7, 0.03);
    canvas.blocks(region, &body, INK);
}

/// A closed cardboard box of edge lengths `size` (x width, y depth, z height), printed on every face.
pub fn cardboard_box(size: Vector3<f32>, seed: u64) -> (MeshBuilder, RgbImage) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (base, accent) = (pick_colour(&mut rng), pick_colour(&mut rng));
    // Atlas: front / back panels below, sides and top / bottom flaps above.
    let front = UvRect::new(0.0, 0.0, 0.5, 0.62);
    let back = UvRect::new(0.5, 0.0, 1.0, 0.62);
    let side_a = UvRect::new(0.0, 0.62, 0.2, 1.0);
    let side_b = UvRect::new(0.2, 0.62, 0.4, 1.0);
    let top = UvRect::new(0.4, 0.62, 0.7, 1.0);
    let bottom = UvRect::new(0.7, 0.62, 1.0, 1.0);
    let mut g = MeshBuilder::default();
    g.cuboid(
        size,
        &Isometry3::identity(),
        [side_a, side_b, back, front, top, bottom],
    );

    let mut canvas = Canvas::new(TEXTURE_SIZE);
    label(&mut canvas, &front, rng.random(), base, accent);
    // Back: a nutrition-table-like grid of text.
    canvas.paint(&back, |s, t| {
        let rule = stripe(t, 0.08, 0.08) * if (0.1..0.9).contains(&s) { 1.0 } else { 0.0 };
        mix(mix(PAPER, base, 0.2), INK, rule)
    });
    let rows = text_lines(rng.random(), [0.12, 0.1, 0.88, 0.9], 10, 0.035);
    canvas.blocks(&back, &rows, INK);
    for side in [side_a, side_b] {
        let noise_seed = rng.random::<u32>();
        canvas.paint(&side, |s, t| {
            let barcode = if t < 0.25 && (0.2..0.8).contains(&s) {
                stripe(s + 0.37 * fbm(s * 9.0, 0.0, 5, 1), 0.04, 0.45)
            } else {
                0.0
            };
            mix(
                shade(base, 0.8 + 0.3 * fbm(s * 10.0, t * 10.0, noise_seed, 3)),
                INK,
                barcode,
            )
        });
        let text = text_lines(rng.random(), [0.1, 0.35, 0.9, 0.9], 6, 0.04);
        canvas.blocks(&side, &text, PAPER);
    }
    for flap in [top, bottom] {
        canvas.paint(&flap, |s, t| {
            let seam = stripe(t + 0.5, 1.0, 0.04);
            mix(
                shade(accent, 0.75 + 0.3 * fbm(s * 16.0, t * 16.0, 11, 3)),
                INK,
                seam,
            )
        });
    }
    (g, canvas.into_image())
}

/// A food can: radius 3.4 cm, height 10 cm, beaded rims, a wrapped paper label and metallic lids.
pub fn can(seed: u64) -> (MeshBuilder, RgbImage) {
    let (r, h, bevel) = (0.034f32, 0.10f32, 0.004f32);
    let lids = UvRect::new(0.0, 0.0, 1.0, 0.2);
    let side = UvRect::new(0.0, 0.2, 1.0, 1.0);
    let mut g = MeshBuilder::default();
    let id = Isometry3::identity();
    g.lathe(
        &[
            &[(0.0, 0.0), (r - bevel, 0.0)],
            &[(r - bevel, 0.0), (r, bevel)],
        ],
        SEGMENTS,
        lids,
        &id,
    );
    g.lathe(
        &[&[(r, bevel), (r, h * 0.5), (r, h - bevel)]],
        SEGMENTS,
        side,
        &id,
    );
    g.lathe(
        &[
            &[(r, h - bevel), (r - bevel, h)],
            &[(r - bevel, h), (0.0, h)],
        ],
        SEGMENTS,
        lids,
        &id,
    );

    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (base, accent) = (pick_colour(&mut rng), pick_colour(&mut rng));
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    canvas.paint(&lids, |s, t| {
        let rings = stripe(t, 0.12, 0.3);
        shade(
            [0.72, 0.72, 0.75],
            0.8 + 0.15 * rings + 0.2 * fbm(s * 40.0, t * 8.0, 3, 3),
        )
    });
    // The label wraps once around: u is the angle, so two copies of the panel face opposite sides.
    let text_seed = rng.random::<u64>();
    canvas.paint(&side, |s, t| {
        let wave = 0.5 + 0.5 * (s * std::f32::consts::TAU * 3.0 + t * 6.0).sin();
        let band = if (0.35..0.6).contains(&t) { 1.0 } else { 0.0 };
        mix(mix(base, shade(base, 0.6), wave * 0.5), accent, band)
    });
    for half in [0.0f32, 0.5] {
        let rects = text_lines(
            text_seed.wrapping_add(half.to_bits() as u64),
            [half + 0.05, 0.66, half + 0.45, 0.9],
            3,
            0.05,
        );
        canvas.blocks(&side, &rects, PAPER);
        let small = text_lines(
            text_seed ^ 77,
            [half + 0.05, 0.05, half + 0.45, 0.3],
            5,
            0.03,
        );
        canvas.blocks(&side, &small, INK);
    }
    (g, canvas.into_image())
}

/// Samples `n + 1` points of a smooth step between two profile points (cosine ease), excluding nothing.
fn ease(from: (f32, f32), to: (f32, f32), n: u32) -> Vec<(f32, f32)> {
    (0..=n)
        .map(|i| {
            let x = i as f32 / n as f32;
            let e = 0.5 - 0.5 * (std::f32::consts::PI * x).cos();
            (from.0 + (to.0 - from.0) * e, from.1 + (to.1 - from.1) * x)
        })
        .collect()
}

/// A squeeze bottle: body radius 3.2 cm up to 11 cm, eased shoulder to a 1.2 cm neck, screw cap; 19 cm tall.
pub fn bottle(seed: u64) -> (MeshBuilder, RgbImage) {
    let r = 0.032f32;
    let body = UvRect::new(0.0, 0.0, 1.0, 0.7);
    let top = UvRect::new(0.0, 0.7, 1.0, 1.0);
    let mut g = MeshBuilder::default();
    let id = Isometry3::identity();
    let shoulder = ease((r, 0.11), (0.012, 0.155), 10);
    g.lathe(
        &[
            &[(0.0, 0.0), (r - 0.005, 0.0)],
            &[(r - 0.005, 0.0), (r, 0.005), (r, 0.06), (r, 0.11)],
        ],
        SEGMENTS,
        body,
        &id,
    );
    g.lathe(
        &[
            &shoulder,
            &[(0.012, 0.155), (0.012, 0.165)],
            &[(0.012, 0.165), (0.015, 0.165)],
            &[(0.015, 0.165), (0.015, 0.185)],
            &[(0.015, 0.185), (0.006, 0.19)],
            &[(0.006, 0.19), (0.0, 0.19)],
        ],
        SEGMENTS,
        top,
        &id,
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let base = pick_colour(&mut rng);
    let accent = pick_colour(&mut rng);
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    for half in [0.0f32, 0.5] {
        let panel = UvRect::new(half, 0.12, half + 0.5, 0.62);
        label(&mut canvas, &panel, rng.random(), accent, base);
    }
    canvas.paint(&UvRect::new(0.0, 0.0, 1.0, 0.12), |s, t| {
        shade(base, 0.8 + 0.3 * fbm(s * 30.0, t * 5.0, 9, 3))
    });
    canvas.paint(&UvRect::new(0.0, 0.62, 1.0, 0.7), |s, t| {
        shade(base, 0.8 + 0.3 * fbm(s * 30.0, t * 5.0, 10, 3))
    });
    canvas.paint(&top, |s, t| {
        // Cap ribs around, plastic noise.
        let ribs = stripe(s, 1.0 / 48.0, 0.5) * if t > 0.5 { 1.0 } else { 0.0 };
        mix(
            shade(base, 0.9 + 0.2 * fbm(s * 20.0, t * 20.0, 4, 3)),
            INK,
            0.6 * ribs,
        )
    });
    (g, canvas.into_image())
}

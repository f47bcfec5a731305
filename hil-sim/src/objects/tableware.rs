//! Tableware and stationery: mug, bowl, wine glass and marker (surfaces of revolution, a swept handle).

use super::builder::{MeshBuilder, UvRect};
use super::packaging::{INK, PAPER, SEGMENTS, pick_colour};
use super::texture::{Canvas, Colour, TEXTURE_SIZE, checker, fbm, mix, shade, stripe, text_lines};
use image::RgbImage;
use nalgebra::Isometry3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A mug: outer radius 4.1 cm, 9.5 cm tall, 4 mm wall, with a C-shaped handle.
pub fn mug(seed: u64) -> (MeshBuilder, RgbImage) {
    let (r, h, wall) = (0.041f32, 0.095f32, 0.004f32);
    let body = UvRect::new(0.0, 0.25, 1.0, 1.0);
    let handle = UvRect::new(0.0, 0.0, 1.0, 0.25);
    let mut g = MeshBuilder::default();
    let id = Isometry3::identity();
    g.lathe(
        &[
            &[(0.0, 0.0), (r - 0.004, 0.0)],
            &[(r - 0.004, 0.0), (r, 0.004)],
            &[(r, 0.004), (r, h * 0.5), (r, h)],
            &[(r, h), (r - wall, h)],
            &[(r - wall, h), (r - wall, h * 0.5), (r - wall, 0.008)],
            &[(r - wall, 0.008), (0.0, 0.008)],
        ],
        SEGMENTS,
        body,
        &id,
    );
    // Handle: half an ellipse in the xz plane from near the rim to near the base, ends buried in the wall.
    let (a, b, zc) = (0.03f32, h * 0.3, h * 0.52);
    let path: Vec<_> = (0..=24)
        .map(|i| {
            let theta = std::f32::consts::FRAC_PI_2 - std::f32::consts::PI * i as f32 / 24.0;
            nalgebra::Point3::new(
                r - 0.003 + (a + 0.003) * theta.cos(),
                0.0,
                zc + b * theta.sin(),
            )
        })
        .collect();
    g.tube(&path, &[0.0065; 25], 20, handle);

    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (base, accent) = (pick_colour(&mut rng), pick_colour(&mut rng));
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    let glaze = rng.random::<u32>();
    canvas.paint(&body, |s, t| {
        // Outside (lower part of the profile's arc length): a glazed pattern of dots and waves; inside plain.
        if t > 0.55 {
            return shade(PAPER, 0.9 + 0.1 * fbm(s * 30.0, t * 30.0, glaze, 2));
        }
        let dots = {
            let (cx, cy) = ((s * 24.0).fract() - 0.5, (t * 12.0).fract() - 0.5);
            if cx * cx + cy * cy < 0.08 { 1.0 } else { 0.0 }
        };
        let wave = stripe(
            t + 0.03 * (s * std::f32::consts::TAU * 8.0).sin(),
            0.09,
            0.3,
        );
        mix(
            mix(
                shade(base, 0.85 + 0.2 * fbm(s * 20.0, t * 20.0, glaze, 3)),
                accent,
                wave,
            ),
            PAPER,
            dots,
        )
    });
    canvas.paint(&handle, |s, t| {
        mix(
            base,
            accent,
            stripe(t, 0.1, 0.5) * 0.5 + 0.1 * fbm(s * 8.0, t * 8.0, 2, 2),
        )
    });
    (g, canvas.into_image())
}

/// A bowl: rim radius 8 cm, 5.5 cm tall, 4 mm wall, with a foot ring.
pub fn bowl(seed: u64) -> (MeshBuilder, RgbImage) {
    let (rim, h, wall, foot) = (0.08f32, 0.055f32, 0.004f32, 0.04f32);
    let uv = UvRect::new(0.0, 0.0, 1.0, 1.0);
    let outer: Vec<(f32, f32)> = (0..=14)
        .map(|i| {
            let a = std::f32::consts::FRAC_PI_2 * i as f32 / 14.0;
            (
                foot + (rim - foot) * a.sin(),
                0.006 + (h - 0.006) * (1.0 - a.cos()),
            )
        })
        .collect();
    let inner: Vec<(f32, f32)> = (0..=14)
        .rev()
        .map(|i| {
            let a = std::f32::consts::FRAC_PI_2 * i as f32 / 14.0;
            (
                (rim - wall) * a.sin(),
                0.006 + wall + (h - 0.006 - wall) * (1.0 - a.cos()),
            )
        })
        .collect();
    let mut g = MeshBuilder::default();
    g.lathe(
        &[
            &[(0.0, 0.0), (foot - 0.003, 0.0)],
            &[(foot - 0.003, 0.0), (foot, 0.006)],
            &outer,
            &[(rim, h), (rim - wall, h)],
            &inner,
        ],
        SEGMENTS,
        uv,
        &Isometry3::identity(),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (base, accent) = (pick_colour(&mut rng), pick_colour(&mut rng));
    let n = rng.random::<u32>();
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    canvas.paint(&uv, |s, t| {
        // Radial petals on the inside, a checker rim band, speckled glaze outside.
        let petals = stripe(s + 0.05 * (t * 30.0).sin(), 1.0 / 16.0, 0.5);
        let c = shade(base, 0.8 + 0.3 * fbm(s * 40.0, t * 20.0, n, 3));
        if t > 0.62 {
            mix(c, accent, petals * 0.8)
        } else if t > 0.5 {
            mix(PAPER, INK, checker(s, t, 48.0))
        } else {
            mix(
                c,
                PAPER,
                if fbm(s * 90.0, t * 90.0, n ^ 5, 1) > 0.72 {
                    1.0
                } else {
                    0.0
                },
            )
        }
    });
    (g, canvas.into_image())
}

/// A marker pen: 7.5 mm barrel radius, cap at the bottom, conical tip at the top; 13 cm long.
pub fn marker(seed: u64) -> (MeshBuilder, RgbImage) {
    let uv = UvRect::new(0.0, 0.0, 1.0, 1.0);
    let mut g = MeshBuilder::default();
    g.lathe(
        &[
            &[(0.0, 0.0), (0.0085, 0.0)],
            &[(0.0085, 0.0), (0.0085, 0.035)],
            &[(0.0085, 0.035), (0.0075, 0.035)],
            &[(0.0075, 0.035), (0.0075, 0.07), (0.0075, 0.11)],
            &[(0.0075, 0.11), (0.0035, 0.122)],
            &[(0.0035, 0.122), (0.0015, 0.128), (0.0, 0.129)],
        ],
        48,
        uv,
        &Isometry3::identity(),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let ink = pick_colour(&mut rng);
    let text = text_lines(rng.random(), [0.05, 0.42, 0.45, 0.7], 2, 0.08);
    let text2: Vec<[f32; 4]> = text
        .iter()
        .map(|r| [r[0] + 0.5, r[1], r[2] + 0.5, r[3]])
        .collect();
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    canvas.paint(&uv, |s, t| {
        // Arc-length fractions: cap below ~0.3, barrel to ~0.85, tip above.
        if t < 0.3 {
            mix(ink, shade(ink, 0.6), stripe(s, 1.0 / 24.0, 0.3))
        } else if t < 0.86 {
            let band = if (0.75..0.82).contains(&t) { 1.0 } else { 0.0 };
            mix(
                shade(PAPER, 0.95 + 0.05 * fbm(s * 50.0, t * 50.0, 1, 2)),
                ink,
                band,
            )
        } else {
            shade(ink, 0.5)
        }
    });
    canvas.blocks(&uv, &text, INK);
    canvas.blocks(&uv, &text2, INK);
    (g, canvas.into_image())
}

/// A stemmed wine glass: foot radius 3.5 cm, 8.5 cm stem, bowl up to 4.2 cm radius, 20 cm tall, 2 mm walls. Rendered
/// opaque, with an etched pattern so that it produces events.
pub fn wine_glass(seed: u64) -> (MeshBuilder, RgbImage) {
    let uv = UvRect::new(0.0, 0.0, 1.0, 1.0);
    let wall = 0.002f32;
    let bowl_profile = |i: u32, n: u32, inset: f32| {
        // Bowl radius over height: from the stem (z = 0.09) through a belly (r 4.2 cm at z = 0.16) to a 2.6 cm rim.
        let x = i as f32 / n as f32;
        let z = 0.09 + 0.11 * x;
        let r = 0.0035 + 0.0385 * (std::f32::consts::PI * 0.8 * x).sin();
        ((r - inset).max(0.0), z)
    };
    let outer: Vec<(f32, f32)> = (0..=16).map(|i| bowl_profile(i, 16, 0.0)).collect();
    let rim_outer = *outer.last().unwrap_or(&(0.035, 0.2));
    let mut inner: Vec<(f32, f32)> = (2..=16).rev().map(|i| bowl_profile(i, 16, wall)).collect();
    inner.push((0.0, 0.09 + wall * 2.0));
    let rim_inner = inner[0];
    let mut g = MeshBuilder::default();
    g.lathe(
        &[
            &[(0.0, 0.0), (0.035, 0.0)],
            &[(0.035, 0.0), (0.035, 0.003)],
            &[(0.035, 0.003), (0.012, 0.006), (0.0035, 0.012)],
            &[(0.0035, 0.012), (0.0035, 0.05), (0.0035, 0.09)],
            &outer,
            &[rim_outer, rim_inner],
            &inner,
        ],
        SEGMENTS,
        uv,
        &Isometry3::identity(),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let tint: Colour = mix([0.8, 0.85, 0.9], pick_colour(&mut rng), 0.15);
    let n = rng.random::<u32>();
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    canvas.paint(&uv, |s, t| {
        // Diamond-cut etching on the bowl, fine rings on the foot and stem.
        let diamonds = checker(s + t * 2.0, s - t * 2.0, 18.0);
        let etched = if t > 0.45 {
            diamonds
        } else {
            stripe(t, 0.03, 0.5)
        };
        mix(
            shade(tint, 0.85 + 0.15 * fbm(s * 40.0, t * 40.0, n, 2)),
            shade(tint, 0.45),
            etched * 0.7,
        )
    });
    (g, canvas.into_image())
}

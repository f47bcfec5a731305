//! Elongated and articulated shapes: banana, hammer, spatula and drill (swept tubes, lathes and cuboids).

use super::builder::{MeshBuilder, UvRect};
use super::texture::{Canvas, Colour, TEXTURE_SIZE, fbm, mix, shade, stripe, text_lines};
use image::RgbImage;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f32::consts::{FRAC_PI_2, PI};

const INK: Colour = [0.08, 0.08, 0.1];

/// The frame whose z axis points along +x (for lathes that should lie along x), at `origin`.
fn along_x(origin: Vector3<f32>) -> Isometry3<f32> {
    Isometry3::from_parts(
        Translation3::from(origin),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), FRAC_PI_2),
    )
}

/// A banana: a tube along a 13 cm-radius arc of 95 degrees (about 21 cm of centre line), 1.8 cm thick in the middle,
/// tapering to a stem at one end and a blunt tip at the other.
pub fn banana(seed: u64) -> (MeshBuilder, RgbImage) {
    let (bend, sweep, n) = (0.13f32, 95f32.to_radians(), 48usize);
    let path: Vec<Point3<f32>> = (0..=n)
        .map(|i| {
            let a = sweep * i as f32 / n as f32;
            Point3::new(bend * a.sin(), 0.0, bend * (1.0 - a.cos()))
        })
        .collect();
    let radii: Vec<f32> = (0..=n)
        .map(|i| {
            let x = i as f32 / n as f32;
            if x > 0.93 {
                0.0045 // stem
            } else {
                (0.018 * (PI * (x / 0.93)).sin().powf(0.55)).max(0.004)
            }
        })
        .collect();
    let uv = UvRect::new(0.0, 0.0, 1.0, 1.0);
    let mut g = MeshBuilder::default();
    g.tube(&path, &radii, 24, uv);

    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n_seed = rng.random::<u32>();
    let ripeness = rng.random_range(0.0..0.4f32);
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    let yellow: Colour = [0.95, 0.8, 0.15];
    let brown: Colour = [0.35, 0.22, 0.08];
    let green: Colour = [0.55, 0.65, 0.15];
    canvas.paint(&uv, |s, t| {
        // Ridges along the fruit, brown speckles, dark ends.
        let ridges = stripe(s, 0.2, 0.1);
        let speck = if fbm(s * 60.0, t * 120.0, n_seed, 2) > 0.78 - ripeness * 0.1 {
            1.0
        } else {
            0.0
        };
        let ends = ((0.05 - t).max(t - 0.92).max(0.0) * 20.0).min(1.0);
        let base = mix(yellow, green, 0.3 * fbm(s * 4.0, t * 6.0, n_seed ^ 1, 3));
        mix(
            mix(
                shade(base, 1.0 - 0.15 * ridges),
                brown,
                speck * (0.6 + ripeness),
            ),
            brown,
            ends,
        )
    });
    (g, canvas.into_image())
}

/// A claw hammer: 28 cm wooden handle (radius 1.35 cm) and a 12 cm steel head with a striking face and a tapered claw.
pub fn hammer(seed: u64) -> (MeshBuilder, RgbImage) {
    let handle_uv = UvRect::new(0.0, 0.0, 1.0, 0.6);
    let head_uv = UvRect::new(0.0, 0.6, 1.0, 1.0);
    let mut g = MeshBuilder::default();
    let path: Vec<Point3<f32>> = (0..=12)
        .map(|i| Point3::new(0.0, 0.0, 0.28 * i as f32 / 12.0))
        .collect();
    let radii: Vec<f32> = (0..=12)
        .map(|i| 0.0135 - 0.002 * (i as f32 / 12.0))
        .collect();
    g.tube(&path, &radii, 24, handle_uv);
    g.lathe(
        &[
            &[(0.0, -0.065), (0.005, -0.065)],
            &[
                (0.005, -0.065),
                (0.011, -0.035),
                (0.0145, -0.01),
                (0.0145, 0.02),
                (0.0145, 0.045),
            ],
            &[(0.0145, 0.045), (0.0155, 0.05)],
            &[(0.0155, 0.05), (0.0, 0.05)],
        ],
        32,
        head_uv,
        &along_x(Vector3::new(0.0, 0.0, 0.29)),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = rng.random::<u32>();
    let wood: Colour = [0.62, 0.42, 0.22];
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    canvas.paint(&handle_uv, |s, t| {
        // Wood grain along the handle, a rubber grip band at the bottom.
        let grain = fbm(
            s * 6.0,
            t * 60.0 + 8.0 * fbm(s * 3.0, t * 3.0, n, 2),
            n ^ 3,
            3,
        );
        if t < 0.3 {
            mix([0.15, 0.15, 0.17], INK, stripe(t, 0.02, 0.5))
        } else {
            shade(wood, 0.7 + 0.5 * grain)
        }
    });
    canvas.paint(&head_uv, |s, t| {
        let brushed = fbm(s * 80.0, t * 4.0, n ^ 9, 3);
        mix(
            shade([0.6, 0.62, 0.66], 0.75 + 0.4 * brushed),
            INK,
            stripe(s, 0.25, 0.04),
        )
    });
    (g, canvas.into_image())
}

/// A kitchen turner: 19 cm handle, a narrowing neck and a 9 x 6 cm blade bent 15 degrees off the handle axis.
pub fn spatula(seed: u64) -> (MeshBuilder, RgbImage) {
    let handle_uv = UvRect::new(0.0, 0.0, 0.5, 1.0);
    let blade_uv = UvRect::new(0.5, 0.0, 1.0, 1.0);
    let mut g = MeshBuilder::default();
    let path: Vec<Point3<f32>> = (0..=16)
        .map(|i| Point3::new(0.0, 0.0, 0.22 * i as f32 / 16.0))
        .collect();
    let radii: Vec<f32> = (0..=16)
        .map(|i| {
            let z = 0.22 * i as f32 / 16.0;
            if z < 0.19 {
                0.0095 - 0.001 * z / 0.19
            } else {
                0.0085 - 0.0045 * (z - 0.19) / 0.03
            }
        })
        .collect();
    g.tube(&path, &radii, 20, handle_uv);
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 15f32.to_radians());
    let blade_centre = Vector3::new(0.0, 0.0, 0.218) + tilt * Vector3::new(0.0, 0.0, 0.045);
    g.cuboid(
        Vector3::new(0.06, 0.003, 0.09),
        &Isometry3::from_parts(Translation3::from(blade_centre), tilt),
        [blade_uv; 6],
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let colour = [0.1, 0.1, 0.1];
    let accent: Colour =
        [[0.85, 0.2, 0.1], [0.1, 0.5, 0.8], [0.2, 0.6, 0.3]][rng.random_range(0..3)];
    let n = rng.random::<u32>();
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    canvas.paint(&handle_uv, |s, t| {
        let rings = stripe(t, 0.05, 0.25);
        mix(
            shade(accent, 0.8 + 0.3 * fbm(s * 20.0, t * 40.0, n, 3)),
            INK,
            rings * if t < 0.7 { 1.0 } else { 0.0 },
        )
    });
    canvas.paint(&blade_uv, |s, t| {
        // Slots and a speckled non-stick coating.
        let slot = stripe(s, 0.2, 0.35) * if (0.3..0.85).contains(&t) { 1.0 } else { 0.0 };
        mix(
            shade(colour, 1.0 + 2.5 * fbm(s * 70.0, t * 70.0, n ^ 4, 2)),
            [0.6, 0.6, 0.6],
            slot,
        )
    });
    (g, canvas.into_image())
}

/// A cordless drill: 17 cm motor body with chuck and bit along +x, a slanted grip and a battery pack at the bottom.
pub fn drill(seed: u64) -> (MeshBuilder, RgbImage) {
    let body_uv = UvRect::new(0.0, 0.5, 0.5, 1.0);
    let grip_uv = UvRect::new(0.5, 0.5, 1.0, 1.0);
    let battery_uv = UvRect::new(0.0, 0.0, 0.5, 0.5);
    let metal_uv = UvRect::new(0.5, 0.0, 1.0, 0.5);
    let mut g = MeshBuilder::default();
    let id = UnitQuaternion::identity();
    g.cuboid(
        Vector3::new(0.17, 0.055, 0.075),
        &Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.175), id),
        [body_uv; 6],
    );
    let grip_tilt = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 12f32.to_radians());
    g.cuboid(
        Vector3::new(0.045, 0.048, 0.12),
        &Isometry3::from_parts(Translation3::new(-0.02, 0.0, 0.09), grip_tilt),
        [grip_uv; 6],
    );
    g.cuboid(
        Vector3::new(0.1, 0.075, 0.045),
        &Isometry3::from_parts(Translation3::new(-0.01, 0.0, 0.0225), id),
        [battery_uv; 6],
    );
    g.lathe(
        &[
            &[(0.0, 0.0), (0.019, 0.0)],
            &[(0.019, 0.0), (0.019, 0.02), (0.013, 0.045)],
            &[(0.013, 0.045), (0.004, 0.05)],
            &[(0.004, 0.05), (0.003, 0.05)],
            &[(0.003, 0.05), (0.003, 0.1), (0.0, 0.108)],
        ],
        32,
        metal_uv,
        &along_x(Vector3::new(0.085, 0.0, 0.185)),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let brand: Colour =
        [[0.95, 0.75, 0.05], [0.05, 0.55, 0.6], [0.85, 0.25, 0.05]][rng.random_range(0..3)];
    let n = rng.random::<u32>();
    let mut canvas = Canvas::new(TEXTURE_SIZE);
    canvas.paint(&body_uv, |s, t| {
        let vents = stripe(s, 0.06, 0.3) * if t > 0.7 && s > 0.6 { 1.0 } else { 0.0 };
        mix(
            shade(brand, 0.85 + 0.25 * fbm(s * 20.0, t * 20.0, n, 3)),
            INK,
            vents,
        )
    });
    let logo = text_lines(rng.random(), [0.1, 0.2, 0.55, 0.45], 2, 0.1);
    canvas.blocks(&body_uv, &logo, INK);
    canvas.paint(&grip_uv, |s, t| {
        let knurl = stripe(s + t, 0.05, 0.5) * stripe(s - t, 0.05, 0.5);
        shade(
            [0.18, 0.18, 0.2],
            0.7 + 0.6 * knurl + 0.3 * fbm(s * 40.0, t * 40.0, n ^ 2, 2),
        )
    });
    canvas.paint(&battery_uv, |s, t| {
        let band = if (0.4..0.55).contains(&t) { 1.0 } else { 0.0 };
        mix(
            shade(
                [0.12, 0.12, 0.13],
                0.8 + 0.4 * fbm(s * 30.0, t * 30.0, n ^ 6, 2),
            ),
            brand,
            band,
        )
    });
    canvas.paint(&metal_uv, |s, t| {
        let jaws = stripe(s, 1.0 / 3.0, 0.15);
        mix(
            shade(
                [0.55, 0.56, 0.6],
                0.7 + 0.5 * fbm(s * 60.0, t * 6.0, n ^ 8, 3),
            ),
            INK,
            jaws,
        )
    });
    (g, canvas.into_image())
}

//! The superquadric family: superellipsoids meshed from a cube.

use super::super::solid::Solid;
use super::parts::{corner, pick, point, tile, turn};
use crate::rng::SeedRng;
use nalgebra::Vector3;
use scene::mesh::Symmetry;
use std::f64::consts::{FRAC_PI_4, PI};

/// Cube coordinate `i` of `0..=n`: equal-angle spacing from exactly -1 to exactly 1, antisymmetric, so that faces
/// meeting at an edge compute the same points.
fn cube_coord(i: usize, n: usize) -> f64 {
    let x = 2 * i as i64 - n as i64;
    let a = x.unsigned_abs() as f64 / n as f64;
    let v = if a >= 1.0 { 1.0 } else { (a * FRAC_PI_4).tan() };
    if x < 0 { -v } else { v }
}

/// A superellipsoid `(|x/a|^(2/e2) + |y/b|^(2/e2))^(e2/e1) + |z/c|^(2/e1) = 1`, meshed by projecting a cube's
/// faces onto it (no poles); each face in its own atlas region. Symmetries: half turns about x, y and z (the
/// semi-axes differ by at least 20 %, so no other).
pub(super) fn superquadric(rng: &mut SeedRng) -> (Solid, Vec<Symmetry>) {
    let big = rng.range(0.05, 0.11);
    let mid = big / rng.range(1.25, 2.0);
    let small = (mid / rng.range(1.2, 1.8)).max(0.012);
    let order = pick(rng, 0, 5);
    let axes = [
        [big, mid, small],
        [big, small, mid],
        [mid, big, small],
        [mid, small, big],
        [small, big, mid],
        [small, mid, big],
    ][order];
    let e1 = rng.range(0.3, 1.6);
    let mut e2 = rng.range(0.3, 1.6);
    if e1 < 0.6 && e2 < 0.6 {
        e2 += 0.6; // not merely a rounded box
    }
    let on_surface = |d: [f64; 3]| {
        let [x, y, z] = d.map(f64::abs);
        let f = (x.powf(2.0 / e2) + y.powf(2.0 / e2)).powf(e2 / e1) + z.powf(2.0 / e1);
        let s = f.powf(-e1 / 2.0);
        point(axes[0] * s * d[0], axes[1] * s * d[1], axes[2] * s * d[2])
    };
    // (outward axis, u axis, v axis) with u x v = outward: component index and sign.
    let faces: [[(usize, f64); 3]; 6] = [
        [(0, 1.0), (1, 1.0), (2, 1.0)],
        [(0, -1.0), (2, 1.0), (1, 1.0)],
        [(1, 1.0), (2, 1.0), (0, 1.0)],
        [(1, -1.0), (0, 1.0), (2, 1.0)],
        [(2, 1.0), (0, 1.0), (1, 1.0)],
        [(2, -1.0), (1, 1.0), (0, 1.0)],
    ];
    let n = 20;
    let mut solid = Solid::default();
    for (k, [(ni, ns), (ui, us), (vi, vs)]) in faces.into_iter().enumerate() {
        let uv = tile(k);
        solid.grid(n + 1, n + 1, |i, j| {
            let mut d = [0.0; 3];
            d[ni] = ns;
            d[ui] = us * cube_coord(i, n);
            d[vi] = vs * cube_coord(j, n);
            corner(
                on_surface(d),
                uv.map(i as f32 / n as f32, j as f32 / n as f32),
            )
        });
    }
    let symmetries = vec![
        turn(Vector3::x(), PI),
        turn(Vector3::y(), PI),
        turn(Vector3::z(), PI),
    ];
    (solid, symmetries)
}

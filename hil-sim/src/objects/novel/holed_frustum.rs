//! The holed frustum family: round or polygonal frustums with an axial through hole.

use super::super::solid::Solid;
use super::parts::{AROUND, corner, pick, point, tile, turns_about_z};
use crate::rng::SeedRng;
use nalgebra::{Point3, Vector3};
use scene::mesh::Symmetry;
use std::f64::consts::TAU;

/// A frustum, `round` or 5-, 6- or 8-sided, 5 to 14 cm tall, its top 45-80 % of its base, with an axial round
/// hole through it (walls at least 8 mm). Outside, top, hole and bottom in atlas regions 0 to 3. Symmetries: any
/// turn about z (round) or the turns by `2 pi k / sides`.
pub(super) fn holed_frustum(rng: &mut SeedRng, round: bool) -> (Solid, Vec<Symmetry>) {
    let sides = if round { 0 } else { [5, 6, 8][pick(rng, 0, 2)] };
    let bottom = rng.range(0.035, 0.08);
    let top = bottom * rng.range(0.45, 0.8);
    let height = rng.range(0.05, 0.14);
    let hole = (top * rng.range(0.3, 0.6)).min(top - 0.008).max(0.006);
    let per_side = if sides == 0 {
        1
    } else {
        AROUND.div_ceil(sides)
    };
    let m = if sides == 0 { AROUND } else { sides * per_side };
    let outline = |j: usize, r: f64| -> [f64; 2] {
        let j = j % m;
        if sides == 0 {
            let a = TAU * j as f64 / m as f64;
            return [r * a.cos(), r * a.sin()];
        }
        let (s, f) = (j / per_side, (j % per_side) as f64 / per_side as f64);
        let (a0, a1) = (
            TAU * s as f64 / sides as f64,
            TAU * (s + 1) as f64 / sides as f64,
        );
        [
            r * (a0.cos() + (a1.cos() - a0.cos()) * f),
            r * (a0.sin() + (a1.sin() - a0.sin()) * f),
        ]
    };
    let circle = |j: usize, r: f64| {
        let a = TAU * (j % m) as f64 / m as f64;
        [r * a.cos(), r * a.sin()]
    };
    let h = height / 2.0;
    let ring = |pts: &dyn Fn(usize) -> [f64; 2], z: f64| -> Vec<Point3<f32>> {
        (0..m)
            .map(|j| {
                let p = pts(j);
                point(p[0], p[1], z)
            })
            .collect()
    };
    let outer_bottom = ring(&|j| outline(j, bottom), -h);
    let outer_top = ring(&|j| outline(j, top), h);
    let inner_top = ring(&|j| circle(j, hole), h);
    let inner_bottom = ring(&|j| circle(j, hole), -h);
    let mut solid = Solid::default();
    // Each band: from one ring to the next, outside on the side of (along the rings) x (across).
    let bands = [
        (&outer_bottom, &outer_top),
        (&outer_top, &inner_top),
        (&inner_top, &inner_bottom),
        (&inner_bottom, &outer_bottom),
    ];
    for (k, (from, to)) in bands.into_iter().enumerate() {
        let uv = tile(k);
        solid.grid(m + 1, 2, |j, across| {
            let p = if across == 0 { from[j % m] } else { to[j % m] };
            corner(p, uv.map(j as f32 / m as f32, across as f32))
        });
    }
    let symmetries = if sides == 0 {
        vec![Symmetry::Continuous {
            axis: Vector3::z_axis(),
            offset: Point3::origin(),
        }]
    } else {
        turns_about_z(sides)
    };
    (solid, symmetries)
}

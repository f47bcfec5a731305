//! The twisted prism family: irregular prisms twisted and tapered along their length.

use super::super::solid::Solid;
use super::extrude::{Ring, extrude};
use super::parts::{pick, sign};
use crate::rng::SeedRng;
use scene::mesh::Symmetry;
use std::f64::consts::TAU;

/// An irregular polygon of 3 to 7 corners (angles and radii jittered), each side split in three, extruded 9 to
/// 20 cm while turning by 45 to 150 degrees and shrinking to 50-95 %, with bevelled ends. No symmetries.
pub(super) fn twisted_prism(rng: &mut SeedRng) -> (Solid, Vec<Symmetry>) {
    let corners = pick(rng, 3, 7);
    let radius = rng.range(0.025, 0.05);
    let length = rng.range(0.09, 0.2);
    let twist = sign(rng) * rng.range(45.0, 150.0).to_radians();
    let taper = rng.range(0.5, 0.95);
    let vertices: Vec<[f64; 2]> = (0..corners)
        .map(|c| {
            // Gaps between corner angles stay below pi, so the outline is star-shaped about the origin.
            let a = TAU * (c as f64 + rng.range(-0.2, 0.2)) / corners as f64;
            let r = radius * rng.range(0.65, 1.0);
            [r * a.cos(), r * a.sin()]
        })
        .collect();
    let split = 3;
    let profile: Vec<[f64; 2]> = (0..corners * split)
        .map(|k| {
            let (a, b) = (vertices[k / split], vertices[(k / split + 1) % corners]);
            let f = (k % split) as f64 / split as f64;
            [a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f]
        })
        .collect();
    let bevel = rng.range(0.004, 0.008);
    let k_end = 1.0 - rng.range(0.003, 0.006) / radius;
    let steps = 20;
    let h = length / 2.0;
    let mut rings = vec![Ring {
        z: -h,
        scale: k_end,
        twist: 0.0,
    }];
    for s in 0..=steps {
        let f = s as f64 / steps as f64;
        rings.push(Ring {
            z: -h + bevel + (length - 2.0 * bevel) * f,
            scale: 1.0 + (taper - 1.0) * f,
            twist: twist * f,
        });
    }
    rings.push(Ring {
        z: h,
        scale: taper * k_end,
        twist,
    });
    (extrude(&profile, [0.0, 0.0], &rings), vec![])
}

//! The star prism family: bevelled prisms over regular stars.

use super::super::solid::Solid;
use super::extrude::{bevelled, extrude};
use super::parts::{pick, turn, turns_about_z};
use crate::rng::SeedRng;
use nalgebra::Vector3;
use scene::mesh::Symmetry;
use std::f64::consts::PI;

/// A bevelled prism over a regular star of `n` points (tips on the x axis and every `2 pi / n`). Symmetries: the
/// dihedral group, turns by `2 pi k / n` about z and half turns about the `n` in-plane axes through tips and notches.
pub(super) fn star_prism(rng: &mut SeedRng) -> (Solid, Vec<Symmetry>) {
    let n = pick(rng, 4, 8);
    let outer = rng.range(0.045, 0.1);
    let inner = outer * rng.range(0.4, 0.7);
    let thickness = rng.range(0.02, 0.05);
    let bevel = thickness * rng.range(0.12, 0.25);
    let inset = rng.range(0.003, 0.007);
    let profile: Vec<[f64; 2]> = (0..2 * n)
        .map(|k| {
            let a = PI * k as f64 / n as f64;
            let r = if k % 2 == 0 { outer } else { inner };
            [r * a.cos(), r * a.sin()]
        })
        .collect();
    let rings = bevelled(thickness, bevel, inset, outer);
    let mut symmetries = turns_about_z(n);
    for m in 0..n {
        let a = PI * m as f64 / n as f64;
        symmetries.push(turn(Vector3::new(a.cos(), a.sin(), 0.0), PI));
    }
    (extrude(&profile, [0.0, 0.0], &rings), symmetries)
}

//! The bracket family: L, T and cross outlines of bars, extruded and bevelled.

use super::super::solid::Solid;
use super::extrude::{bevelled, extrude, reach};
use super::parts::sign;
use crate::rng::SeedRng;
use scene::mesh::Symmetry;

/// An outline (counter-clockwise seen from +z) and a point it is star-shaped about.
type Outline = (Vec<[f64; 2]>, [f64; 2]);

/// An L, T or cross of bars (`shape` 0, 1, 2; never symmetric: unequal arms, an off-centre stem, unequal widths)
/// extruded 2.5 to 6 cm and bevelled. No symmetries.
pub(super) fn bracket(rng: &mut SeedRng, shape: usize) -> (Solid, Vec<Symmetry>) {
    let depth = rng.range(0.025, 0.06);
    let w1 = rng.range(0.025, 0.045);
    // Widths differ by at least 8 mm, so no diagonal mirror maps one bar onto the other.
    let w2 = if rng.uniform() < 0.5 {
        w1 + rng.range(0.008, 0.015)
    } else {
        (w1 - rng.range(0.008, 0.012)).max(0.017)
    };
    let (profile, kernel) = match shape {
        0 => l_outline(rng, w1, w2),
        1 => t_outline(rng, w1, w2),
        _ => cross_outline(rng, w1, w2),
    };
    let bevel = depth * rng.range(0.1, 0.18);
    let rings = bevelled(
        depth,
        bevel,
        rng.range(0.002, 0.004),
        reach(&profile, kernel),
    );
    (extrude(&profile, kernel, &rings), vec![])
}

/// An L: a bar of width `w1` along x and one of width `w2` along y, of unequal lengths.
fn l_outline(rng: &mut SeedRng, w1: f64, w2: f64) -> Outline {
    let a = rng.range(0.1, 0.2);
    let b = a * rng.range(0.45, 0.8); // arms differ by at least 2 cm
    (
        vec![[0.0, 0.0], [a, 0.0], [a, w1], [w2, w1], [w2, b], [0.0, b]],
        [w2 / 2.0, w1 / 2.0],
    )
}

/// A T: a top bar of width `w1` and a stem of width `w2` off its centre.
fn t_outline(rng: &mut SeedRng, w1: f64, w2: f64) -> Outline {
    let a = rng.range(0.11, 0.2);
    let b = rng.range(0.07, 0.15);
    let room = a / 2.0 - w2 / 2.0 - 0.005;
    let s = sign(rng) * room * rng.range(0.25, 0.6);
    (
        vec![
            [s - w2 / 2.0, 0.0],
            [s + w2 / 2.0, 0.0],
            [s + w2 / 2.0, b - w1],
            [a / 2.0, b - w1],
            [a / 2.0, b],
            [-a / 2.0, b],
            [-a / 2.0, b - w1],
            [s - w2 / 2.0, b - w1],
        ],
        [s, b - w1 / 2.0],
    )
}

/// A cross: a bar of width `w1` along x and one of width `w2` along y, crossing at the origin.
fn cross_outline(rng: &mut SeedRng, w1: f64, w2: f64) -> Outline {
    // Arms from the crossing: each pair differs by at least 1.5 cm.
    let arm = |rng: &mut SeedRng, w: f64| {
        let short = w / 2.0 + rng.range(0.02, 0.04);
        let long = short + rng.range(0.015, 0.05);
        if rng.uniform() < 0.5 {
            (short, long)
        } else {
            (long, short)
        }
    };
    let (a1, a2) = arm(rng, w2);
    let (b1, b2) = arm(rng, w1);
    let (h1, h2) = (w1 / 2.0, w2 / 2.0);
    (
        vec![
            [-h2, -b1],
            [h2, -b1],
            [h2, -h1],
            [a2, -h1],
            [a2, h1],
            [h2, h1],
            [h2, b2],
            [-h2, b2],
            [-h2, h1],
            [-a1, h1],
            [-a1, -h1],
            [-h2, -h1],
        ],
        [0.0, 0.0],
    )
}

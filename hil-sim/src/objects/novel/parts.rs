//! Small pieces every family uses: atlas regions, turns about axes through the origin, corners and random picks.

use super::super::builder::UvRect;
use super::super::solid::Corner;
use crate::rng::SeedRng;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::mesh::Symmetry;
use std::f64::consts::TAU;

/// Segments around every round outline (torus tube, round frustum); the major circle of a full torus has 64.
pub(super) const AROUND: usize = 48;

/// A turn by `angle` about `axis` through the origin.
pub(super) fn turn(axis: Vector3<f64>, angle: f64) -> Symmetry {
    Symmetry::Discrete(Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_scaled_axis(axis.normalize() * angle),
    ))
}

/// The `n - 1` turns by multiples of `2 pi / n` about z.
pub(super) fn turns_about_z(n: usize) -> Vec<Symmetry> {
    (1..n)
        .map(|k| turn(Vector3::z(), TAU * k as f64 / n as f64))
        .collect()
}

/// Region `k` (0 to 5) of the atlas: three columns, two rows.
pub(super) fn tile(k: usize) -> UvRect {
    let (c, r) = ((k % 3) as f32, (k / 3 % 2) as f32);
    UvRect::new(c / 3.0, r / 2.0, (c + 1.0) / 3.0, (r + 1.0) / 2.0)
}

/// A solid corner at `p` with texture coordinates `uv`.
pub(super) fn corner(p: Point3<f32>, uv: [f32; 2]) -> Corner {
    Corner { p, uv }
}

/// A single-precision point from double-precision coordinates.
pub(super) fn point(x: f64, y: f64, z: f64) -> Point3<f32> {
    Point3::new(x as f32, y as f32, z as f32)
}

/// A whole number in `lo..=hi`.
pub(super) fn pick(rng: &mut SeedRng, lo: usize, hi: usize) -> usize {
    (lo + (rng.uniform() * (hi - lo + 1) as f64) as usize).min(hi)
}

/// A random sign.
pub(super) fn sign(rng: &mut SeedRng) -> f64 {
    if rng.uniform() < 0.5 { -1.0 } else { 1.0 }
}

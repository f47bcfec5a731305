//! The prism sweep shared by the star prism, bracket and twisted prism families: a star-shaped profile carried
//! through scaled and turned cross-sections and closed by fans.

use super::super::solid::{Corner, Solid};
use super::parts::{corner, point, tile};
use nalgebra::Point3;

/// One cross-section of an extrusion: the profile scaled by `scale` about its kernel point, turned by `twist`
/// (radians) about it, at height `z`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Ring {
    /// Height, metres.
    pub z: f64,
    /// Scale of the profile about its kernel point.
    pub scale: f64,
    /// Turn about the kernel point, radians.
    pub twist: f64,
}

/// A prism over `profile` (a simple polygon, counter-clockwise seen from +z, star-shaped about `kernel`: every
/// vertex seen from it) through `rings` (bottom to top), closed by fans from the kernel point. Sides in atlas
/// region 0 (`u` along the outline, `v` up), bottom and top in regions 1 and 2.
pub(super) fn extrude(profile: &[[f64; 2]], kernel: [f64; 2], rings: &[Ring]) -> Solid {
    let m = profile.len();
    let at: Vec<Vec<Point3<f32>>> = rings
        .iter()
        .map(|r| {
            let (s, c) = r.twist.sin_cos();
            profile
                .iter()
                .map(|v| {
                    let (x, y) = ((v[0] - kernel[0]) * r.scale, (v[1] - kernel[1]) * r.scale);
                    point(kernel[0] + c * x - s * y, kernel[1] + s * x + c * y, r.z)
                })
                .collect()
        })
        .collect();
    let mut along = vec![0.0f64; m + 1];
    for j in 0..m {
        let (a, b) = (profile[j], profile[(j + 1) % m]);
        along[j + 1] = along[j] + (b[0] - a[0]).hypot(b[1] - a[1]);
    }
    let total = along[m].max(1e-12);
    let (z0, z1) = (rings[0].z, rings[rings.len() - 1].z);
    let side = tile(0);
    let mut solid = Solid::default();
    solid.grid(m + 1, rings.len(), |j, k| {
        corner(
            at[k][j % m],
            side.map(
                (along[j] / total) as f32,
                ((rings[k].z - z0) / (z1 - z0)) as f32,
            ),
        )
    });
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in profile {
        for a in 0..2 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12);
    for (end, region) in [(0, tile(1)), (rings.len() - 1, tile(2))] {
        let cap = |p: Point3<f32>| {
            corner(
                p,
                region.map(
                    ((f64::from(p.x) - lo[0]) / span) as f32,
                    ((f64::from(p.y) - lo[1]) / span) as f32,
                ),
            )
        };
        let mut ring: Vec<Corner> = (0..=m).map(|j| cap(at[end][j % m])).collect();
        if end == 0 {
            ring.reverse(); // the bottom faces -z
        }
        solid.fan(cap(point(kernel[0], kernel[1], rings[end].z)), &ring);
    }
    solid
}

/// The largest distance of a profile vertex from the kernel point.
pub(super) fn reach(profile: &[[f64; 2]], kernel: [f64; 2]) -> f64 {
    profile
        .iter()
        .map(|v| (v[0] - kernel[0]).hypot(v[1] - kernel[1]))
        .fold(0.0, f64::max)
}

/// Straight-sided rings with a bevel of `bevel` metres (height) at both ends that insets the outline by up to
/// `inset` metres.
pub(super) fn bevelled(height: f64, bevel: f64, inset: f64, reach: f64) -> Vec<Ring> {
    let k = 1.0 - inset / reach.max(1e-9);
    let h = height / 2.0;
    [(-h, k), (-h + bevel, 1.0), (h - bevel, 1.0), (h, k)]
        .into_iter()
        .map(|(z, scale)| Ring {
            z,
            scale,
            twist: 0.0,
        })
        .collect()
}

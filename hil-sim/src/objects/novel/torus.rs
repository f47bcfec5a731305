//! The torus family: whole tori and C-ring segments with an elliptical tube.

use super::super::solid::{Corner, Solid};
use super::parts::{AROUND, corner, point, tile, turn};
use crate::rng::SeedRng;
use nalgebra::{Point3, Vector3};
use scene::mesh::Symmetry;
use std::f64::consts::{PI, TAU};

/// A torus of major radius `R`, tube semi-axes `r1` (in the plane) and `r2` (along z), `whole` or a segment of 200
/// to 300 degrees symmetric about +x with flat ends. Tube in atlas region 0, ends in 1 and 2. Symmetries: any turn
/// about z and a half turn about x (whole); the half turn about x (segment).
pub(super) fn torus(rng: &mut SeedRng, whole: bool) -> (Solid, Vec<Symmetry>) {
    let big = rng.range(0.04, 0.085);
    let r1 = rng.range(0.012, 0.026);
    let r2 = (r1 * rng.range(0.7, 1.4)).max(0.011);
    let sweep = if whole {
        TAU
    } else {
        rng.range(200.0, 300.0).to_radians()
    };
    let (major, minor) = (if whole { 64 } else { 48 }, AROUND / 2);
    let angle = |i: usize| {
        if whole {
            TAU * (i % major) as f64 / major as f64
        } else {
            -sweep / 2.0 + sweep * i as f64 / major as f64
        }
    };
    let at = |i: usize, j: usize| {
        let (phi, theta) = (angle(i), TAU * (j % minor) as f64 / minor as f64);
        let r = big + r1 * theta.cos();
        point(r * phi.cos(), r * phi.sin(), r2 * theta.sin())
    };
    let uv = tile(0);
    let mut solid = Solid::default();
    solid.grid(major + 1, minor + 1, |i, j| {
        corner(
            at(i, j),
            uv.map(i as f32 / major as f32, j as f32 / minor as f32),
        )
    });
    let mut symmetries = vec![turn(Vector3::x(), PI)];
    if whole {
        symmetries.push(Symmetry::Continuous {
            axis: Vector3::z_axis(),
            offset: Point3::origin(),
        });
    } else {
        for (i, region) in [(0, tile(1)), (major, tile(2))] {
            let cap = |j: usize| {
                let theta = TAU * j as f64 / minor as f64;
                corner(
                    at(i, j),
                    region.map(
                        (0.5 + 0.5 * theta.cos()) as f32,
                        (0.5 + 0.5 * theta.sin()) as f32,
                    ),
                )
            };
            let mut ring: Vec<Corner> = (0..=minor).map(cap).collect();
            if i == major {
                ring.reverse(); // the far end faces the other way
            }
            let phi = angle(i);
            let centre = corner(
                point(big * phi.cos(), big * phi.sin(), 0.0),
                region.map(0.5, 0.5),
            );
            solid.fan(centre, &ring);
        }
    }
    (solid, symmetries)
}

//! The safety net's motion check at one depth frame (`recon::MovingNeighbourhood`): keeping the previous frame's
//! moved surfaces around the object and scoring three poses (the estimate and the two depth-only candidates), on a
//! 848x480 depth frame where an object-and-hand block moved 6 cm in front of a wall near enough to be carried too:
//! the carried depth is full (about 12k points), the worst case.

// `criterion_group!` defines undocumented public functions.
#![allow(missing_docs)]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Point3};
use scene::geometry::PinholeCamera;
use std::hint::black_box;
use tracker::recon::{CarriedDepth, DepthRig, MovingNeighbourhood};

const W: usize = 848;
const H: usize = 480;

/// A wall at 0.8 m with a 160 x 200 pixel block at 0.6 m, its left edge at `u0`.
fn frame(u0: usize) -> DepthFrame {
    let mut depth_m = vec![0.8f32; W * H];
    for v in 140..340 {
        for u in u0..u0 + 160 {
            depth_m[v * W + u] = 0.6;
        }
    }
    DepthFrame {
        index: 0,
        width: W as u32,
        height: H as u32,
        depth_m,
    }
}

fn motion_check(c: &mut Criterion) {
    let camera =
        PinholeCamera::new(420.0, 420.0, 423.5, 239.5, W as u32, H as u32).expect("camera");
    let rig = DepthRig {
        camera,
        event_from_depth: Isometry3::identity(),
    };
    let (before, after) = (frame(300), frame(360));
    let shift = 60.0 * 0.6 / 420.0;
    let anchor = Isometry3::translation(0.0, 0.0, 0.6);
    let poses = [
        Isometry3::translation(shift, 0.0, 0.6),
        Isometry3::translation(shift + 0.04, 0.0, 0.6),
        Isometry3::translation(shift, 0.0, 0.58),
    ];
    let mut carried = CarriedDepth::new();
    carried.register(&before, &rig, &Point3::new(0.0, 0.0, 0.6), 0.3, 0);
    let mut neighbourhood = MovingNeighbourhood::new();
    c.bench_function("motion_check_capture_and_three_poses", |b| {
        b.iter(|| {
            neighbourhood.capture(&carried, &anchor, &after, &rig);
            let mut sum = 0.0;
            for p in &poses {
                sum += neighbourhood
                    .motion_agreement(p, &after, &rig, 0.025)
                    .unwrap_or(0.0);
            }
            black_box(sum)
        })
    });
    println!(
        "carried points {}, kept after capture {}",
        carried.len(),
        neighbourhood.len()
    );
}

criterion_group!(benches, motion_check);
criterion_main!(benches);

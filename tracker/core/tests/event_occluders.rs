//! The event term leaves another tracked object's events to that object where it hides this one: events on an
//! occluder's rendered silhouette are dropped, events on an object behind are kept.

#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../../scene/tests/common/mod.rs"]
mod common;

use drivers::event::CdEvent;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use scene::geometry::Roi;
use scene::render::{CpuRenderer, RenderTarget, Renderer, Scene, SceneObject};
use std::sync::Arc;
use tracker::recon::{EventSurface, IntensityFilterConfig};
use tracker::refine::{EventEdges, EventTerm};

/// Kept event bins in the ROI of cube 1 at 0.5 m, with cube 2 beside it at `other_z`, every pixel of the image
/// having fired; and the number of ROI pixels showing cube 2.
fn kept_bins(other_z: f64, occluder_z: f32) -> (usize, usize) {
    let cam = common::vga();
    let mut renderer = CpuRenderer::new();
    let mesh = renderer.add_mesh(Arc::new(common::cube(0.1))).unwrap();
    let turn = UnitQuaternion::from_euler_angles(0.4, -0.3, 0.2);
    let this = Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.5), turn);
    let other = Isometry3::from_parts(Translation3::new(0.07, 0.0, other_z), turn);
    let scene = [
        SceneObject {
            mesh,
            pose: this,
            id: 1,
        },
        SceneObject {
            mesh,
            pose: other,
            id: 2,
        },
    ];
    let roi = Roi::around_object(&cam, &(this * Point3::origin()), 0.17, 1.2, 160).unwrap();
    let mut target = RenderTarget::new();
    renderer
        .render(
            &Scene::objects(&scene).geometry_only(),
            &cam.crop(&roi),
            &mut target,
        )
        .unwrap();
    let events: Vec<CdEvent> = (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .map(|(x, y)| CdEvent {
            t_us: 10_000,
            x: x as u16,
            y: y as u16,
            polarity: true,
        })
        .collect();
    let mut surface = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    surface.integrate(&events);
    let mut edges = EventEdges::default();
    edges.collect(
        &EventTerm::default(),
        &surface,
        &roi,
        target.mask(),
        target.depth(),
        occluder_z,
        1,
        10_000,
        2_000,
        400,
        None,
    );
    let shown = target.mask().iter().filter(|&&l| l == 2).count();
    (edges.stats().bins, shown)
}

#[test]
fn events_on_a_nearer_object_are_left_to_it() {
    // Nothing counts as an occluder: every bin is kept.
    let (all, shown) = kept_bins(0.35, f32::NEG_INFINITY);
    assert!(shown > 1000, "the other cube shows on {shown} ROI pixels");
    // The other cube 15 cm nearer hides part of this one's ROI: its bins go, all of them and only them.
    let (kept, shown_near) = kept_bins(0.35, 0.5);
    assert_eq!(shown_near, shown);
    assert_eq!(
        kept,
        all - shown,
        "kept {kept} of {all}, the occluder shows on {shown}"
    );
    // 15 cm behind, it is no occluder: this cube's leading edge sweeps over it, so its bins stay.
    let (all_behind, shown_behind) = kept_bins(0.65, f32::NEG_INFINITY);
    let (kept_behind, _) = kept_bins(0.65, 0.5);
    assert!(shown_behind > 500, "{shown_behind}");
    assert_eq!(kept_behind, all_behind);
}

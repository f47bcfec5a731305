//! The outline shift search on the aperture problem: a long bar moving sideways fires events along its long
//! edges only, so every shift along its length scores alike. Told the direction of motion, the search keeps the
//! outline where it is along the bar and moves it only across.

#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../../scene/tests/common/mod.rs"]
mod common;

use drivers::event::CdEvent;
use nalgebra::{Isometry3, Point3, Translation3, Vector3};
use scene::geometry::Roi;
use scene::render::{CpuRenderer, RenderTarget, Renderer, Scene, SceneObject};
use std::sync::Arc;
use tracker::recon::{EventSurface, IntensityFilterConfig};
use tracker::refine::{EventEdges, EventTerm, ModelView};

/// The searched shift (full-image pixels) of an upright 2 x 16 cm bar at 0.5 m whose hypothesis lags 6 mm to the
/// left of a strip of events as wide as the bar at its true place and as tall as the image.
fn searched_shift(term: &EventTerm, motion_dir: Option<[f64; 2]>) -> Option<[f64; 2]> {
    let cam = common::vga();
    let mut renderer = CpuRenderer::new();
    let mesh = renderer
        .add_mesh(Arc::new(common::cuboid(Vector3::new(0.02, 0.16, 0.02))))
        .unwrap();
    let hypothesis = Isometry3::from_parts(Translation3::new(-0.006, 0.0, 0.5), Default::default());
    // Columns the bar covers at its true place.
    let half_px = 0.01 * cam.fx / 0.5;
    let (x0, x1) = (
        (cam.cx - half_px).round() as u16,
        (cam.cx + half_px).round() as u16,
    );
    let events: Vec<CdEvent> = (0..cam.height as u16)
        .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
        .map(|(x, y)| CdEvent {
            t_us: 10_000,
            x,
            y,
            polarity: true,
        })
        .collect();
    let mut surface = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    surface.integrate(&events);
    // A wide ROI, so that no shift in range moves the bar's ends out of it.
    let roi = Roi::around_object(&cam, &(hypothesis * Point3::origin()), 0.2, 1.2, 160).unwrap();
    let roi_cam = cam.crop(&roi);
    let mut target = RenderTarget::new();
    let scene = [SceneObject {
        mesh,
        pose: hypothesis,
        id: 1,
    }];
    renderer
        .render(
            &Scene::objects(&scene).geometry_only(),
            &roi_cam,
            &mut target,
        )
        .unwrap();
    let mut view = ModelView::with_capacity(600, 200);
    view.extract(&target, &roi_cam, 1, &hypothesis, 600, 200);
    let mut edges = EventEdges::default();
    edges.collect(
        term,
        &surface,
        &roi,
        target.mask(),
        target.depth(),
        f32::INFINITY,
        1,
        10_000,
        2_000,
        400,
        None,
    );
    edges.search_shift(term, &view, &hypothesis, &cam, 20.0, motion_dir)
}

#[test]
fn a_bar_moving_sideways_is_shifted_across_only() {
    let term = EventTerm {
        search_aperture_tolerance: 0.05,
        ..EventTerm::default()
    };
    // 6 mm at 0.5 m is 6.3 px to the right.
    let [du, dv] = searched_shift(&term, Some([1.0, 0.0])).expect("a shift");
    assert!((du - 6.3).abs() < 3.0, "du {du}");
    // Within the fine search's two bins (3 px here) of no shift along the bar; it keeps the first of equal
    // scores, so it may still move that far.
    assert!(dv.abs() < 6.0, "dv {dv}");
    // Without the direction of motion, or with the tie-break off, any shift along the bar scores as well as
    // the right one, and the scan takes the first of them: far up the bar.
    for (term, dir) in [
        (term, None),
        (
            EventTerm {
                search_aperture_tolerance: 0.0,
                ..term
            },
            Some([1.0, 0.0]),
        ),
    ] {
        let [du, dv] = searched_shift(&term, dir).expect("a shift");
        assert!((du - 6.3).abs() < 3.0, "du {du}");
        assert!(
            dv < -15.0,
            "dv {dv}: the scan no longer takes the first of equal scores"
        );
    }
}

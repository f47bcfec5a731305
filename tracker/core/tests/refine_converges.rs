//! Render-and-compare refinement converges: the depth term alone recovers a perturbed pose of a cube from a
//! depth image rendered at the true pose, and the event term moves a lagging silhouette onto recent events.

#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../../scene/tests/common/mod.rs"]
mod common;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use scene::geometry::Roi;
use scene::render::{CpuRenderer, RenderTarget, Renderer, Scene, SceneObject};
use std::sync::Arc;
use tracker::recon::DepthImage;
use tracker::refine::{DepthTerm, ModelView, NormalEquations, StepBounds, apply_step, solve_step};

fn truth() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.02, -0.01, 0.5),
        UnitQuaternion::from_euler_angles(0.4, -0.3, 0.2),
    )
}

/// The 160x160 ROI of the 0.17 m-diameter test object around `pose` in the VGA camera, with the object (id 1)
/// rendered there into `target` (geometry only: refinement reads depth, normals and mask). Returns the ROI and its
/// camera.
fn render_roi_at(
    renderer: &mut CpuRenderer,
    id: scene::render::MeshId,
    pose: &Isometry3<f64>,
    target: &mut RenderTarget,
) -> (Roi, scene::geometry::PinholeCamera) {
    let cam = common::vga();
    let roi =
        Roi::around_object(&cam, &(pose * nalgebra::Point3::origin()), 0.17, 1.2, 160).unwrap();
    let roi_cam = cam.crop(&roi);
    let scene = [SceneObject {
        mesh: id,
        pose: *pose,
        id: 1,
    }];
    renderer
        .render(&Scene::objects(&scene).geometry_only(), &roi_cam, target)
        .unwrap();
    (roi, roi_cam)
}

fn refine_depth(start: Isometry3<f64>, iterations: usize) -> Isometry3<f64> {
    let cam = common::vga();
    let mesh = Arc::new(common::cube(0.1));
    let mut renderer = CpuRenderer::new();
    let id = renderer.add_mesh(mesh.clone()).unwrap();
    let center = Vector3::zeros();
    let roi = Roi::around_object(
        &cam,
        &(truth() * nalgebra::Point3::origin()),
        0.17,
        1.2,
        160,
    )
    .unwrap();
    let roi_cam = cam.crop(&roi);
    // Measured depth: the cube at the true pose.
    let mut measured = RenderTarget::new();
    let truth_scene = [SceneObject {
        mesh: id,
        pose: truth(),
        id: 1,
    }];
    renderer
        .render(&Scene::objects(&truth_scene), &roi_cam, &mut measured)
        .unwrap();
    let depth = DepthImage {
        width: roi_cam.width,
        height: roi_cam.height,
        z: measured.depth().to_vec(),
    };
    let term = DepthTerm::default();
    let bounds = StepBounds {
        max_rotation: 20f64.to_radians(),
        max_translation: 0.05,
    };
    let mut pose = start;
    let mut target = RenderTarget::new();
    let mut view = ModelView::with_capacity(600, 200);
    for _ in 0..iterations {
        // Re-render at the hypothesis each round (as the tracker does every tick).
        let scene = [SceneObject {
            mesh: id,
            pose,
            id: 1,
        }];
        renderer
            .render(&Scene::objects(&scene), &roi_cam, &mut target)
            .unwrap();
        view.extract(&target, &roi_cam, 1, &pose, 600, 200);
        for _ in 0..3 {
            let mut ne = NormalEquations::default();
            term.accumulate(&view, &pose, &center, &roi_cam, &depth, &mut ne);
            let Some(step) = solve_step(&ne, 1e-3, &bounds) else {
                break;
            };
            pose = apply_step(&pose, &center, &step);
        }
    }
    pose
}

fn errors(a: &Isometry3<f64>, b: &Isometry3<f64>) -> (f64, f64) {
    (
        (a.translation.vector - b.translation.vector).norm(),
        a.rotation.angle_to(&b.rotation).to_degrees(),
    )
}

#[test]
fn depth_term_recovers_a_perturbed_pose() {
    for (axis, deg, shift) in [
        (Vector3::x(), 5.0, Vector3::new(0.005, 0.0, 0.0)),
        (Vector3::y(), -8.0, Vector3::new(0.0, -0.008, 0.004)),
        (
            Vector3::new(1.0, 1.0, 0.0).normalize(),
            10.0,
            Vector3::new(0.01, 0.0, -0.01),
        ),
    ] {
        let t = truth();
        let start = Isometry3::from_parts(
            Translation3::from(t.translation.vector + shift),
            UnitQuaternion::from_scaled_axis(axis * f64::to_radians(deg)) * t.rotation,
        );
        let (e_t0, e_r0) = errors(&start, &t);
        let end = refine_depth(start, 4);
        let (e_t, e_r) = errors(&end, &t);
        assert!(
            e_t < 1e-3 && e_r < 0.5,
            "from {e_t0:.4} m {e_r0:.2} deg to {e_t:.4} m {e_r:.2} deg"
        );
    }
}

/// Events of a moving textured cube at the true pose (every covered pixel fired at 10 ms), plus `extra` pixels
/// (e.g. a hand holding it).
fn cube_events(
    extra: &dyn Fn(u32, u32) -> bool,
) -> (
    tracker::recon::EventSurface,
    CpuRenderer,
    scene::render::MeshId,
) {
    use drivers::event::CdEvent;
    use tracker::recon::{EventSurface, IntensityFilterConfig};
    let cam = common::vga();
    let mut renderer = CpuRenderer::new();
    let id = renderer.add_mesh(Arc::new(common::cube(0.1))).unwrap();
    let mut full = RenderTarget::new();
    let scene = [SceneObject {
        mesh: id,
        pose: truth(),
        id: 1,
    }];
    renderer
        .render(&Scene::objects(&scene), &cam, &mut full)
        .unwrap();
    let events: Vec<CdEvent> = (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .filter(|&(x, y)| full.mask()[(y * cam.width + x) as usize] == 1 || extra(x, y))
        .map(|(x, y)| CdEvent {
            t_us: 10_000,
            x: x as u16,
            y: y as u16,
            polarity: true,
        })
        .collect();
    let mut surface = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    surface.integrate(&events);
    (surface, renderer, id)
}

/// Refines `start` with the event term alone (`rounds` re-renders) and returns the final pose.
fn refine_events(
    term: &tracker::refine::EventTerm,
    surface: &tracker::recon::EventSurface,
    renderer: &mut CpuRenderer,
    id: scene::render::MeshId,
    start: Isometry3<f64>,
    speed: f64,
    rounds: usize,
) -> Isometry3<f64> {
    use tracker::refine::EventEdges;
    let cam = common::vga();
    let center = Vector3::zeros();
    let bounds = StepBounds {
        max_rotation: 0.2,
        max_translation: 0.02,
    };
    let mut pose = start;
    let mut target = RenderTarget::new();
    let mut view = ModelView::with_capacity(600, 200);
    let mut edges = EventEdges::default();
    // Moving right at `speed` m/s: sets each contour point's expected band of events in the window.
    let motion = nalgebra::Vector6::new(speed, 0.0, 0.0, 0.0, 0.0, 0.0);
    for _ in 0..rounds {
        let (roi, roi_cam) = render_roi_at(renderer, id, &pose, &mut target);
        view.extract(&target, &roi_cam, 1, &pose, 600, 200);
        edges.collect(
            term,
            surface,
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
        edges.associate(term, &view, &pose, &center, &cam, &motion, 0.002);
        let mut ne = NormalEquations::default();
        edges.accumulate(term, &view, &pose, &center, &cam, &mut ne);
        // A weak prior keeps the unobserved directions put.
        for k in 0..6 {
            ne.h[(k, k)] += 1e3;
        }
        let Some(step) = solve_step(&ne, 1e-3, &bounds) else {
            break;
        };
        pose = apply_step(&pose, &center, &step);
    }
    pose
}

fn lateral(dx: f64) -> Isometry3<f64> {
    let t = truth();
    Isometry3::from_parts(
        Translation3::from(t.translation.vector + Vector3::new(dx, 0.0, 0.0)),
        t.rotation,
    )
}

#[test]
fn event_term_moves_a_lagging_silhouette_onto_the_events() {
    use tracker::refine::{EventTerm, EventTermKind};
    let (surface, mut renderer, id) = cube_events(&|_, _| false);
    // The hypothesis lags 8 mm to the left (about 10 px at 0.5 m).
    let before = 0.008;
    // The hinge's inward pull needs a moving outline (1 m/s); the lines see a still outline's step as well.
    for (kind, speed) in [(EventTermKind::Lines, 0.0), (EventTermKind::Hinge, 1.0)] {
        let term = EventTerm {
            kind,
            ..EventTerm::default()
        };
        let pose = refine_events(
            &term,
            &surface,
            &mut renderer,
            id,
            lateral(-before),
            speed,
            6,
        );
        let after = (pose.translation.vector - truth().translation.vector).norm();
        assert!(
            after < 0.35 * before,
            "{kind:?}: translation error {before:.4} m -> {after:.4} m"
        );
    }
}

#[test]
fn correspondence_lines_ignore_a_hand_next_to_the_object() {
    use tracker::refine::{EventTerm, EventTermKind};
    let cam = common::vga();
    // A "hand": a 60 x 80 px block of events touching the cube's right side.
    let c = truth() * nalgebra::Point3::origin();
    let u = cam.fx * c.x / c.z + cam.cx;
    let v = cam.fy * c.y / c.z + cam.cy;
    let (x0, y0) = (u + 45.0, v - 40.0);
    let hand = move |x: u32, y: u32| {
        let (x, y) = (f64::from(x), f64::from(y));
        x >= x0 && x < x0 + 60.0 && y >= y0 && y < y0 + 80.0
    };
    let (surface, mut renderer, id) = cube_events(&hand);
    let mut error = |kind| {
        let term = EventTerm {
            kind,
            ..EventTerm::default()
        };
        let pose = refine_events(&term, &surface, &mut renderer, id, truth(), 0.0, 6);
        // Lateral error: the silhouette's scale says little about depth, which the depth term fixes.
        (pose.translation.vector - truth().translation.vector)
            .xy()
            .norm()
    };
    let lines = error(EventTermKind::Lines);
    let hinge = error(EventTermKind::Hinge);
    // Starting at the truth, the lines stay within half a millimetre; the hinge is dragged towards the hand.
    assert!(lines < 5e-4, "lines moved {lines:.4} m off the truth");
    assert!(
        hinge > 2.0 * lines,
        "hinge {hinge:.4} m, lines {lines:.4} m"
    );
}

#[test]
fn outline_search_finds_a_shift_beyond_the_refinement_range() {
    use tracker::refine::{EventEdges, EventTerm};
    let cam = common::vga();
    let (surface, mut renderer, id) = cube_events(&|_, _| false);
    // 25 mm to the left at 0.5 m: about 26 px, beyond the residuals' 12 px reach.
    let start = lateral(-0.025);
    let term = EventTerm::default();
    let mut target = RenderTarget::new();
    let (roi, roi_cam) = render_roi_at(&mut renderer, id, &start, &mut target);
    let mut view = ModelView::with_capacity(600, 200);
    view.extract(&target, &roi_cam, 1, &start, 600, 200);
    let mut edges = EventEdges::default();
    edges.collect(
        &term,
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
    let expected = 0.025 * cam.fx / 0.5;
    let [du, dv] = edges
        .search_shift(&term, &view, &start, &cam, 40.0, None)
        .expect("a shift");
    assert!(
        (du - expected).abs() < 3.0 && dv.abs() < 3.0,
        "found ({du:.1}, {dv:.1}) px, expected ({expected:.1}, 0)"
    );
    // A shorter range still moves towards the events, as far as it may.
    let [du, dv] = edges
        .search_shift(&term, &view, &start, &cam, 8.0, None)
        .expect("a partial shift");
    assert!(
        du > 0.0 && du.hypot(dv) <= 8.0 * 2f64.sqrt() + 0.5,
        "({du:.1}, {dv:.1}) px"
    );
}

/// Refines `start` with the intensity-edge term alone against `surface`'s `I_t` (at 10 ms); returns the final
/// pose and the residuals of the last round.
fn refine_intensity(
    term: &tracker::refine::IntensityTerm,
    surface: &tracker::recon::EventSurface,
    renderer: &mut CpuRenderer,
    id: scene::render::MeshId,
    start: Isometry3<f64>,
    rounds: usize,
) -> (Isometry3<f64>, usize) {
    use tracker::refine::IntensityEdges;
    let cam = common::vga();
    let center = Vector3::zeros();
    let bounds = StepBounds {
        max_rotation: 0.2,
        max_translation: 0.02,
    };
    let (mut pose, mut active) = (start, 0);
    let mut target = RenderTarget::new();
    let mut view = ModelView::with_capacity(600, 200);
    let mut edges = IntensityEdges::default();
    for _ in 0..rounds {
        let (roi, roi_cam) = render_roi_at(renderer, id, &pose, &mut target);
        view.extract(&target, &roi_cam, 1, &pose, 600, 200);
        edges.associate(
            term,
            &view,
            &pose,
            &cam,
            surface,
            10_000,
            roi.width / f64::from(roi.out_width),
        );
        let mut ne = NormalEquations::default();
        active = edges.accumulate(term, &view, &pose, &center, &cam, &mut ne);
        for k in 0..6 {
            ne.h[(k, k)] += 1e3;
        }
        let Some(step) = solve_step(&ne, 1e-3, &bounds) else {
            break;
        };
        pose = apply_step(&pose, &center, &step);
    }
    (pose, active)
}

#[test]
fn intensity_edges_move_a_lagging_silhouette_onto_the_reconstructed_outline() {
    use tracker::recon::{EventSurface, IntensityFilterConfig};
    use tracker::refine::IntensityTerm;
    // I_t is +contrast on the cube's true silhouette and 0 elsewhere: its only edge is the true outline.
    let (surface, mut renderer, id) = cube_events(&|_, _| false);
    let term = IntensityTerm {
        weight: 1.0,
        max_distance_px: 14.0,
        ..IntensityTerm::default()
    };
    let before = 0.008;
    let (pose, active) = refine_intensity(&term, &surface, &mut renderer, id, lateral(-before), 6);
    let after = (pose.translation.vector - truth().translation.vector).norm();
    assert!(active > 20, "only {active} intensity residuals");
    assert!(
        after < 0.25 * before,
        "translation error {before:.4} m -> {after:.4} m"
    );
    // Without any events I_t is flat: no edge, no residual, no motion.
    let cam = common::vga();
    let flat = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    let (pose, active) = refine_intensity(&term, &flat, &mut renderer, id, lateral(-before), 3);
    assert_eq!(active, 0);
    assert!((pose.translation.vector - lateral(-before).translation.vector).norm() < 1e-9);
}

#[test]
fn contrast_maximisation_recovers_the_velocity_of_a_moving_outline() {
    use drivers::event::CdEvent;
    use tracker::recon::{EventSurface, IntensityFilterConfig};
    use tracker::refine::{EventEdges, EventTerm, EventTermKind};
    let cam = common::vga();
    let mut renderer = CpuRenderer::new();
    let id = renderer.add_mesh(Arc::new(common::cube(0.1))).unwrap();
    // The cube moves at 1 m/s along x; its outline fires events every 0.5 ms over the last 4 ms before 10 ms.
    let speed = 1.0;
    let mut surface = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    let mut full = RenderTarget::new();
    for k in (0..9).rev() {
        let age_s = 0.0005 * f64::from(k);
        let t_us = 10_000 - (age_s * 1e6) as i64;
        let scene = [SceneObject {
            mesh: id,
            pose: lateral(-speed * age_s),
            id: 1,
        }];
        renderer
            .render(&Scene::objects(&scene).geometry_only(), &cam, &mut full)
            .unwrap();
        let inside = |x: u32, y: u32| full.mask()[(y * cam.width + x) as usize] == 1;
        let events: Vec<CdEvent> = (1..cam.height - 1)
            .flat_map(|y| (1..cam.width - 1).map(move |x| (x, y)))
            .filter(|&(x, y)| inside(x, y) && !(inside(x - 1, y) && inside(x + 1, y)))
            .map(|(x, y)| CdEvent {
                t_us,
                x: x as u16,
                y: y as u16,
                polarity: true,
            })
            .collect();
        surface.integrate(&events);
    }
    let term = EventTerm {
        kind: EventTermKind::ContrastMax,
        min_neighbours: 1,
        ..EventTerm::default()
    };
    let pose = truth();
    let mut target = RenderTarget::new();
    let (roi, _) = render_roi_at(&mut renderer, id, &pose, &mut target);
    let mut edges = EventEdges::default();
    edges.collect(
        &term,
        &surface,
        &roi,
        target.mask(),
        target.depth(),
        f32::INFINITY,
        1,
        10_000,
        4_500,
        400,
        None,
    );
    let center = pose * nalgebra::Point3::origin();
    edges.lift_events(
        &surface,
        &cam,
        target.depth(),
        target.mask(),
        1,
        10_000,
        4_500,
        center.z,
        4_000,
    );
    assert!(
        edges.lifted_events() > 100,
        "{} events",
        edges.lifted_events()
    );
    let found = edges.maximise_contrast(&cam, &center, &nalgebra::Vector6::zeros(), 0.5, 0.0, 6);
    assert!(
        (found[0] - speed).abs() < 0.25 && found[1].abs() < 0.25,
        "velocity {found:?}, expected ({speed}, 0, 0)"
    );
}

#[test]
fn depth_stats_count_what_the_accumulation_counts() {
    let mut renderer = CpuRenderer::new();
    let id = renderer.add_mesh(Arc::new(common::cube(0.1))).unwrap();
    let mut measured = RenderTarget::new();
    let (_, roi_cam) = render_roi_at(&mut renderer, id, &truth(), &mut measured);
    let depth = DepthImage {
        width: roi_cam.width,
        height: roi_cam.height,
        z: measured.depth().to_vec(),
    };
    let term = DepthTerm::default();
    let mut view = ModelView::with_capacity(600, 200);
    // At the truth, 4 mm off (some residuals beyond two sigma) and 4 cm behind the measurement (occluded).
    for (shift, expect_occluded) in [(0.0, false), (0.004, false), (0.04, true)] {
        let pose = Translation3::new(0.0, 0.0, shift) * truth();
        let mut target = RenderTarget::new();
        render_roi_at(&mut renderer, id, &pose, &mut target);
        view.extract(&target, &roi_cam, 1, &pose, 600, 200);
        let mut ne = NormalEquations::default();
        let accumulated =
            term.accumulate(&view, &pose, &Vector3::zeros(), &roi_cam, &depth, &mut ne);
        let counted = term.stats(&view, &pose, &roi_cam, &depth);
        assert_eq!(counted, accumulated, "shift {shift}");
        assert!(counted.points > 100, "{counted:?}");
        assert_eq!(
            counted.occluded > counted.points / 2,
            expect_occluded,
            "{counted:?}"
        );
        assert!(ne.count <= counted.measured, "{counted:?} {}", ne.count);
    }
}

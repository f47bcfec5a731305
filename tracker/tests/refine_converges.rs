//! Render-and-compare refinement converges: the depth term alone recovers a perturbed pose of a cube from a
//! depth image rendered at the true pose, and the event term moves a lagging silhouette onto recent events.

mod common;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::sync::Arc;
use tracker::geometry::Roi;
use tracker::recon::DepthImage;
use tracker::refine::{DepthTerm, ModelView, NormalEquations, StepBounds, apply_step, solve_step};
use tracker::render::{CpuRenderer, RenderTarget, Renderer, Scene, SceneObject};

fn truth() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.02, -0.01, 0.5),
        UnitQuaternion::from_euler_angles(0.4, -0.3, 0.2),
    )
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

#[test]
fn event_term_moves_a_lagging_silhouette_onto_the_events() {
    use drivers::event::CdEvent;
    use tracker::recon::{EventSurface, IntensityFilterConfig};
    use tracker::refine::{EventEdges, EventTerm};
    let cam = common::vga();
    let mesh = Arc::new(common::cube(0.1));
    let mut renderer = CpuRenderer::new();
    let id = renderer.add_mesh(mesh).unwrap();
    let t = truth();
    // Events: every pixel the cube covers at the true pose fired at t = 10 ms (a moving textured object).
    let mut full = RenderTarget::new();
    renderer
        .render(
            &Scene::objects(&[SceneObject {
                mesh: id,
                pose: t,
                id: 1,
            }]),
            &cam,
            &mut full,
        )
        .unwrap();
    let events: Vec<CdEvent> = (0..cam.height)
        .flat_map(|y| (0..cam.width).map(move |x| (x, y)))
        .filter(|&(x, y)| full.mask()[(y * cam.width + x) as usize] == 1)
        .map(|(x, y)| CdEvent {
            t_us: 10_000,
            x: x as u16,
            y: y as u16,
            polarity: true,
        })
        .collect();
    let mut surface = EventSurface::new(cam.width, cam.height, IntensityFilterConfig::default());
    surface.integrate(&events);
    // The hypothesis lags 8 mm to the left (about 10 px at 0.5 m).
    let mut pose = Isometry3::from_parts(
        Translation3::from(t.translation.vector - Vector3::new(0.008, 0.0, 0.0)),
        t.rotation,
    );
    let term = EventTerm::default();
    let center = Vector3::zeros();
    let bounds = StepBounds {
        max_rotation: 0.2,
        max_translation: 0.02,
    };
    let before = (pose.translation.vector - t.translation.vector).norm();
    let mut target = RenderTarget::new();
    let mut view = ModelView::with_capacity(600, 200);
    let mut edges = EventEdges::default();
    // Moving right at 1 m/s: the event window's sweep makes the contour pull active.
    let motion = nalgebra::Vector6::new(1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for _ in 0..6 {
        let roi =
            Roi::around_object(&cam, &(pose * nalgebra::Point3::origin()), 0.17, 1.2, 160).unwrap();
        let roi_cam = cam.crop(&roi);
        renderer
            .render(
                &Scene::objects(&[SceneObject {
                    mesh: id,
                    pose,
                    id: 1,
                }]),
                &roi_cam,
                &mut target,
            )
            .unwrap();
        view.extract(&target, &roi_cam, 1, &pose, 600, 200);
        edges.collect(&term, &surface, &roi, target.mask(), 1, 10_000, 2_000, 400);
        edges.associate(&term, &view, &pose, &center, &cam, &motion, 0.002);
        let mut ne = NormalEquations::default();
        edges.accumulate(&term, &view, &pose, &center, &cam, &mut ne);
        // A weak prior keeps the unobserved directions put.
        for k in 0..6 {
            ne.h[(k, k)] += 1e3;
        }
        let Some(step) = solve_step(&ne, 1e-3, &bounds) else {
            break;
        };
        pose = apply_step(&pose, &center, &step);
    }
    let after = (pose.translation.vector - t.translation.vector).norm();
    assert!(
        after < 0.35 * before,
        "translation error {before:.4} m -> {after:.4} m"
    );
}

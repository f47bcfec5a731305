//! Renders ahead against plain renders: taken only by the identical request, replaced oldest first, errors
//! reported on request, meshes added later known.

use super::*;
use crate::geometry::PinholeCamera;
use crate::mesh::{Mesh, MeshParts};
use crate::render::{CpuRenderer, SceneObject};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

fn cube() -> Arc<Mesh> {
    let h = 0.05;
    let positions = [
        [-h, -h, -h],
        [h, -h, -h],
        [h, h, -h],
        [-h, h, -h],
        [-h, -h, h],
        [h, -h, h],
        [h, h, h],
        [-h, h, h],
    ]
    .map(|[x, y, z]| Point3::new(x, y, z));
    let triangles = vec![
        [0, 2, 1],
        [0, 3, 2],
        [4, 5, 6],
        [4, 6, 7],
        [0, 1, 5],
        [0, 5, 4],
        [3, 7, 6],
        [3, 6, 2],
        [0, 4, 7],
        [0, 7, 3],
        [1, 2, 6],
        [1, 6, 5],
    ];
    let parts = MeshParts {
        positions: positions.to_vec(),
        triangles,
        ..MeshParts::default()
    };
    Arc::new(Mesh::new("cube", parts).expect("a valid cube"))
}

fn pose(x: f64, angle: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, 0.0, 0.5),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), angle),
    )
}

fn setup() -> (RenderAhead, CpuRenderer, MeshId, PinholeCamera, Roi) {
    setup_with(Box::new(CpuRenderer::new()))
}

/// A `RenderAhead` of `inner` and a plain CPU renderer, each with the cube registered, a camera and a ROI.
fn setup_with(
    inner: Box<dyn Renderer + Send>,
) -> (RenderAhead, CpuRenderer, MeshId, PinholeCamera, Roi) {
    let mut ahead = RenderAhead::new(inner);
    let mut plain = CpuRenderer::new();
    let mesh = ahead.add_mesh(cube()).expect("mesh");
    assert_eq!(plain.add_mesh(cube()).expect("mesh"), mesh);
    let camera = PinholeCamera::new(600.0, 600.0, 320.0, 240.0, 640, 480).expect("camera");
    let roi = Roi::new(250.0, 170.0, 140.0, 140.0, 64, 64).expect("roi");
    (ahead, plain, mesh, camera, roi)
}

/// Renders `scene`'s ROI with `ahead` and with `plain`, asserts the two images are identical, and returns
/// `ahead`'s.
fn render_both(
    ahead: &mut RenderAhead,
    plain: &mut CpuRenderer,
    scene: &Scene<'_>,
    camera: &PinholeCamera,
    roi: &Roi,
) -> RenderTarget {
    let (mut got, mut want) = (RenderTarget::new(), RenderTarget::new());
    ahead
        .render_roi(scene, camera, roi, &mut got)
        .expect("render");
    plain
        .render_roi(scene, camera, roi, &mut want)
        .expect("render");
    assert!(same(&got, &want));
    got
}

fn same(a: &RenderTarget, b: &RenderTarget) -> bool {
    a.width() == b.width()
        && a.height() == b.height()
        && a.mask() == b.mask()
        && a.depth()
            .iter()
            .map(|d| d.to_bits())
            .eq(b.depth().iter().map(|d| d.to_bits()))
        && a.normals() == b.normals()
        && a.camera() == b.camera()
}

#[test]
fn a_render_ahead_is_taken_only_by_the_identical_request_and_matches_a_plain_render() {
    let (mut ahead, mut plain, mesh, camera, roi) = setup();
    let objects = [SceneObject {
        mesh,
        pose: pose(0.0, 0.3),
        id: 1,
    }];
    let scene = Scene::objects(&objects).geometry_only();
    assert!(ahead.prefetch_roi(&scene, &camera, &roi).expect("prefetch"));
    // Asking twice starts one render.
    assert!(ahead.prefetch_roi(&scene, &camera, &roi).expect("prefetch"));
    let moved = [SceneObject {
        pose: pose(1e-9, 0.3),
        ..objects[0]
    }];
    // A different pose (by a nanometre) renders on request and leaves the render ahead in place.
    let moved_scene = Scene::objects(&moved).geometry_only();
    render_both(&mut ahead, &mut plain, &moved_scene, &camera, &roi);
    assert_eq!(ahead.prefetch_counts().used, 0);
    let got = render_both(&mut ahead, &mut plain, &scene, &camera, &roi);
    assert!(got.mask().contains(&1));
    assert_eq!(
        ahead.prefetch_counts(),
        PrefetchCounts {
            started: 1,
            used: 1
        }
    );
    // Taken once: the same request again renders on request.
    render_both(&mut ahead, &mut plain, &scene, &camera, &roi);
    assert_eq!(ahead.prefetch_counts().used, 1);
}

#[test]
fn more_renders_ahead_than_slots_replace_the_oldest_and_every_taken_one_is_right() {
    let (mut ahead, mut plain, mesh, camera, roi) = setup();
    let scenes: Vec<[SceneObject; 1]> = (0..AHEAD_SLOTS + 3)
        .map(|k| {
            [SceneObject {
                mesh,
                pose: pose(0.002 * k as f64, 0.1 * k as f64),
                id: 1,
            }]
        })
        .collect();
    // Past the last slot, each prefetch replaces the oldest render (waiting for it if it is still being made).
    for s in &scenes {
        assert!(
            ahead
                .prefetch_roi(&Scene::objects(s).geometry_only(), &camera, &roi)
                .expect("prefetch")
        );
    }
    for s in scenes.iter().rev() {
        let scene = Scene::objects(s).geometry_only();
        render_both(&mut ahead, &mut plain, &scene, &camera, &roi);
    }
    // The three oldest were replaced before anyone asked; the rest were taken.
    assert_eq!(
        ahead.prefetch_counts(),
        PrefetchCounts {
            started: (AHEAD_SLOTS + 3) as u64,
            used: AHEAD_SLOTS as u64
        }
    );
}

#[test]
fn a_failing_render_ahead_reports_its_error_on_request() {
    let (mut ahead, _, _, camera, roi) = setup();
    let objects = [SceneObject {
        mesh: MeshId(7),
        pose: pose(0.0, 0.0),
        id: 1,
    }];
    let scene = Scene::objects(&objects);
    assert!(ahead.prefetch_roi(&scene, &camera, &roi).expect("prefetch"));
    let mut target = RenderTarget::new();
    assert_eq!(
        ahead.render_roi(&scene, &camera, &roi, &mut target),
        Err(RenderError::UnknownMesh(MeshId(7)))
    );
    assert_eq!(ahead.prefetch_counts().used, 0);
}

#[test]
fn a_mesh_added_after_rendering_ahead_is_known_to_the_next_render_ahead() {
    let (mut ahead, mut plain, _, camera, roi) = setup();
    let objects = [SceneObject {
        mesh: MeshId(0),
        pose: pose(0.0, 0.2),
        id: 1,
    }];
    assert!(
        ahead
            .prefetch_roi(&Scene::objects(&objects), &camera, &roi)
            .expect("prefetch")
    );
    let second = ahead.add_mesh(cube()).expect("mesh");
    assert_eq!(plain.add_mesh(cube()).expect("mesh"), second);
    let objects = [SceneObject {
        mesh: second,
        pose: pose(0.01, 0.2),
        id: 2,
    }];
    let scene = Scene::objects(&objects);
    assert!(ahead.prefetch_roi(&scene, &camera, &roi).expect("prefetch"));
    let got = render_both(&mut ahead, &mut plain, &scene, &camera, &roi);
    assert!(got.mask().contains(&2));
    assert_eq!(ahead.prefetch_counts().used, 1);
}

#[test]
fn forgotten_renders_ahead_are_not_taken_and_their_slots_are_reused() {
    let (mut ahead, mut plain, mesh, camera, roi) = setup();
    // Rounds as the tracker makes them: two renders ahead, one taken, the rest forgotten before the next round.
    for k in 0..20 {
        let at = |x: f64| {
            [SceneObject {
                mesh,
                pose: pose(x, 0.05 * k as f64),
                id: 1,
            }]
        };
        let (taken, other) = (at(0.001), at(0.002));
        ahead.forget_prefetched();
        for s in [&taken, &other] {
            assert!(
                ahead
                    .prefetch_roi(&Scene::objects(s).geometry_only(), &camera, &roi)
                    .expect("prefetch")
            );
        }
        let scene = Scene::objects(&taken).geometry_only();
        render_both(&mut ahead, &mut plain, &scene, &camera, &roi);
    }
    assert_eq!(
        ahead.prefetch_counts(),
        PrefetchCounts {
            started: 40,
            used: 20
        }
    );
    // Two slots per round, and at most one more while a forgotten render is still on the helper thread.
    assert!(ahead.slots.len() <= 3, "{} slots", ahead.slots.len());
    // A forgotten render is not taken, even by its own request.
    let objects = [SceneObject {
        mesh,
        pose: pose(0.0, 1.0),
        id: 1,
    }];
    let scene = Scene::objects(&objects).geometry_only();
    assert!(ahead.prefetch_roi(&scene, &camera, &roi).expect("prefetch"));
    ahead.forget_prefetched();
    render_both(&mut ahead, &mut plain, &scene, &camera, &roi);
    assert_eq!(ahead.prefetch_counts().used, 20);
}

/// Renders with a CPU renderer; its forks panic in every render.
struct ForksPanic(CpuRenderer);

/// A renderer that panics in every render.
struct Panics;

impl Renderer for Panics {
    fn add_mesh(&mut self, _: Arc<Mesh>) -> Result<MeshId, RenderError> {
        Ok(MeshId(0))
    }
    fn device(&self) -> RenderDevice {
        RenderDevice::CpuRasteriser
    }
    fn render(
        &mut self,
        _: &Scene<'_>,
        _: &PinholeCamera,
        _: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        panic!("a render that panics");
    }
}

impl Renderer for ForksPanic {
    fn add_mesh(&mut self, mesh: Arc<Mesh>) -> Result<MeshId, RenderError> {
        self.0.add_mesh(mesh)
    }
    fn device(&self) -> RenderDevice {
        self.0.device()
    }
    fn render(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        self.0.render(scene, camera, target)
    }
    fn fork(&self) -> Option<Box<dyn Renderer + Send>> {
        Some(Box::new(Panics))
    }
}

#[test]
fn a_panic_on_the_helper_thread_is_caught_and_the_request_renders_on_the_callers_thread() {
    let (mut ahead, mut plain, mesh, camera, roi) =
        setup_with(Box::new(ForksPanic(CpuRenderer::new())));
    for k in 0..3 {
        let objects = [SceneObject {
            mesh,
            pose: pose(0.0, 0.1 * f64::from(k)),
            id: 1,
        }];
        let scene = Scene::objects(&objects).geometry_only();
        assert!(ahead.prefetch_roi(&scene, &camera, &roi).expect("prefetch"));
        let got = render_both(&mut ahead, &mut plain, &scene, &camera, &roi);
        assert!(got.mask().contains(&1));
    }
    // The helper thread survived each panic: every prefetch started, none was taken.
    assert_eq!(
        ahead.prefetch_counts(),
        PrefetchCounts {
            started: 3,
            used: 0
        }
    );
}

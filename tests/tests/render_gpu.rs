//! The wgpu renderer against the CPU renderer on the 12 library meshes (several poses, 160x160 ROI), on a scene of
//! mutually occluding objects in front of a background mesh (full frame and ROI), and on invalid input; and its
//! prefetched renders, taken only by the identical request.
//!
//! Needs a Vulkan adapter: on a machine without a GPU, Mesa's lavapipe (`apt-get install mesa-vulkan-drivers`, which
//! `.ci/setup` does). Without one these tests fail; they never pass silently.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use hil_sim::objects::{ObjectKind, generate, library};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use scene::geometry::{PinholeCamera, Roi};
use scene::mesh::{Material, Mesh, MeshParts, Texture};
use scene::render::{
    BackgroundMesh, CpuRenderer, GpuRenderer, MASK_BACKGROUND, MASK_EMPTY, MeshId, PrefetchCounts,
    RenderDevice, RenderError, RenderTarget, Renderer, RendererKind, Scene, SceneObject,
    create_renderer,
};
use std::sync::Arc;

fn gpu_renderer() -> GpuRenderer {
    GpuRenderer::new().unwrap_or_else(|e| {
        panic!(
            "the GPU renderer could not start ({e}). These tests need a Vulkan driver: install \
             mesa-vulkan-drivers (lavapipe), as .ci/setup does on CI"
        )
    })
}

fn camera() -> PinholeCamera {
    PinholeCamera::from_horizontal_fov(70f64.to_radians(), 1280, 720).expect("valid camera")
}

/// How far the two renders of one image agree.
#[derive(Debug, Default)]
struct Agreement {
    /// Pixels away from any mask edge (3x3 neighbourhood uniform in both masks).
    interior: usize,
    /// Interior pixels whose mask differs.
    interior_mask_mismatch: usize,
    /// All pixels whose mask differs.
    mask_mismatch: usize,
    /// Pixels both render with the same label.
    both: usize,
    /// Largest depth difference over `both`, metres.
    max_depth_all: f32,
    /// Pixels of `both` whose depth differs by more than 1 mm.
    depth_over_1mm: usize,
    /// Largest depth difference over interior pixels with no depth step (3x3 range < 1 cm), metres.
    max_depth_smooth: f32,
    /// Normal angles over `both`, degrees (sorted).
    normal_deg: Vec<f32>,
    /// Intensity differences over `both` (sorted).
    intensity: Vec<f32>,
    /// Labels seen in the CPU mask.
    labels: Vec<u16>,
}

fn percentile(sorted: &[f32], p: f64) -> f32 {
    if sorted.is_empty() {
        return 0.0;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

impl Agreement {
    fn interior_mask_fraction(&self) -> f64 {
        1.0 - self.interior_mask_mismatch as f64 / self.interior.max(1) as f64
    }
}

fn compare(cpu: &RenderTarget, gpu: &RenderTarget) -> Agreement {
    assert_eq!((cpu.width(), cpu.height()), (gpu.width(), gpu.height()));
    assert_eq!(cpu.camera(), gpu.camera());
    let (w, h) = (cpu.width() as i64, cpu.height() as i64);
    let mut a = Agreement::default();
    let at = |x: i64, y: i64| (y * w + x) as usize;
    for y in 0..h {
        for x in 0..w {
            let i = at(x, y);
            let (mc, mg) = (cpu.mask()[i], gpu.mask()[i]);
            if !a.labels.contains(&mc) {
                a.labels.push(mc);
            }
            let mut uniform = true;
            let (mut zmin, mut zmax) = (f32::INFINITY, 0.0f32);
            for (dx, dy) in (-1..=1).flat_map(|dy| (-1..=1).map(move |dx| (dx, dy))) {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w || ny >= h {
                    continue;
                }
                let j = at(nx, ny);
                uniform &= cpu.mask()[j] == mc && gpu.mask()[j] == mc;
                zmin = zmin.min(cpu.depth()[j]);
                zmax = zmax.max(cpu.depth()[j]);
            }
            if mc != mg {
                a.mask_mismatch += 1;
            }
            if uniform {
                a.interior += 1;
                if mc != mg {
                    a.interior_mask_mismatch += 1;
                }
            }
            if mc == MASK_EMPTY || mc != mg {
                continue;
            }
            a.both += 1;
            let dz = (cpu.depth()[i] - gpu.depth()[i]).abs();
            a.max_depth_all = a.max_depth_all.max(dz);
            if dz > 1e-3 {
                a.depth_over_1mm += 1;
            }
            if uniform && zmax - zmin < 0.01 {
                a.max_depth_smooth = a.max_depth_smooth.max(dz);
            }
            let (nc, ng) = (cpu.normals()[i], gpu.normals()[i]);
            let dot: f32 = (0..3).map(|k| nc[k] * ng[k]).sum();
            a.normal_deg.push(dot.clamp(-1.0, 1.0).acos().to_degrees());
            a.intensity
                .push((cpu.intensity()[i] - gpu.intensity()[i]).abs());
            let len: f32 = ng.iter().map(|c| c * c).sum::<f32>().sqrt();
            assert!((len - 1.0).abs() < 1e-3, "GPU normal {ng:?} is not unit");
        }
    }
    a.normal_deg.sort_by(f32::total_cmp);
    a.intensity.sort_by(f32::total_cmp);
    a
}

/// Asserts the agreement the backends promise and prints the figures.
fn check(what: &str, a: &Agreement, min_rendered: usize) {
    let normal_p99 = percentile(&a.normal_deg, 0.99);
    let intensity_p99 = percentile(&a.intensity, 0.99);
    println!(
        "{what}: {} px both, interior mask agreement {:.4}% ({} of {} interior px differ, {} px overall), max depth \
         diff {:.3} mm (smooth interior {:.4} mm, {} px > 1 mm), normals p99 {:.3} deg max {:.2} deg, intensity \
         p99 {:.4} max {:.4}",
        a.both,
        100.0 * a.interior_mask_fraction(),
        a.interior_mask_mismatch,
        a.interior,
        a.mask_mismatch,
        a.max_depth_all * 1e3,
        a.max_depth_smooth * 1e3,
        a.depth_over_1mm,
        normal_p99,
        percentile(&a.normal_deg, 1.0),
        intensity_p99,
        percentile(&a.intensity, 1.0),
    );
    assert!(
        a.both >= min_rendered,
        "{what}: only {} px rendered by both",
        a.both
    );
    assert!(
        a.interior_mask_fraction() >= 0.999,
        "{what}: masks agree on only {:.3}% of non-boundary pixels",
        100.0 * a.interior_mask_fraction()
    );
    // Silhouette pixels may go either way, but only a thin outline of them.
    assert!(
        a.mask_mismatch <= a.both / 20 + 8,
        "{what}: {} pixels differ in mask",
        a.mask_mismatch
    );
    assert!(
        a.max_depth_smooth < 1e-3,
        "{what}: depth differs by {:.3} mm on a smooth interior pixel",
        a.max_depth_smooth * 1e3
    );
    assert!(
        a.depth_over_1mm * 200 <= a.both,
        "{what}: {} of {} pixels differ in depth by more than 1 mm",
        a.depth_over_1mm,
        a.both
    );
    assert!(
        normal_p99 < 3.0,
        "{what}: normals p99 {normal_p99} degrees apart"
    );
    assert!(
        intensity_p99 < 0.02,
        "{what}: intensity p99 difference {intensity_p99}"
    );
}

/// Renders `scene` (in `roi` or the full image) with both backends.
fn render_both(
    cpu: &mut CpuRenderer,
    gpu: &mut GpuRenderer,
    scene: &Scene<'_>,
    roi: Option<&Roi>,
) -> (RenderTarget, RenderTarget) {
    let (mut a, mut b) = (RenderTarget::new(), RenderTarget::new());
    let cam = camera();
    match roi {
        Some(roi) => {
            cpu.render_roi(scene, &cam, roi, &mut a)
                .expect("CPU render");
            gpu.render_roi(scene, &cam, roi, &mut b)
                .expect("GPU render");
        }
        None => {
            cpu.render(scene, &cam, &mut a).expect("CPU render");
            gpu.render(scene, &cam, &mut b).expect("GPU render");
        }
    }
    (a, b)
}

fn register(cpu: &mut CpuRenderer, gpu: &mut GpuRenderer, mesh: Mesh) -> (MeshId, f64) {
    let mesh = Arc::new(mesh);
    let id = cpu.add_mesh(mesh.clone()).expect("CPU registers");
    assert_eq!(gpu.add_mesh(mesh.clone()).expect("GPU registers"), id);
    (id, mesh.diameter())
}

fn pose(t: [f64; 3], euler: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        UnitQuaternion::from_euler_angles(euler[0], euler[1], euler[2]),
    )
}

#[test]
fn the_device_says_whether_a_gpu_draws() {
    let gpu = gpu_renderer();
    let device = gpu.device();
    let RenderDevice::Vulkan { adapter, on_cpu } = &device else {
        panic!("the wgpu renderer reports {device:?}");
    };
    assert_eq!(adapter, gpu.adapter());
    // lavapipe (llvmpipe) is Mesa's CPU driver: the operator is told the CPU renderer is faster; a real GPU is not
    // warned about.
    let lavapipe = adapter.contains("llvmpipe");
    assert_eq!(*on_cpu, lavapipe, "{adapter}");
    assert_eq!(device.warning().is_some(), lavapipe, "{adapter}");
}

#[test]
fn library_meshes_match_the_cpu_renderer_in_the_roi() {
    let mut gpu = gpu_renderer();
    println!("adapter: {}", gpu.adapter());
    let mut cpu = CpuRenderer::new();
    let (mut worst_depth, mut worst_mask, mut worst_normal) = (0.0f32, 1.0f64, 0.0f32);
    for object in library(3) {
        let mesh = object.to_mesh().expect("library mesh");
        let (id, diameter) = register(&mut cpu, &mut gpu, mesh);
        let poses = [
            ("front", pose([0.02, -0.01, 0.6], [0.3, -0.4, 0.2])),
            ("rotated", pose([-0.05, 0.03, 0.7], [2.6, 1.3, -2.1])),
            (
                "close",
                pose([0.0, 0.02, 0.05 + diameter], [-0.7, 0.5, 2.8]),
            ),
        ];
        for (label, pose) in poses {
            let objects = [SceneObject {
                mesh: id,
                pose,
                id: 7,
            }];
            let scene = Scene::objects(&objects);
            let centre = pose * Point3::<f64>::origin();
            let roi = Roi::around_object(&camera(), &centre, diameter, 1.2, 160).expect("roi");
            let (a, b) = render_both(&mut cpu, &mut gpu, &scene, Some(&roi));
            let agreement = compare(&a, &b);
            check(&format!("{} {label}", object.name()), &agreement, 500);
            assert!(agreement.labels.contains(&7));
            // The tracker's render: the geometry-only pipelines (fewer interpolated values).
            let geometry = scene.geometry_only();
            let (ga, gb) = render_both(&mut cpu, &mut gpu, &geometry, Some(&roi));
            check(
                &format!("{} {label}, geometry only", object.name()),
                &compare(&ga, &gb),
                500,
            );
            assert!(gb.intensity().iter().all(|&i| i == 0.0));
            worst_depth = worst_depth.max(agreement.max_depth_all);
            worst_mask = worst_mask.min(agreement.interior_mask_fraction());
            worst_normal = worst_normal.max(percentile(&agreement.normal_deg, 0.99));
        }
    }
    println!(
        "library summary: max depth diff {:.3} mm, worst interior mask agreement {:.4}%, worst normal p99 {:.3} deg",
        worst_depth * 1e3,
        100.0 * worst_mask,
        worst_normal
    );
}

/// A textured square in the x-y plane of side `size` metres, facing -z.
fn wall(size: f32) -> Mesh {
    let h = size / 2.0;
    let texels = (0..64 * 64)
        .map(|i| [((i * 37) % 101) as f32 / 100.0; 3])
        .collect();
    let parts = MeshParts {
        positions: vec![
            Point3::new(-h, -h, 0.0),
            Point3::new(h, -h, 0.0),
            Point3::new(h, h, 0.0),
            Point3::new(-h, h, 0.0),
        ],
        uvs: vec![[0.0, 0.0], [3.0, 0.0], [3.0, 3.0], [0.0, 3.0]],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![Material {
            name: "wall".into(),
            diffuse: [0.9, 0.8, 0.7],
            texture: Some(Arc::new(
                Texture::from_linear(64, 64, texels).expect("texture"),
            )),
        }],
        ..MeshParts::default()
    };
    Mesh::new("test-wall", parts).expect("valid wall")
}

#[test]
fn occluding_objects_and_background_match_in_full_frame_and_roi() {
    let mut gpu = gpu_renderer();
    let mut cpu = CpuRenderer::new();
    let kinds = [ObjectKind::CrackerBox, ObjectKind::Mug, ObjectKind::Can];
    let ids: Vec<MeshId> = kinds
        .iter()
        .map(|&k| register(&mut cpu, &mut gpu, generate(k, 1).to_mesh().expect("mesh")).0)
        .collect();
    let (wall_id, _) = register(&mut cpu, &mut gpu, wall(2.0));
    // The mug in front of the box, the can in front of both, overlapping on screen; the wall behind.
    let objects = [
        SceneObject {
            mesh: ids[0],
            pose: pose([0.0, 0.0, 0.9], [0.2, 0.5, 0.1]),
            id: 1,
        },
        SceneObject {
            mesh: ids[1],
            pose: pose([0.05, 0.02, 0.7], [1.9, 0.3, 0.4]),
            id: 2,
        },
        SceneObject {
            mesh: ids[2],
            pose: pose([-0.03, 0.04, 0.55], [1.2, -0.2, 0.0]),
            id: 3,
        },
    ];
    let background = [BackgroundMesh {
        mesh: wall_id,
        pose: pose([0.0, 0.0, 1.4], [0.2, -0.3, 0.0]),
    }];
    let scene = Scene::objects(&objects).with_background(&background);

    // A ROI first, then the full frame (the GPU targets grow), then the ROI again (reused, larger targets).
    let roi =
        Roi::around_object(&camera(), &Point3::new(0.0, 0.02, 0.7), 0.35, 1.2, 160).expect("roi");
    let (a, b) = render_both(&mut cpu, &mut gpu, &scene, Some(&roi));
    let first = compare(&a, &b);
    check("occlusion ROI", &first, 5000);
    let (fa, fb) = render_both(&mut cpu, &mut gpu, &scene, None);
    let full = compare(&fa, &fb);
    check("occlusion full frame", &full, 100_000);
    let (c, d) = render_both(&mut cpu, &mut gpu, &scene, Some(&roi));
    assert_eq!(c.mask(), a.mask(), "the CPU renderer is deterministic");
    assert_eq!(
        d.mask(),
        b.mask(),
        "the GPU renderer gives the same ROI after growing its targets"
    );
    assert_eq!(d.depth(), b.depth());

    // Geometry only (what the tracker asks for): same geometry as the shaded render, no intensity.
    let (g_cpu, g_gpu) = render_both(&mut cpu, &mut gpu, &scene.geometry_only(), Some(&roi));
    assert_eq!(g_gpu.mask(), b.mask());
    assert_eq!(g_gpu.depth(), b.depth());
    assert!(b.intensity().iter().any(|&i| i > 0.0));
    assert!(g_gpu.intensity().iter().all(|&i| i == 0.0));
    check(
        "occlusion ROI, geometry only",
        &compare(&g_cpu, &g_gpu),
        5000,
    );

    // Every object is visible and partly hidden: fewer pixels than when rendered alone.
    for agreement in [&first, &full] {
        for label in [1, 2, 3, MASK_BACKGROUND] {
            assert!(
                agreement.labels.contains(&label),
                "label {label} missing: {:?}",
                agreement.labels
            );
        }
    }
    let count = |t: &RenderTarget, id: u16| t.mask().iter().filter(|&&m| m == id).count();
    for (i, object) in objects.iter().enumerate().take(2) {
        let alone = [*object];
        let mut solo = RenderTarget::new();
        gpu.render(&Scene::objects(&alone), &camera(), &mut solo)
            .expect("GPU render");
        let (together, by_itself) = (count(&fb, object.id), count(&solo, object.id));
        assert!(
            together + 200 < by_itself,
            "object {i} should be occluded: {together} px in the scene, {by_itself} px alone"
        );
    }
}

#[test]
fn gpu_renderer_reports_the_same_input_errors_and_is_selectable() {
    let mut gpu = gpu_renderer();
    let mesh = Arc::new(generate(ObjectKind::Can, 0).to_mesh().expect("mesh"));
    let id = gpu.add_mesh(mesh).expect("registered");
    let cam = camera();
    let mut target = RenderTarget::new();
    let ok = pose([0.0, 0.0, 0.5], [0.0; 3]);
    let render = |gpu: &mut GpuRenderer, scene: &Scene<'_>, target: &mut RenderTarget| {
        gpu.render(scene, &cam, target)
    };
    let reserved = [SceneObject {
        mesh: id,
        pose: ok,
        id: MASK_EMPTY,
    }];
    assert_eq!(
        render(&mut gpu, &Scene::objects(&reserved), &mut target),
        Err(RenderError::ReservedObjectId(0))
    );
    // A handle from another renderer that has more meshes.
    let mut other = CpuRenderer::new();
    let can = Arc::new(generate(ObjectKind::Can, 0).to_mesh().expect("mesh"));
    other.add_mesh(can.clone()).expect("registered");
    let foreign = other.add_mesh(can).expect("registered");
    let unknown = [SceneObject {
        mesh: foreign,
        pose: ok,
        id: 1,
    }];
    assert_eq!(
        render(&mut gpu, &Scene::objects(&unknown), &mut target),
        Err(RenderError::UnknownMesh(foreign))
    );
    let mut bad_near = Scene::objects(&[]);
    bad_near.near = 0.0;
    assert!(matches!(
        render(&mut gpu, &bad_near, &mut target),
        Err(RenderError::InvalidNear(_))
    ));
    let mut nan = ok;
    nan.translation.x = f64::NAN;
    let non_finite = [SceneObject {
        mesh: id,
        pose: nan,
        id: 1,
    }];
    assert!(matches!(
        render(&mut gpu, &Scene::objects(&non_finite), &mut target),
        Err(RenderError::NonFinitePose { .. })
    ));
    let mut bad_cam = cam;
    bad_cam.fx = -1.0;
    assert!(matches!(
        gpu.render(&Scene::objects(&[]), &bad_cam, &mut target),
        Err(RenderError::Camera(_))
    ));
    let mut huge = cam;
    (huge.width, huge.height) = (1 << 16, 1 << 16);
    assert!(matches!(
        gpu.render(&Scene::objects(&[]), &huge, &mut target),
        Err(RenderError::ImageTooLarge { .. })
    ));
    // After the errors, rendering works; an empty scene renders empty.
    gpu.render(&Scene::objects(&[]), &cam, &mut target)
        .expect("empty scene");
    assert!(target.mask().iter().all(|&m| m == MASK_EMPTY));
    assert!(target.depth().iter().all(|&z| z == 0.0));

    let mut boxed = create_renderer(RendererKind::Gpu).expect("GPU renderer by kind");
    let id = boxed
        .add_mesh(Arc::new(
            generate(ObjectKind::Can, 0).to_mesh().expect("mesh"),
        ))
        .expect("registered");
    let objects = [SceneObject {
        mesh: id,
        pose: ok,
        id: 4,
    }];
    let handle = std::thread::spawn(move || {
        let mut t = RenderTarget::new();
        boxed
            .render(&Scene::objects(&objects), &camera(), &mut t)
            .map(|()| t)
    });
    let t = handle
        .join()
        .expect("render thread")
        .expect("render on another thread");
    assert!(t.mask().iter().filter(|&&m| m == 4).count() > 1000);
}

/// The images of `a` and `b` are bit-identical (depth, normals, mask, intensity, camera).
fn assert_same_image(a: &RenderTarget, b: &RenderTarget, what: &str) {
    assert_eq!(a.camera(), b.camera(), "{what}: camera");
    assert_eq!(a.mask(), b.mask(), "{what}: mask");
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(a.depth()), bits(b.depth()), "{what}: depth");
    assert_eq!(
        bits(a.intensity()),
        bits(b.intensity()),
        "{what}: intensity"
    );
    let normals = |t: &RenderTarget| bits(&t.normals().concat());
    assert_eq!(normals(a), normals(b), "{what}: normals");
}

#[test]
fn a_prefetched_render_is_taken_only_by_the_identical_request() {
    let mut gpu = gpu_renderer();
    let mug = Arc::new(
        generate(ObjectKind::Mug, 3)
            .to_mesh()
            .expect("library mesh"),
    );
    let id = gpu.add_mesh(mug.clone()).expect("GPU registers");
    let cam = camera();
    let at = |p: Isometry3<f64>| {
        [SceneObject {
            mesh: id,
            pose: p,
            id: 4,
        }]
    };
    let (p0, p1) = (
        pose([0.01, 0.0, 0.5], [0.4, -0.3, 0.2]),
        pose([0.03, -0.01, 0.55], [0.2, 0.5, -0.4]),
    );
    let roi_of = |p: &Isometry3<f64>| {
        Roi::around_object(&cam, &(p * Point3::origin()), mug.diameter(), 1.2, 160).expect("roi")
    };
    let direct = |gpu: &mut GpuRenderer, p: Isometry3<f64>| {
        let objects = at(p);
        let mut t = RenderTarget::new();
        gpu.render_roi(
            &Scene::objects(&objects).geometry_only(),
            &cam,
            &roi_of(&p),
            &mut t,
        )
        .expect("render");
        t
    };
    let expected0 = direct(&mut gpu, p0);
    let expected1 = direct(&mut gpu, p1);
    assert_eq!(gpu.prefetch_counts(), PrefetchCounts::default());

    // Prefetched, then requested identically: taken, and the same image as rendering on request.
    let objects = at(p0);
    let scene = Scene::objects(&objects).geometry_only();
    assert!(
        gpu.prefetch_roi(&scene, &cam, &roi_of(&p0))
            .expect("prefetch")
    );
    let mut taken = RenderTarget::new();
    gpu.render_roi(&scene, &cam, &roi_of(&p0), &mut taken)
        .expect("render");
    assert_same_image(&taken, &expected0, "prefetched image");
    assert_eq!(
        gpu.prefetch_counts(),
        PrefetchCounts {
            started: 1,
            used: 1
        }
    );

    // Prefetched at one pose, requested at another: rendered again, the prefetch is not taken.
    assert!(
        gpu.prefetch_roi(&scene, &cam, &roi_of(&p0))
            .expect("prefetch")
    );
    let other = at(p1);
    let mut fresh = RenderTarget::new();
    gpu.render_roi(
        &Scene::objects(&other).geometry_only(),
        &cam,
        &roi_of(&p1),
        &mut fresh,
    )
    .expect("render");
    assert_same_image(&fresh, &expected1, "request that differs from the prefetch");
    assert_eq!(
        gpu.prefetch_counts(),
        PrefetchCounts {
            started: 2,
            used: 1
        }
    );
    // Shaded instead of geometry only is another request too.
    let mut shaded = RenderTarget::new();
    gpu.render_roi(&Scene::objects(&objects), &cam, &roi_of(&p0), &mut shaded)
        .expect("render");
    assert!(shaded.intensity().iter().any(|&i| i > 0.0));
    assert_eq!(gpu.prefetch_counts().used, 1);
    // The unused prefetch is still there for its own request.
    gpu.render_roi(&scene, &cam, &roi_of(&p0), &mut taken)
        .expect("render");
    assert_same_image(&taken, &expected0, "prefetch taken after other renders");
    assert_eq!(
        gpu.prefetch_counts(),
        PrefetchCounts {
            started: 2,
            used: 2
        }
    );

    // Several in flight (one per object of a scene), each taken by its own request, in any order; more than the
    // slots replaces the oldest without error.
    let poses: Vec<_> = (0..10)
        .map(|k| {
            pose(
                [0.01 * f64::from(k), 0.0, 0.5],
                [0.1 * f64::from(k), 0.2, 0.0],
            )
        })
        .collect();
    for p in &poses {
        let objects = at(*p);
        assert!(
            gpu.prefetch_roi(&Scene::objects(&objects).geometry_only(), &cam, &roi_of(p))
                .expect("prefetch")
        );
    }
    for p in poses.iter().rev() {
        let want = {
            let mut g = gpu_renderer();
            assert_eq!(g.add_mesh(mug.clone()).expect("GPU registers"), id);
            direct(&mut g, *p)
        };
        let objects = at(*p);
        gpu.render_roi(
            &Scene::objects(&objects).geometry_only(),
            &cam,
            &roi_of(p),
            &mut taken,
        )
        .expect("render");
        assert_same_image(&taken, &want, "one of several prefetches");
    }
    let counts = gpu.prefetch_counts();
    assert_eq!(counts.started, 2 + 10);
    // The last 8 (the slots) were taken; the first 2 were replaced before their request came.
    assert_eq!(counts.used, 2 + 8);

    // A forgotten prefetch is not taken, even by its own request, which renders again (the same image).
    assert!(
        gpu.prefetch_roi(&scene, &cam, &roi_of(&p0))
            .expect("prefetch")
    );
    gpu.forget_prefetched();
    gpu.render_roi(&scene, &cam, &roi_of(&p0), &mut taken)
        .expect("render");
    assert_same_image(
        &taken,
        &expected0,
        "request after its prefetch was forgotten",
    );
    assert_eq!(
        gpu.prefetch_counts(),
        PrefetchCounts {
            started: 2 + 10 + 1,
            used: 2 + 8
        }
    );
}

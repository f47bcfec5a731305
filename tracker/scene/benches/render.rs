//! Renderer throughput, CPU and (with the `gpu` feature) wgpu backends: the tracker's per-tick ROI render (160x160 crop
//! of 1.2 x diameter around a ~5k-triangle textured object) and a 1280x720 full frame with a textured background plane.
//! A GPU render includes waiting for the device and reading the image back into the `RenderTarget`.

// `criterion_group!` defines undocumented public functions.
#![allow(missing_docs)]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::geometry::{PinholeCamera, Roi};
use scene::mesh::{Material, Mesh, MeshParts, Texture};
use scene::render::{
    BackgroundMesh, CpuRenderer, RenderTarget, Renderer, RendererKind, Scene, SceneObject,
};
use std::hint::black_box;
use std::sync::Arc;

fn noise_texture(size: u32) -> Arc<Texture> {
    let mut state = 0x9e37_79b9_u32;
    let texels = (0..size * size)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            [(state & 0xff) as f32 / 255.0; 3]
        })
        .collect();
    Arc::new(Texture::from_linear(size, size, texels).expect("valid texture size"))
}

/// A textured ellipsoid with `2 * rings * segments` triangles (about 5k for 50 x 50).
fn ellipsoid(radii: [f32; 3], rings: u32, segments: u32) -> Mesh {
    let mut parts = MeshParts::default();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let d = Vector3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            parts
                .positions
                .push(Point3::new(d.x * radii[0], d.y * radii[1], d.z * radii[2]));
            parts
                .normals
                .push(Vector3::new(d.x / radii[0], d.y / radii[1], d.z / radii[2]).normalize());
            parts
                .uvs
                .push([j as f32 / segments as f32, 1.0 - i as f32 / rings as f32]);
        }
    }
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let a = i * row + j;
            parts.triangles.push([a, a + row, a + 1]);
            parts.triangles.push([a + 1, a + row, a + row + 1]);
        }
    }
    parts.materials = vec![Material {
        name: "noise".into(),
        diffuse: [1.0; 3],
        texture: Some(noise_texture(256)),
    }];
    Mesh::new("bench-ellipsoid", parts).expect("valid mesh")
}

fn plane(size: f32) -> Mesh {
    let h = size / 2.0;
    let parts = MeshParts {
        positions: vec![
            Point3::new(-h, -h, 0.0),
            Point3::new(h, -h, 0.0),
            Point3::new(h, h, 0.0),
            Point3::new(-h, h, 0.0),
        ],
        uvs: vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        materials: vec![Material {
            name: "wall".into(),
            diffuse: [1.0; 3],
            texture: Some(noise_texture(512)),
        }],
        ..MeshParts::default()
    };
    Mesh::new("bench-plane", parts).expect("valid mesh")
}

/// Benchmarks one backend; names are prefixed with `gpu_` for the wgpu backend (the CPU names are unchanged).
fn bench_backend(c: &mut Criterion, kind: RendererKind, renderer: &mut dyn Renderer) {
    let prefix = match kind {
        RendererKind::Cpu => "",
        RendererKind::Gpu => "gpu_",
    };
    // EVK4-like event camera: 1280x720, ~70 degree horizontal field of view.
    let camera =
        PinholeCamera::from_horizontal_fov(70f64.to_radians(), 1280, 720).expect("valid camera");
    let object = Arc::new(ellipsoid([0.09, 0.05, 0.04], 50, 50));
    println!(
        "object: {} triangles, diameter {:.3} m",
        object.triangles().len(),
        object.diameter()
    );
    let mesh = renderer.add_mesh(object.clone()).expect("registered");
    let wall = renderer.add_mesh(Arc::new(plane(3.0))).expect("registered");
    let pose = Isometry3::from_parts(
        Translation3::new(0.05, -0.02, 0.5),
        UnitQuaternion::from_euler_angles(0.4, 0.8, 0.2),
    );
    let objects = [SceneObject { mesh, pose, id: 1 }];
    let center = pose * Point3::origin();
    let roi =
        Roi::around_object(&camera, &center, object.diameter(), 1.2, 160).expect("roi in view");
    let mut target = RenderTarget::with_capacity(160, 160);

    c.bench_function(&format!("{prefix}render_roi_160_5k_tris"), |b| {
        b.iter(|| {
            renderer
                .render_roi(&Scene::objects(&objects), &camera, &roi, &mut target)
                .expect("render");
            black_box(target.depth()[80 * 160 + 80]);
        })
    });

    let background = [BackgroundMesh {
        mesh: wall,
        pose: Isometry3::translation(0.0, 0.0, 1.5),
    }];
    let scene = Scene::objects(&objects).with_background(&background);
    let mut full = RenderTarget::with_capacity(1280, 720);
    c.bench_function(
        &format!("{prefix}render_full_1280x720_5k_tris_plus_background"),
        |b| {
            b.iter(|| {
                renderer.render(&scene, &camera, &mut full).expect("render");
                black_box(full.depth()[360 * 1280 + 640]);
            })
        },
    );
}

fn bench_render(c: &mut Criterion) {
    bench_backend(c, RendererKind::Cpu, &mut CpuRenderer::new());
    #[cfg(feature = "gpu")]
    match scene::render::GpuRenderer::new() {
        Ok(mut gpu) => {
            println!("GPU adapter: {}", gpu.adapter());
            bench_backend(c, RendererKind::Gpu, &mut gpu);
        }
        Err(e) => println!("GPU renderer benchmarks skipped: {e}"),
    }
}

criterion_group!(benches, bench_render);
criterion_main!(benches);

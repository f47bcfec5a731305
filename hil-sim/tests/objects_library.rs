//! The procedural object library: realistic sizes, real symmetries, textures that produce contrast, determinism, and
//! the OBJ + MTL + PNG round trip through the tracker's mesh loader.

#![allow(clippy::unwrap_used, clippy::expect_used)]

use hil_sim::objects::{
    ObjectKind, ProceduralObject, generate, library, models_info_json, write_library, write_object,
};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use scene::geometry::{PinholeCamera, Roi};
use scene::mesh::{Mesh, MeshLoadOptions, Symmetry, load_obj};
use scene::render::{CpuRenderer, RenderTarget, Renderer, Scene, SceneObject};
use std::collections::HashMap;
use std::sync::Arc;

/// Expected diameter (metres) of each kind, from its documented dimensions.
fn expected_diameter(kind: ObjectKind) -> f64 {
    match kind {
        ObjectKind::CrackerBox => (0.16f64.powi(2) + 0.06f64.powi(2) + 0.21f64.powi(2)).sqrt(),
        ObjectKind::PuddingBox => (0.09f64.powi(2) + 0.035f64.powi(2) + 0.11f64.powi(2)).sqrt(),
        ObjectKind::Can => (0.068f64.powi(2) + 0.1f64.powi(2)).sqrt(),
        ObjectKind::Bottle => 0.195,
        ObjectKind::Mug => 0.13,
        ObjectKind::Bowl => 0.165,
        ObjectKind::Banana => 0.2,
        ObjectKind::Hammer => 0.33,
        ObjectKind::Spatula => 0.31,
        ObjectKind::Drill => 0.28,
        ObjectKind::Marker => 0.13,
        ObjectKind::WineGlass => 0.21,
    }
}

fn mesh_of(o: &ProceduralObject) -> Mesh {
    o.to_mesh().unwrap_or_else(|e| panic!("{}: {e}", o.name()))
}

#[test]
fn library_covers_the_categories_with_realistic_sizes() {
    let objects = library(1);
    assert!(objects.len() >= 10);
    let mut names: Vec<_> = objects.iter().map(|o| o.name()).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), objects.len());
    for o in &objects {
        let m = mesh_of(o);
        let d = m.diameter();
        let e = expected_diameter(o.kind);
        assert!(
            (d - e).abs() < 0.15 * e,
            "{}: diameter {d:.3} m, expected about {e:.3} m",
            o.name()
        );
        assert!(
            m.triangles().len() >= 12 && m.triangles().len() < 20_000,
            "{}: {} triangles",
            o.name(),
            m.triangles().len()
        );
        // Centred on the bounding box.
        assert!(
            m.aabb().center().coords.norm() < 1e-6,
            "{} not centred",
            o.name()
        );
        assert_eq!((o.texture.width(), o.texture.height()), (512, 512));
        assert_eq!(ObjectKind::from_name(o.name()), Some(o.kind));
    }
}

/// Largest distance from a transformed vertex to the nearest original vertex (grid-accelerated).
fn vertex_set_mismatch(m: &Mesh, t: &Isometry3<f64>) -> f64 {
    let cell = 0.002;
    let key = |p: &Point3<f64>| {
        (
            (p.x / cell).floor() as i64,
            (p.y / cell).floor() as i64,
            (p.z / cell).floor() as i64,
        )
    };
    let mut grid: HashMap<(i64, i64, i64), Vec<Point3<f64>>> = HashMap::new();
    for p in m.positions() {
        let p = p.cast::<f64>();
        grid.entry(key(&p)).or_default().push(p);
    }
    let mut worst: f64 = 0.0;
    for p in m.positions() {
        let q = t * p.cast::<f64>();
        let (kx, ky, kz) = key(&q);
        let mut best = f64::INFINITY;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&(kx + dx, ky + dy, kz + dz)) {
                        for r in list {
                            best = best.min((r - q).norm());
                        }
                    }
                }
            }
        }
        worst = worst.max(best.min(cell * 2.0));
    }
    worst
}

#[test]
fn declared_symmetries_map_the_shape_onto_itself() {
    for o in library(2) {
        let m = mesh_of(&o);
        for s in &o.symmetries {
            let t = match s {
                Symmetry::Discrete(t) => *t,
                // A rotation by a multiple of the lathe's segment angle maps vertices onto vertices.
                Symmetry::Continuous { axis, offset } => {
                    let r =
                        UnitQuaternion::from_axis_angle(axis, std::f64::consts::TAU * 3.0 / 16.0);
                    Isometry3::from_parts(Translation3::from(offset.coords - r * offset.coords), r)
                }
            };
            let err = vertex_set_mismatch(&m, &t);
            assert!(err < 1e-5, "{}: symmetry {s:?} is off by {err} m", o.name());
        }
    }
    // Objects declared asymmetric really are: half a turn about z moves the mug's handle.
    let mug = mesh_of(&generate(ObjectKind::Mug, 0));
    let half_turn = Isometry3::rotation(Vector3::z() * std::f64::consts::PI);
    assert!(vertex_set_mismatch(&mug, &half_turn) > 1e-3);
}

#[test]
fn generation_is_deterministic_and_seed_varies_texture_only() {
    for kind in ObjectKind::ALL {
        let (a, b, c) = (generate(kind, 5), generate(kind, 5), generate(kind, 6));
        assert_eq!(a.geometry.positions, b.geometry.positions);
        assert_eq!(a.geometry.triangles, b.geometry.triangles);
        assert_eq!(a.texture, b.texture, "{}", kind.name());
        assert_eq!(a.geometry.positions, c.geometry.positions);
        assert_ne!(
            a.texture,
            c.texture,
            "{}: seed should change the texture",
            kind.name()
        );
    }
}

fn camera() -> PinholeCamera {
    PinholeCamera::from_horizontal_fov(70f64.to_radians(), 1280, 720).unwrap()
}

fn render_roi(mesh: Mesh, pose: Isometry3<f64>) -> RenderTarget {
    let mut r = CpuRenderer::new();
    let diameter = mesh.diameter();
    let id = r.add_mesh(Arc::new(mesh)).unwrap();
    let cam = camera();
    let roi = Roi::around_object(&cam, &(pose * Point3::origin()), diameter, 1.2, 160).unwrap();
    let mut t = RenderTarget::new();
    r.render_roi(
        &Scene::objects(&[SceneObject {
            mesh: id,
            pose,
            id: 1,
        }]),
        &cam,
        &roi,
        &mut t,
    )
    .unwrap();
    t
}

fn viewing_pose() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.5),
        UnitQuaternion::from_euler_angles(-1.2, 0.3, 0.5),
    )
}

#[test]
fn written_objects_load_back_identically() {
    let dir = tempfile::tempdir().unwrap();
    for o in library(3) {
        let files = write_object(&o, dir.path()).unwrap();
        let loaded = load_obj(&files.obj, &MeshLoadOptions::default()).unwrap();
        assert!(
            loaded.warnings.is_empty(),
            "{}: {:?}",
            o.name(),
            loaded.warnings
        );
        let (a, b) = (mesh_of(&o), loaded.mesh);
        assert_eq!(a.triangles().len(), b.triangles().len(), "{}", o.name());
        assert!((a.diameter() - b.diameter()).abs() < 1e-9, "{}", o.name());
        assert_eq!(a.aabb(), b.aabb());
        let tex = b.materials()[0].texture.as_ref().expect("texture loaded");
        assert_eq!(
            a.materials()[0].texture.as_deref(),
            Some(tex.as_ref()),
            "{}: texture differs",
            o.name()
        );
        // Rendered from the same pose, the in-memory and loaded meshes look the same.
        let (ra, rb) = (render_roi(a, viewing_pose()), render_roi(b, viewing_pose()));
        assert_eq!(ra.mask(), rb.mask(), "{}", o.name());
        let max_diff = ra
            .intensity()
            .iter()
            .zip(rb.intensity())
            .map(|(x, y)| (x - y).abs())
            .fold(0.0f32, f32::max);
        assert!(
            max_diff < 1e-5,
            "{}: intensity differs by {max_diff}",
            o.name()
        );
    }
}

#[test]
fn textures_produce_contrast_when_rendered() {
    for o in library(4) {
        let t = render_roi(mesh_of(&o), viewing_pose());
        let w = t.width() as usize;
        let visible = t.mask().iter().filter(|&&m| m == 1).count();
        assert!(
            visible > 1000,
            "{}: only {visible} pixels visible",
            o.name()
        );
        // Mean absolute log-intensity step between horizontally adjacent object pixels: events need texture.
        let (mut sum, mut n) = (0.0f64, 0usize);
        for i in 0..t.mask().len() - 1 {
            if (i + 1) % w != 0 && t.mask()[i] == 1 && t.mask()[i + 1] == 1 {
                let (a, b) = (t.intensity()[i].max(1e-3), t.intensity()[i + 1].max(1e-3));
                sum += f64::from((a.ln() - b.ln()).abs());
                n += 1;
            }
        }
        let mean = sum / n as f64;
        assert!(
            mean > 0.02,
            "{}: mean log-intensity step {mean:.4} is too flat",
            o.name()
        );
    }
}

#[test]
fn library_writes_models_info_in_bop_shape() {
    let dir = tempfile::tempdir().unwrap();
    let written = write_library(dir.path(), 9).unwrap();
    assert_eq!(written.len(), ObjectKind::ALL.len());
    for (_, files, _) in &written {
        assert!(files.obj.exists() && files.mtl.exists() && files.texture.exists());
    }
    let infos: Vec<_> = written
        .iter()
        .map(|(id, _, info)| (*id, info.clone()))
        .collect();
    let json = models_info_json(&infos);
    let can_id = ObjectKind::ALL
        .iter()
        .position(|k| *k == ObjectKind::Can)
        .unwrap()
        + 1;
    let mug_id = ObjectKind::ALL
        .iter()
        .position(|k| *k == ObjectKind::Mug)
        .unwrap()
        + 1;
    let box_id = ObjectKind::ALL
        .iter()
        .position(|k| *k == ObjectKind::CrackerBox)
        .unwrap()
        + 1;
    let can = &json[can_id.to_string()];
    assert!(
        (can["diameter"].as_f64().unwrap() - infos[can_id - 1].1.diameter * 1000.0).abs() < 1e-9
    );
    assert!(can["diameter"].as_f64().unwrap() > 100.0, "millimetres");
    assert_eq!(
        can["symmetries_continuous"][0]["axis"],
        serde_json::json!([0.0, 0.0, 1.0])
    );
    assert_eq!(can["symmetries_discrete"].as_array().unwrap().len(), 1);
    assert_eq!(
        json[box_id.to_string()]["symmetries_discrete"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    assert!(
        json[mug_id.to_string()]
            .get("symmetries_discrete")
            .is_none()
    );
    assert!(
        json[mug_id.to_string()]
            .get("symmetries_continuous")
            .is_none()
    );
    // Sizes: the cracker box is 160 x 60 x 210 mm.
    let b = &json[box_id.to_string()];
    for (k, v) in [("size_x", 160.0), ("size_y", 60.0), ("size_z", 210.0)] {
        assert!((b[k].as_f64().unwrap() - v).abs() < 0.01, "{k}");
    }
}

#[test]
fn writing_into_an_unwritable_place_names_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, b"x").unwrap();
    let err = write_object(&generate(ObjectKind::Can, 0), &blocker.join("sub")).unwrap_err();
    assert!(err.to_string().contains("file"), "{err}");
}

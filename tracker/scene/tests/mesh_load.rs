//! Mesh loading, measurements, sampling and error reporting.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use nalgebra::Point3;
use scene::mesh::{MeshError, MeshLoadOptions, MeshWarning, load_obj};
use std::path::{Path, PathBuf};

const CUBE_OBJ: &str = "\
mtllib cube.mtl
v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl painted
f 1/1 4/4 3/3 2/2
f 5/1 6/2 7/3 8/4
f 1/1 2/2 6/3 5/4
f 2/1 3/2 7/3 6/4
f 3/1 4/2 8/3 7/4
f 4/1 1/2 5/3 8/4
";

const CUBE_MTL: &str = "newmtl painted\nKd 1 1 1\nmap_Kd cube.png\n";

fn write(dir: &Path, name: &str, contents: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, contents).unwrap();
    p
}

fn write_png(path: &Path, w: u32, h: u32) {
    let img = image::RgbImage::from_fn(w, h, |x, y| {
        image::Rgb([(x * 40) as u8, (y * 40) as u8, 200])
    });
    img.save(path).unwrap();
}

fn cube_dir() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "cube.obj", CUBE_OBJ.as_bytes());
    write(dir.path(), "cube.mtl", CUBE_MTL.as_bytes());
    write_png(&dir.path().join("cube.png"), 4, 3);
    (dir, obj)
}

#[test]
fn unit_cube_loads_with_texture_and_measures() {
    let (_dir, obj) = cube_dir();
    let loaded = load_obj(&obj, &MeshLoadOptions::default()).unwrap();
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let m = &loaded.mesh;
    assert_eq!(m.triangles().len(), 12, "quads are triangulated");
    assert!((m.diameter() - 3f64.sqrt()).abs() < 1e-6);
    assert_eq!(m.aabb().min, Point3::new(-0.5, -0.5, -0.5));
    assert_eq!(m.aabb().max, Point3::new(0.5, 0.5, 0.5));
    assert!((m.surface_area() - 6.0).abs() < 1e-6);
    let texture = m.materials()[0].texture.as_ref().expect("texture loaded");
    assert_eq!((texture.width(), texture.height()), (4, 3));
    assert!(m.uvs().is_some());
}

#[test]
fn jpeg_textures_load() {
    let (dir, obj) = cube_dir();
    let img = image::RgbImage::from_fn(8, 8, |x, _| image::Rgb([(x * 30) as u8, 0, 0]));
    img.save(dir.path().join("cube.jpg")).unwrap();
    write(
        dir.path(),
        "cube.mtl",
        b"newmtl painted\nKd 1 1 1\nmap_Kd cube.jpg\n",
    );
    let m = load_obj(&obj, &MeshLoadOptions::default()).unwrap().mesh;
    assert_eq!(m.materials()[0].texture.as_ref().unwrap().width(), 8);
}

#[test]
fn surface_samples_lie_on_the_cube_and_are_area_weighted() {
    let m = common::cube(1.0);
    let samples = m.sample_surface_seeded(20_000, 42);
    assert_eq!(samples.len(), 20_000);
    for s in &samples {
        let p = s.position;
        let max = p.x.abs().max(p.y.abs()).max(p.z.abs());
        assert!((max - 0.5).abs() < 1e-6, "{p:?} is not on the surface");
        assert!(p.iter().all(|c| c.abs() <= 0.5 + 1e-6));
        // The normal is perpendicular to the face the point lies on.
        assert!((s.normal.norm() - 1.0).abs() < 1e-9);
    }
    // Equal-area faces: each of the 6 gets ~1/6 of the samples.
    let mut per_face = [0usize; 6];
    for s in &samples {
        per_face[s.triangle as usize / 2] += 1;
    }
    for c in per_face {
        assert!(
            (c as f64 / 20_000.0 - 1.0 / 6.0).abs() < 0.015,
            "{per_face:?}"
        );
    }
    // Deterministic for a seed.
    assert_eq!(samples, m.sample_surface_seeded(20_000, 42));
}

#[test]
fn samples_follow_triangle_areas() {
    // Two triangles with areas 1 : 3.
    let obj = "v 0 0 0\nv 1 0 0\nv 0 2 0\nv 10 0 0\nv 13 0 0\nv 10 2 0\nf 1 2 3\nf 4 5 6\n";
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "two.obj", obj.as_bytes());
    let m = load_obj(&p, &MeshLoadOptions::default()).unwrap();
    let s = m.mesh.sample_surface_seeded(40_000, 7);
    let big = s.iter().filter(|s| s.triangle == 1).count() as f64 / 40_000.0;
    assert!((big - 0.75).abs() < 0.01, "{big}");
    for x in &s {
        assert!(x.position.z.abs() < 1e-9);
        if x.triangle == 1 {
            assert!(x.position.x >= 10.0 - 1e-9);
        }
    }
}

fn err_of(path: &Path) -> (MeshError, String) {
    let e = load_obj(path, &MeshLoadOptions::default()).unwrap_err();
    let msg = e.to_string();
    (e, msg)
}

#[test]
fn missing_obj_is_reported_with_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("nope.obj");
    let (e, msg) = err_of(&p);
    assert!(matches!(e, MeshError::Read { .. }));
    assert!(msg.contains("nope.obj"), "{msg}");
}

#[test]
fn corrupt_obj_is_reported_with_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "bad.obj",
        b"v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n",
    );
    let (e, msg) = err_of(&p);
    assert!(matches!(e, MeshError::Parse { kind: "OBJ", .. }), "{e:?}");
    assert!(msg.contains("bad.obj"), "{msg}");
    let p = write(
        dir.path(),
        "oob.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n",
    );
    let (_, msg) = err_of(&p);
    assert!(msg.contains("oob.obj"), "{msg}");
}

#[test]
fn empty_obj_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "empty.obj", b"# nothing here\nv 0 0 0\n");
    let (e, msg) = err_of(&p);
    assert!(matches!(e, MeshError::Empty { .. }), "{e:?}");
    assert!(
        msg.contains("empty.obj") && msg.contains("no triangles"),
        "{msg}"
    );
}

#[test]
fn non_finite_vertex_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "nan.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 NaN 0\nf 1 2 3\n",
    );
    let (e, msg) = err_of(&p);
    assert!(
        matches!(e, MeshError::NonFiniteVertex { vertex: 2, .. }),
        "{e:?}"
    );
    assert!(msg.contains("nan.obj") && msg.contains("#2"), "{msg}");
}

#[test]
fn missing_or_corrupt_material_files_are_reported() {
    let (dir, obj) = cube_dir();
    std::fs::remove_file(dir.path().join("cube.mtl")).unwrap();
    let (e, msg) = err_of(&obj);
    assert!(matches!(e, MeshError::Read { .. }), "{e:?}");
    assert!(msg.contains("cube.mtl"), "{msg}");

    write(dir.path(), "cube.mtl", b"newmtl painted\nKd 1 x 1\n");
    let (_, msg) = err_of(&obj);
    assert!(msg.contains("cube.mtl"), "{msg}");

    // A colour with two numbers: the OBJ parser underneath panics on it, so it is refused before, by line.
    write(
        dir.path(),
        "cube.mtl",
        b"newmtl painted\n\nKs 1 1 1\nKd  0 0\n",
    );
    let (e, msg) = err_of(&obj);
    assert!(matches!(e, MeshError::Parse { kind: "MTL", .. }), "{e:?}");
    assert!(
        msg.contains("cube.mtl") && msg.contains("line 4: `Kd` needs three numbers"),
        "{msg}"
    );
}

#[test]
fn missing_or_corrupt_textures_are_reported() {
    let (dir, obj) = cube_dir();
    std::fs::remove_file(dir.path().join("cube.png")).unwrap();
    let (e, msg) = err_of(&obj);
    assert!(matches!(e, MeshError::Read { .. }));
    assert!(msg.contains("cube.png"), "{msg}");

    write(
        dir.path(),
        "cube.png",
        b"\x89PNG\r\n\x1a\nthis is not a png",
    );
    let (e, msg) = err_of(&obj);
    assert!(matches!(e, MeshError::Texture { .. }), "{e:?}");
    assert!(msg.contains("cube.png") && msg.contains("painted"), "{msg}");
}

#[test]
fn millimetre_meshes_warn_and_scale_fixes_them() {
    let dir = tempfile::tempdir().unwrap();
    // A 100 mm cube authored in millimetres.
    let scaled = CUBE_OBJ
        .lines()
        .filter(|l| !l.starts_with("mtllib") && !l.starts_with("usemtl"))
        .map(|l| {
            if l.starts_with("v ") {
                l.replace("0.5", "50")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let p = write(dir.path(), "mm.obj", scaled.as_bytes());
    let loaded = load_obj(&p, &MeshLoadOptions::default()).unwrap();
    let warning = loaded
        .warnings
        .iter()
        .find(|w| matches!(w, MeshWarning::LikelyMillimetres { .. }))
        .expect("warning");
    assert!(warning.to_string().contains("mm.obj") && warning.to_string().contains("millimetres"));
    let fixed = load_obj(
        &p,
        &MeshLoadOptions {
            scale: 0.001,
            ..MeshLoadOptions::default()
        },
    )
    .unwrap();
    assert!(fixed.warnings.is_empty());
    assert!((fixed.mesh.diameter() - 0.1 * 3f64.sqrt()).abs() < 1e-6);
    let bad = load_obj(
        &p,
        &MeshLoadOptions {
            scale: f64::NAN,
            ..MeshLoadOptions::default()
        },
    )
    .unwrap_err();
    assert!(bad.to_string().contains("mm.obj"));
}

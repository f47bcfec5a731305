//! Property tests of the OBJ / MTL loader on generated and arbitrary files: it never panics, every error names
//! the file at fault, and every mesh it accepts is one the renderers can use (finite vertices, triangles within
//! the vertex list, attributes per vertex).

#![allow(clippy::unwrap_used, clippy::expect_used)]

use proptest::prelude::*;
use scene::mesh::{MeshError, MeshLoadOptions, load_obj};
use std::path::Path;

/// A number as OBJ files may spell it: ordinary, extreme, non-finite or not a number at all.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => (-2.0f32..2.0).prop_map(|v| format!("{v}")),
        1 => Just("nan".to_string()),
        1 => Just("inf".to_string()),
        1 => Just("-1e39".to_string()),
        1 => Just("1e-45".to_string()),
        1 => Just("0x10".to_string()),
        1 => Just("".to_string()),
    ]
}

/// A face vertex reference: position, optional texture coordinate and normal, any of them out of range, zero or
/// negative (relative).
fn face_vertex() -> impl Strategy<Value = String> {
    let index = prop_oneof![
        6 => (1i64..12).prop_map(|i| i.to_string()),
        1 => (-12i64..0).prop_map(|i| i.to_string()),
        1 => Just("0".to_string()),
        1 => Just("4294967297".to_string()),
        1 => Just("-99999999999".to_string()),
        1 => Just("x".to_string()),
    ];
    (
        index.clone(),
        prop::option::of(index.clone()),
        prop::option::of(index),
    )
        .prop_map(|(v, t, n)| match (t, n) {
            (None, None) => v,
            (Some(t), None) => format!("{v}/{t}"),
            (None, Some(n)) => format!("{v}//{n}"),
            (Some(t), Some(n)) => format!("{v}/{t}/{n}"),
        })
}

/// One line of an OBJ file.
fn obj_line() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (number(), number(), number()).prop_map(|(x, y, z)| format!("v {x} {y} {z}")),
        1 => (number(), number()).prop_map(|(x, y)| format!("v {x} {y}")),
        2 => (number(), number()).prop_map(|(u, v)| format!("vt {u} {v}")),
        2 => (number(), number(), number()).prop_map(|(x, y, z)| format!("vn {x} {y} {z}")),
        6 => prop::collection::vec(face_vertex(), 0..6).prop_map(|vs| format!("f {}", vs.join(" "))),
        1 => Just("mtllib m.mtl".to_string()),
        1 => Just("mtllib missing.mtl".to_string()),
        1 => prop_oneof![Just("a"), Just("b"), Just("nope")].prop_map(|m| format!("usemtl {m}")),
        1 => prop_oneof![Just("o part"), Just("g group"), Just("s 1"), Just("l 1 2"), Just("p 1")]
            .prop_map(str::to_string),
        1 => "[ -~]{0,12}",
    ]
}

/// One line of an MTL file.
fn mtl_line() -> impl Strategy<Value = String> {
    prop_oneof![
        2 => prop_oneof![Just("a"), Just("b")].prop_map(|m| format!("newmtl {m}")),
        2 => (number(), number(), number()).prop_map(|(r, g, b)| format!("Kd {r} {g} {b}")),
        1 => Just("map_Kd missing.png".to_string()),
        1 => Just("map_Kd not_an_image.png".to_string()),
        1 => "[ -~]{0,12}",
    ]
}

/// Checks what `load_obj` made of `dir/m.obj`: an error that names a file of `dir`, or a usable mesh.
fn check_load(dir: &Path) -> Result<(), TestCaseError> {
    let obj = dir.join("m.obj");
    match load_obj(&obj, &MeshLoadOptions::default()) {
        Err(e) => {
            let message = e.to_string();
            let names_a_file = [
                "m.obj",
                "m.mtl",
                "missing.mtl",
                "missing.png",
                "not_an_image.png",
            ]
            .iter()
            .any(|f| message.contains(&dir.join(f).display().to_string()));
            prop_assert!(
                names_a_file,
                "the error names no file of the mesh: {message}"
            );
            if let MeshError::InvalidScale { .. } = e {
                prop_assert!(false, "the default scale was refused: {message}");
            }
        }
        Ok(loaded) => {
            let m = &loaded.mesh;
            let n = m.positions().len();
            prop_assert!(
                !m.triangles().is_empty(),
                "a mesh without triangles was accepted"
            );
            prop_assert!(
                m.positions()
                    .iter()
                    .all(|p| p.coords.iter().all(|c| c.is_finite()))
            );
            prop_assert!(
                m.triangles().iter().flatten().all(|&i| (i as usize) < n),
                "a triangle refers past the {n} vertices"
            );
            if let Some(normals) = m.normals() {
                prop_assert_eq!(normals.len(), n);
            }
            if let Some(uvs) = m.uvs() {
                prop_assert_eq!(uvs.len(), n);
            }
        }
    }
    Ok(())
}

// 256 cases each by default; `PROPTEST_CASES=N` runs more.
proptest! {
    #[test]
    fn generated_obj_and_mtl_files_load_or_fail_by_name(
        obj in prop::collection::vec(obj_line(), 0..24),
        mtl in prop::option::of(prop::collection::vec(mtl_line(), 0..8)),
    ) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("m.obj"), obj.join("\n")).unwrap();
        if let Some(mtl) = mtl {
            std::fs::write(dir.path().join("m.mtl"), mtl.join("\n")).unwrap();
        }
        std::fs::write(dir.path().join("not_an_image.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
        check_load(dir.path())?;
    }

    #[test]
    fn arbitrary_bytes_load_or_fail_by_name(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("m.obj"), &bytes).unwrap();
        check_load(dir.path())?;
    }
}

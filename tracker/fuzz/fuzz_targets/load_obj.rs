#![no_main]
//! Fuzz the OBJ / MTL loader: the input is an OBJ file, optionally followed by a NUL byte and the MTL file it may
//! name as `m.mtl`. No input panics; an error names a file; a mesh it accepts has finite vertices and triangles
//! within its vertex list.

#[allow(dead_code, unused_imports)]
#[path = "../../scene/src/mesh/mod.rs"]
mod mesh;

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

/// A directory of this process for the files under test.
fn scratch() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("et6d-fuzz-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch directory");
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    let dir = scratch();
    let (obj, mtl) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    };
    let obj_path = dir.join("m.obj");
    let mtl_path = dir.join("m.mtl");
    std::fs::write(&obj_path, obj).expect("write the OBJ");
    match mtl {
        Some(m) => std::fs::write(&mtl_path, m).expect("write the MTL"),
        None => {
            let _ = std::fs::remove_file(&mtl_path);
        }
    }
    match mesh::load_obj(&obj_path, &mesh::MeshLoadOptions::default()) {
        Err(e) => {
            let message = e.to_string();
            // A file the OBJ or MTL names may lie anywhere (`mtllib /elsewhere/x.mtl`); the rest are ours.
            let file = match &e {
                mesh::MeshError::Read { path, .. } | mesh::MeshError::Texture { path, .. } => {
                    path.clone()
                }
                _ => dir.clone(),
            };
            assert!(
                message.contains(&file.display().to_string()),
                "the error names no file: {message}"
            );
        }
        Ok(loaded) => {
            let m = &loaded.mesh;
            let n = m.positions().len();
            assert!(!m.triangles().is_empty());
            assert!(
                m.positions()
                    .iter()
                    .all(|p| p.coords.iter().all(|c| c.is_finite()))
            );
            assert!(m.triangles().iter().flatten().all(|&i| (i as usize) < n));
        }
    }
});

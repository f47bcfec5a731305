//! Writing objects as Wavefront OBJ + MTL + PNG texture, and the BOP-style `models_info` for a set of objects.

use super::library;
use super::model::ObjectModel;
use scene::mesh::{MeshError, ObjectInfo};
use serde_json::{Map, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why an object could not be written.
#[derive(Debug, thiserror::Error)]
pub enum ObjectWriteError {
    /// A file or directory could not be created or written.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The texture could not be encoded.
    #[error("cannot encode texture {}: {reason}", path.display())]
    Texture {
        /// The PNG file.
        path: PathBuf,
        /// What the encoder reported.
        reason: String,
    },
    /// The generated geometry is invalid (a generator bug, reported rather than written).
    #[error("generated object '{name}' is invalid: {source}")]
    Invalid {
        /// The object's name.
        name: String,
        /// What is wrong.
        #[source]
        source: MeshError,
    },
}

/// The files written for one object.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectFiles {
    /// The OBJ file (`<name>.obj`); load it with [`scene::mesh::load_obj`].
    pub obj: PathBuf,
    /// The material file (`<name>.mtl`).
    pub mtl: PathBuf,
    /// The diffuse texture (`<name>.png`).
    pub texture: PathBuf,
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ObjectWriteError> {
    std::fs::write(path, bytes).map_err(|source| ObjectWriteError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `object` into `dir` (created if missing) as `<name>.obj`, `<name>.mtl` and `<name>.png`. Coordinates are
/// written in metres with full f32 precision, so the loaded mesh equals [`ObjectModel::to_mesh`].
pub fn write_object<O: ObjectModel + ?Sized>(
    object: &O,
    dir: &Path,
) -> Result<ObjectFiles, ObjectWriteError> {
    std::fs::create_dir_all(dir).map_err(|source| ObjectWriteError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let name = object.name();
    let files = ObjectFiles {
        obj: dir.join(format!("{name}.obj")),
        mtl: dir.join(format!("{name}.mtl")),
        texture: dir.join(format!("{name}.png")),
    };
    let g = object.geometry();
    // OBJ: one vertex / texcoord / normal per index, faces reference the same index thrice.
    let mut obj = String::with_capacity(g.positions.len() * 96 + g.triangles.len() * 40);
    let _ = writeln!(
        obj,
        "# EventTrack6D procedural object '{name}' (units: metres)"
    );
    let _ = writeln!(obj, "mtllib {name}.mtl\no {name}");
    for p in &g.positions {
        let _ = writeln!(obj, "v {} {} {}", p.x, p.y, p.z);
    }
    for t in &g.uvs {
        let _ = writeln!(obj, "vt {} {}", t[0], t[1]);
    }
    for n in &g.normals {
        let _ = writeln!(obj, "vn {} {} {}", n.x, n.y, n.z);
    }
    let _ = writeln!(obj, "usemtl {name}");
    for t in &g.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(obj, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
    }
    let mtl = format!(
        "# EventTrack6D procedural object '{name}'\nnewmtl {name}\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nd 1\nillum 1\nmap_Kd {name}.png\n"
    );
    write_file(&files.obj, obj.as_bytes())?;
    write_file(&files.mtl, mtl.as_bytes())?;
    object
        .texture()
        .save_with_format(&files.texture, image::ImageFormat::Png)
        .map_err(|e| ObjectWriteError::Texture {
            path: files.texture.clone(),
            reason: e.to_string(),
        })?;
    Ok(files)
}

/// BOP `models_info.json` content for `objects`: keys are object ids (`"1"`, `"2"`, ...), values the entries of
/// [`ObjectInfo::to_bop_json`] (millimetres).
pub fn models_info_json(objects: &[(u32, ObjectInfo)]) -> Value {
    let mut map = Map::new();
    for (id, info) in objects {
        map.insert(id.to_string(), info.to_bop_json());
    }
    Value::Object(map)
}

/// Generates the whole library with `seed` and writes every object into `dir`, returning each object's id (its
/// position in [`super::ObjectKind::ALL`] plus one), files and information. The caller stores the information with
/// [`models_info_json`].
pub fn write_library(
    dir: &Path,
    seed: u64,
) -> Result<Vec<(u32, ObjectFiles, ObjectInfo)>, ObjectWriteError> {
    library(seed)
        .iter()
        .enumerate()
        .map(|(i, object)| {
            let info = object.info().map_err(|source| ObjectWriteError::Invalid {
                name: object.name().to_string(),
                source,
            })?;
            let files = write_object(object, dir)?;
            Ok((i as u32 + 1, files, info))
        })
        .collect()
}

//! Wavefront OBJ loading (via `tobj`) with MTL materials and PNG/JPEG diffuse textures.

use super::obj_precheck::{face_index_out_of_range, short_colour_line};
use super::texture::srgb_to_linear;
use super::{Material, Mesh, MeshError, MeshParts, MeshWarning, Texture};
use nalgebra::{Point3, Vector3};
use std::cell::RefCell;
use std::collections::HashMap;
use std::io::{BufReader, Cursor};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How to interpret a mesh file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshLoadOptions {
    /// Multiplies every coordinate on load (e.g. `0.001` for a mesh authored in millimetres). Finite, > 0.
    pub scale: f64,
    /// A loaded diameter above this (metres) triggers [`MeshWarning::LikelyMillimetres`].
    pub millimetre_warning_diameter: f64,
}

impl Default for MeshLoadOptions {
    fn default() -> Self {
        Self {
            scale: 1.0,
            millimetre_warning_diameter: 5.0,
        }
    }
}

/// A loaded mesh with the warnings found while loading it (callers should log them).
#[derive(Debug, Clone)]
pub struct LoadedMesh {
    /// The mesh, in metres.
    pub mesh: Mesh,
    /// Non-fatal problems.
    pub warnings: Vec<MeshWarning>,
}

fn read_file(path: &Path) -> Result<Vec<u8>, MeshError> {
    std::fs::read(path).map_err(|error| MeshError::Read {
        path: path.to_path_buf(),
        error,
    })
}

fn load_texture(path: &Path, material: &str) -> Result<Texture, MeshError> {
    let bytes = read_file(path)?;
    let bad = |reason: String| MeshError::Texture {
        path: path.to_path_buf(),
        material: material.to_string(),
        reason,
    };
    let image = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| bad(e.to_string()))?
        .decode()
        .map_err(|e| bad(e.to_string()))?
        .into_rgb8();
    let (w, h) = image.dimensions();
    Texture::from_srgb8(w, h, image.as_raw())
        .ok_or_else(|| bad(format!("unusable image size {w}x{h}")))
}

/// Converts tobj materials, loading each distinct texture once.
fn convert_materials(
    obj_dir: &Path,
    materials: &[tobj::Material],
) -> Result<Vec<(Material, Option<PathBuf>)>, MeshError> {
    let mut cache: HashMap<PathBuf, Arc<Texture>> = HashMap::new();
    materials
        .iter()
        .map(|m| {
            let diffuse = m.diffuse.unwrap_or([1.0, 1.0, 1.0]);
            let texture_path = m.diffuse_texture.as_ref().map(|t| obj_dir.join(t.trim()));
            let texture = match &texture_path {
                None => None,
                Some(p) => Some(match cache.get(p) {
                    Some(t) => t.clone(),
                    None => {
                        let t = Arc::new(load_texture(p, &m.name)?);
                        cache.insert(p.clone(), t.clone());
                        t
                    }
                }),
            };
            // MTL Kd values are conventionally sRGB-ish display values in [0, 1]; treat them as sRGB and linearise.
            let lin = diffuse.map(|c| srgb_to_linear((c.clamp(0.0, 1.0) * 255.0).round() as u8));
            Ok((
                Material {
                    name: m.name.clone(),
                    diffuse: lin,
                    texture,
                },
                texture_path,
            ))
        })
        .collect()
}

/// Loads an OBJ file (triangulating polygons) with its MTL materials and diffuse textures, scaled by
/// `options.scale` into metres.
///
/// Errors name the file at fault: the OBJ, a missing or malformed MTL, a missing or undecodable texture, or a mesh
/// that is empty or has non-finite vertices.
pub fn load_obj(path: &Path, options: &MeshLoadOptions) -> Result<LoadedMesh, MeshError> {
    if !(options.scale.is_finite() && options.scale > 0.0) {
        return Err(MeshError::InvalidScale {
            path: path.to_path_buf(),
            scale: options.scale,
        });
    }
    let bytes = read_file(path)?;
    if let Some(reason) = face_index_out_of_range(&bytes) {
        return Err(MeshError::Parse {
            path: path.to_path_buf(),
            kind: "OBJ",
            reason,
        });
    }
    let obj_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    // The material loader cannot return our error type; remember which MTL failed and why.
    let mtl_failure: RefCell<Option<MeshError>> = RefCell::new(None);
    let load_options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj_buf(
        &mut BufReader::new(Cursor::new(bytes)),
        &load_options,
        |mtl| {
            let mtl_path = obj_dir.join(mtl);
            let record = |e: MeshError| {
                mtl_failure.borrow_mut().get_or_insert(e);
            };
            match std::fs::read(&mtl_path) {
                Ok(data) => {
                    if let Some(reason) = short_colour_line(&data) {
                        record(MeshError::Parse {
                            path: mtl_path.clone(),
                            kind: "MTL",
                            reason,
                        });
                        return Err(tobj::LoadError::MaterialParseError);
                    }
                    tobj::load_mtl_buf(&mut BufReader::new(Cursor::new(data))).inspect_err(|e| {
                        record(MeshError::Parse {
                            path: mtl_path.clone(),
                            kind: "MTL",
                            reason: e.to_string(),
                        })
                    })
                }
                Err(error) => {
                    record(MeshError::Read {
                        path: mtl_path.clone(),
                        error,
                    });
                    Err(tobj::LoadError::OpenFileFailed)
                }
            }
        },
    )
    .map_err(|e| MeshError::Parse {
        path: path.to_path_buf(),
        kind: "OBJ",
        reason: e.to_string(),
    })?;
    if let Some(e) = mtl_failure.into_inner() {
        return Err(e);
    }
    let materials = materials.map_err(|e| MeshError::Parse {
        path: path.to_path_buf(),
        kind: "MTL",
        reason: e.to_string(),
    })?;
    let converted = convert_materials(path.parent().unwrap_or(Path::new("")), &materials)?;

    let mut warnings = Vec::new();
    let mut parts = MeshParts::default();
    let any_uvs = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    let all_normals = models
        .iter()
        .all(|m| !m.mesh.normals.is_empty() || m.mesh.indices.is_empty());
    // One extra default material for faces without one, appended only if needed.
    let default_material = converted.len() as u32;
    let mut uses_default = false;
    let scale = options.scale as f32;
    for model in &models {
        let m = &model.mesh;
        let base = parts.positions.len() as u32;
        let count = m.positions.len() / 3;
        parts.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Point3::new(p[0], p[1], p[2]) * scale),
        );
        if all_normals {
            parts.normals.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|n| Vector3::new(n[0], n[1], n[2])),
            );
        }
        if any_uvs {
            if m.texcoords.len() == count * 2 {
                parts
                    .uvs
                    .extend(m.texcoords.chunks_exact(2).map(|t| [t[0], t[1]]));
            } else {
                parts.uvs.extend(std::iter::repeat_n([0.0, 0.0], count));
            }
        }
        let material = match m.material_id {
            Some(id) if id < converted.len() => id as u32,
            _ => {
                uses_default = true;
                default_material
            }
        };
        for tri in m.indices.chunks_exact(3) {
            // Out-of-range indices are reported by Mesh::new (after the offset, still out of range).
            parts
                .triangles
                .push([base + tri[0], base + tri[1], base + tri[2]]);
            parts.triangle_materials.push(material);
        }
    }
    for (material, texture_path) in &converted {
        if material.texture.is_some() && !any_uvs && texture_path.is_some() {
            warnings.push(MeshWarning::TextureWithoutUvs {
                path: path.to_path_buf(),
                material: material.name.clone(),
            });
        }
    }
    parts.materials = converted.into_iter().map(|(m, _)| m).collect();
    if uses_default {
        if !parts.materials.is_empty() {
            warnings.push(MeshWarning::MissingMaterial {
                path: path.to_path_buf(),
            });
        }
        parts.materials.push(Material::default());
    }
    let mesh = Mesh::new(path, parts)?;
    if mesh.diameter() > options.millimetre_warning_diameter {
        warnings.push(MeshWarning::LikelyMillimetres {
            path: path.to_path_buf(),
            diameter: mesh.diameter(),
        });
    }
    Ok(LoadedMesh { mesh, warnings })
}

//! Triangle meshes of tracked objects and static background: loading (OBJ + MTL + PNG/JPEG texture), validation,
//! measurements (bounding box, diameter), area-weighted surface sampling, BOP-style object information and render
//! meshes simplified within a tolerance.
//!
//! All geometry is in the object frame, metres. A [`Mesh`] is immutable once built and always valid: non-empty, finite,
//! indices in range, attribute arrays consistent.

mod error;
mod info;
mod measure;
mod obj;
mod obj_precheck;
mod simplify;
pub(crate) mod texture;

pub use error::{MeshError, MeshWarning};
pub use info::{ObjectInfo, ObjectInfoError, Symmetry};
pub use measure::{Aabb, SurfacePoint};
pub use obj::{LoadedMesh, MeshLoadOptions, load_obj};
pub use simplify::{Simplification, simplify_for_render};
pub use texture::Texture;

use nalgebra::{Point3, Vector3};
use std::path::PathBuf;
use std::sync::Arc;

/// The position `p` (metres) rounded to whole micrometres: vertices with equal keys are one point. Exporters and
/// lathes often leave seams whose two copies differ in the last bits; the CPU renderer's closedness test and the
/// render-mesh simplifier weld them by this key.
pub(crate) fn weld_key(p: [f32; 3]) -> [i64; 3] {
    p.map(|v| (f64::from(v) * 1e6).round() as i64)
}

/// A surface material: a diffuse (Lambertian) albedo, optionally modulated by a texture.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Material name (from the MTL file, or chosen by the generator).
    pub name: String,
    /// Diffuse albedo, linear RGB in `[0, 1]` (MTL `Kd`), multiplied with the texture when there is one.
    pub diffuse: [f32; 3],
    /// Diffuse texture (MTL `map_Kd`), shared between meshes that use the same image.
    pub texture: Option<Arc<Texture>>,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            diffuse: [0.6, 0.6, 0.6],
            texture: None,
        }
    }
}

/// The raw parts of a mesh, validated by [`Mesh::new`].
#[derive(Debug, Clone, Default)]
pub struct MeshParts {
    /// Vertex positions, object frame, metres.
    pub positions: Vec<Point3<f32>>,
    /// Optional per-vertex normals (object frame; normalised on construction). Empty = flat (face) normals.
    pub normals: Vec<Vector3<f32>>,
    /// Optional per-vertex texture coordinates (OBJ convention: `v = 0` is the bottom row of the image). Empty = none.
    pub uvs: Vec<[f32; 2]>,
    /// Triangles as vertex indices; counter-clockwise seen from outside by convention (the renderer is two-sided).
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle (into `materials`); empty = every triangle uses material 0.
    pub triangle_materials: Vec<u32>,
    /// Materials; empty = one default grey material.
    pub materials: Vec<Material>,
}

/// A validated triangle mesh with materials, in metres, with its bounding box and diameter precomputed.
#[derive(Debug, Clone)]
pub struct Mesh {
    source: PathBuf,
    positions: Vec<Point3<f32>>,
    normals: Option<Vec<Vector3<f32>>>,
    uvs: Option<Vec<[f32; 2]>>,
    triangles: Vec<[u32; 3]>,
    triangle_materials: Vec<u32>,
    materials: Vec<Material>,
    aabb: Aabb,
    diameter: f64,
    area: f64,
}

impl Mesh {
    /// Validates `parts` and builds a mesh. `source` names the input (a file path or a generator name) in errors.
    pub fn new(source: impl Into<PathBuf>, parts: MeshParts) -> Result<Self, MeshError> {
        let path = source.into();
        let MeshParts {
            positions,
            normals,
            uvs,
            triangles,
            mut triangle_materials,
            mut materials,
        } = parts;
        if positions.is_empty() || triangles.is_empty() {
            return Err(MeshError::Empty { path });
        }
        if let Some((vertex, p)) = positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFiniteVertex {
                path,
                vertex,
                value: [p.x, p.y, p.z],
            });
        }
        let n = positions.len();
        for (what, len) in [
            ("normals", normals.len()),
            ("texture coordinates", uvs.len()),
        ] {
            if len != 0 && len != n {
                return Err(MeshError::AttributeCount {
                    path,
                    what,
                    expected: n,
                    found: len,
                });
            }
        }
        if let Some(vertex) = uvs
            .iter()
            .position(|uv| !(uv[0].is_finite() && uv[1].is_finite()))
        {
            return Err(MeshError::NonFiniteAttribute {
                path,
                what: "texture coordinate",
                vertex,
            });
        }
        if let Some(vertex) = normals
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NonFiniteAttribute {
                path,
                what: "normal",
                vertex,
            });
        }
        for (triangle, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(MeshError::IndexOutOfRange {
                    path,
                    triangle,
                    index,
                    vertex_count: n,
                });
            }
        }
        if materials.is_empty() {
            materials.push(Material::default());
        }
        if triangle_materials.is_empty() {
            triangle_materials = vec![0; triangles.len()];
        } else if triangle_materials.len() != triangles.len() {
            return Err(MeshError::AttributeCount {
                path,
                what: "triangle materials",
                expected: triangles.len(),
                found: triangle_materials.len(),
            });
        }
        if let Some(triangle) = triangle_materials
            .iter()
            .position(|&m| m as usize >= materials.len())
        {
            return Err(MeshError::MaterialOutOfRange {
                path,
                triangle,
                material: triangle_materials[triangle],
                material_count: materials.len(),
            });
        }
        // Normalise supplied normals; a zero normal falls back to flat shading for the whole mesh.
        let normals = if normals.is_empty() || normals.iter().any(|v| v.norm_squared() == 0.0) {
            None
        } else {
            Some(normals.into_iter().map(|v| v.normalize()).collect())
        };
        let area = measure::total_area(&positions, &triangles);
        if area <= 0.0 {
            return Err(MeshError::ZeroArea { path });
        }
        let aabb = Aabb::of_points(&positions);
        let diameter = measure::diameter(&positions);
        Ok(Self {
            source: path,
            positions,
            normals,
            uvs: if uvs.is_empty() { None } else { Some(uvs) },
            triangles,
            triangle_materials,
            materials,
            aabb,
            diameter,
            area,
        })
    }

    /// Where the mesh came from (file path or generator name), for messages.
    pub fn source(&self) -> &std::path::Path {
        &self.source
    }
    /// Vertex positions, object frame, metres.
    pub fn positions(&self) -> &[Point3<f32>] {
        &self.positions
    }
    /// Unit per-vertex normals, if the mesh has them (otherwise renderers use face normals).
    pub fn normals(&self) -> Option<&[Vector3<f32>]> {
        self.normals.as_deref()
    }
    /// Per-vertex texture coordinates (OBJ convention, `v` up), if any.
    pub fn uvs(&self) -> Option<&[[f32; 2]]> {
        self.uvs.as_deref()
    }
    /// Triangles as vertex indices (all in range).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// Material index of each triangle (all in range of [`Mesh::materials`]).
    pub fn triangle_materials(&self) -> &[u32] {
        &self.triangle_materials
    }
    /// Materials (at least one).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }
    /// Axis-aligned bounding box, object frame, metres.
    pub fn aabb(&self) -> Aabb {
        self.aabb
    }
    /// Diameter: the largest distance between two vertices, metres (BOP's definition).
    pub fn diameter(&self) -> f64 {
        self.diameter
    }
    /// Total surface area, square metres.
    pub fn surface_area(&self) -> f64 {
        self.area
    }

    /// Samples `count` points uniformly over the surface (area-weighted over triangles, uniform within each), using
    /// `rng` so that callers control determinism.
    pub fn sample_surface<R: rand::Rng + ?Sized>(
        &self,
        count: usize,
        rng: &mut R,
    ) -> Vec<SurfacePoint> {
        measure::sample_surface(self.positions(), self.triangles(), count, rng)
    }

    /// [`Mesh::sample_surface`] with a ChaCha8 generator seeded by `seed` (deterministic across platforms).
    pub fn sample_surface_seeded(&self, count: usize, seed: u64) -> Vec<SurfacePoint> {
        use rand::SeedableRng;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        self.sample_surface(count, &mut rng)
    }
}

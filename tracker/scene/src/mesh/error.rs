//! Errors and warnings raised while loading or building meshes. Every variant names the input it is about.

use std::path::PathBuf;

/// Why a mesh could not be loaded or built.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A file (OBJ, MTL or texture) could not be read: missing, a directory, no permission.
    #[error("cannot read {}: {error}", path.display())]
    Read {
        /// The file that could not be read.
        path: PathBuf,
        /// The underlying I/O error (in the message, so not also a source).
        error: std::io::Error,
    },
    /// An OBJ or MTL file is malformed.
    #[error("malformed {kind} file {}: {reason}", path.display())]
    Parse {
        /// The malformed file.
        path: PathBuf,
        /// `"OBJ"` or `"MTL"`.
        kind: &'static str,
        /// What the parser reported.
        reason: String,
    },
    /// A texture image referenced by a material could not be decoded.
    #[error("cannot decode texture {} (material '{material}'): {reason}", path.display())]
    Texture {
        /// The texture file.
        path: PathBuf,
        /// The material that references it.
        material: String,
        /// What the decoder reported.
        reason: String,
    },
    /// The mesh has no vertices or no triangles.
    #[error("mesh {} is empty: it has no triangles", path.display())]
    Empty {
        /// The mesh input.
        path: PathBuf,
    },
    /// A vertex position is NaN or infinite.
    #[error(
        "mesh {} has a non-finite vertex position {value:?} (#{vertex} in the loaded mesh's order, which may \
         differ from the file's `v` lines)",
        path.display()
    )]
    NonFiniteVertex {
        /// The mesh input.
        path: PathBuf,
        /// Index of the first bad vertex.
        vertex: usize,
        /// Its coordinates.
        value: [f32; 3],
    },
    /// A normal or texture coordinate is NaN or infinite.
    #[error("mesh {} has a non-finite {what} at vertex #{vertex}", path.display())]
    NonFiniteAttribute {
        /// The mesh input.
        path: PathBuf,
        /// `"normal"` or `"texture coordinate"`.
        what: &'static str,
        /// Index of the first bad vertex.
        vertex: usize,
    },
    /// A per-vertex or per-triangle attribute array has the wrong length.
    #[error("mesh {} has {found} {what}, expected {expected}", path.display())]
    AttributeCount {
        /// The mesh input.
        path: PathBuf,
        /// Which attribute.
        what: &'static str,
        /// Expected count.
        expected: usize,
        /// Actual count.
        found: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("mesh {} triangle #{triangle} refers to vertex {index} but there are {vertex_count} vertices", path.display())]
    IndexOutOfRange {
        /// The mesh input.
        path: PathBuf,
        /// Index of the bad triangle.
        triangle: usize,
        /// The out-of-range vertex index.
        index: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A triangle refers to a material that does not exist.
    #[error("mesh {} triangle #{triangle} uses material {material} but there are {material_count}", path.display())]
    MaterialOutOfRange {
        /// The mesh input.
        path: PathBuf,
        /// Index of the bad triangle.
        triangle: usize,
        /// The out-of-range material index.
        material: u32,
        /// Number of materials.
        material_count: usize,
    },
    /// Every triangle is degenerate, so the mesh has no surface.
    #[error("mesh {} has zero surface area (all triangles degenerate)", path.display())]
    ZeroArea {
        /// The mesh input.
        path: PathBuf,
    },
    /// The requested load scale is not a finite positive number.
    #[error("invalid scale {scale} for mesh {}: must be finite and > 0", path.display())]
    InvalidScale {
        /// The mesh input.
        path: PathBuf,
        /// The rejected scale.
        scale: f64,
    },
}

/// Something suspicious about a mesh that does not prevent using it.
#[derive(Debug, Clone, PartialEq)]
pub enum MeshWarning {
    /// The mesh is much larger than a hand-held object, as if its units were millimetres while metres are expected.
    LikelyMillimetres {
        /// The mesh file.
        path: PathBuf,
        /// Its diameter as loaded, in (supposed) metres.
        diameter: f64,
    },
    /// A material has a texture but the mesh has no texture coordinates, so the texture is ignored.
    TextureWithoutUvs {
        /// The mesh file.
        path: PathBuf,
        /// The material.
        material: String,
    },
    /// Some faces reference no material; they use the default grey.
    MissingMaterial {
        /// The mesh file.
        path: PathBuf,
    },
}

impl std::fmt::Display for MeshWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::LikelyMillimetres { path, diameter } => write!(
                f,
                "mesh {} has a diameter of {diameter:.1} m: it looks like millimetres, metres are expected \
                 (load it with scale 0.001)",
                path.display()
            ),
            Self::TextureWithoutUvs { path, material } => write!(
                f,
                "mesh {}: material '{material}' has a texture but the mesh has no texture coordinates",
                path.display()
            ),
            Self::MissingMaterial { path } => {
                write!(
                    f,
                    "mesh {}: some faces have no material; using default grey",
                    path.display()
                )
            }
        }
    }
}

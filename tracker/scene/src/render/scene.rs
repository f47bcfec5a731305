//! What to render: posed object instances, static background meshes and the lighting.

use super::MeshId;
use nalgebra::{Isometry3, Vector3};

/// Mask value of pixels where nothing was rendered.
pub const MASK_EMPTY: u16 = 0;
/// Mask value of pixels covered by a static background mesh.
pub const MASK_BACKGROUND: u16 = u16::MAX;

/// One tracked object to render: a registered mesh at a pose, labelled `id` in the mask.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneObject {
    /// The mesh, as registered with the renderer.
    pub mesh: MeshId,
    /// `T_cam_obj`: maps object-frame points (metres) into the camera frame.
    pub pose: Isometry3<f64>,
    /// Mask label, in `1..=65534` (0 is empty, 65535 is background).
    pub id: u16,
}

/// A static background mesh (table, wall, clutter): rendered and shaded like an object, labelled
/// [`MASK_BACKGROUND`] in the mask.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BackgroundMesh {
    /// The mesh, as registered with the renderer.
    pub mesh: MeshId,
    /// `T_cam_mesh`, metres.
    pub pose: Isometry3<f64>,
}

/// Lambertian + ambient lighting: `intensity = albedo * (ambient + diffuse * max(0, n . l))`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lighting {
    /// Unit direction from the surface towards a distant light, camera frame (x right, y down, z forward).
    pub direction: Vector3<f64>,
    /// Ambient term, unitless, `>= 0`.
    pub ambient: f64,
    /// Diffuse (directional) term, unitless, `>= 0`.
    pub diffuse: f64,
}

impl Default for Lighting {
    /// A light slightly above the camera, shining along the optical axis.
    fn default() -> Self {
        Self {
            direction: Vector3::new(0.0, -0.3, -1.0).normalize(),
            ambient: 0.3,
            diffuse: 0.7,
        }
    }
}

/// A scene: object instances, static background meshes, lighting and the near clipping distance.
///
/// Borrowed slices so the tracker can build a scene per tick without allocating.
#[derive(Debug, Clone, Copy)]
pub struct Scene<'a> {
    /// Tracked objects.
    pub objects: &'a [SceneObject],
    /// Static background meshes.
    pub background: &'a [BackgroundMesh],
    /// Lighting.
    pub lighting: Lighting,
    /// Near clipping distance along z, metres (> 0); surfaces closer than this are cut away.
    pub near: f64,
    /// Whether the intensity channel is wanted. When `false` the backends skip texturing and lighting and leave
    /// intensity at 0; depth, normals and mask are unaffected.
    pub shade_intensity: bool,
    /// Which object pixels need a surface normal.
    pub normals: NormalCoverage,
}

/// Which object pixels of a render get a surface normal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalCoverage {
    /// Every rendered pixel.
    Everywhere,
    /// At least the pixels of each object's surface sampling grid: `u` and `v` both multiples of
    /// [`surface_grid_stride`]`(visible, max_samples)`, where `visible` is the number of pixels of that object in the
    /// render. Other pixels may hold a zero normal. Only honoured when intensity is not shaded (shading needs every
    /// normal); a backend may always write more normals than asked.
    SurfaceGrid {
        /// Most surface samples the caller takes per object.
        max_samples: usize,
    },
}

/// Pitch (pixels) of the grid on which refinement samples an object's surface: the smallest that keeps the samples
/// of `visible` object pixels under about `max_samples`. At least 1.
pub fn surface_grid_stride(visible: usize, max_samples: usize) -> usize {
    ((visible as f64 / max_samples.max(1) as f64).sqrt().ceil() as usize).max(1)
}

impl<'a> Scene<'a> {
    /// Default near clipping distance, metres.
    pub const DEFAULT_NEAR: f64 = 0.01;

    /// A scene of objects only, with default lighting and near plane.
    pub fn objects(objects: &'a [SceneObject]) -> Self {
        Self {
            objects,
            background: &[],
            lighting: Lighting::default(),
            near: Self::DEFAULT_NEAR,
            shade_intensity: true,
            normals: NormalCoverage::Everywhere,
        }
    }

    /// The same scene without the intensity channel (geometry for tracking: depth, normals, mask).
    pub fn geometry_only(self) -> Self {
        Self {
            shade_intensity: false,
            ..self
        }
    }

    /// The same scene with normals only where surface sampling on a grid of at most `max_samples` points per object
    /// reads them (see [`NormalCoverage::SurfaceGrid`]).
    pub fn normals_on_surface_grid(self, max_samples: usize) -> Self {
        Self {
            normals: NormalCoverage::SurfaceGrid { max_samples },
            ..self
        }
    }

    /// The same scene with static background meshes.
    pub fn with_background(self, background: &'a [BackgroundMesh]) -> Self {
        Self { background, ..self }
    }
}

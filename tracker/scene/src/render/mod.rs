//! Rendering of posed meshes into depth, normals, object mask and shaded intensity, for a full image or a region of
//! interest with any pinhole intrinsics.
//!
//! [`Renderer`] is the interface; [`CpuRenderer`] the deterministic CPU rasteriser; `GpuRenderer` (cargo feature
//! `gpu`, on by default) the same outputs on `wgpu` over Vulkan. [`create_renderer`] picks one by [`RendererKind`]
//! (as a configuration file names it). Every backend implements the same trait: meshes are registered once (uploaded) and referred to by [`MeshId`]; every render writes into a caller-owned
//! [`RenderTarget`] whose buffers are reused, so rendering per tick does not allocate in steady state.
//!
//! Rendering a region of interest is rendering with the ROI's intrinsics ([`PinholeCamera::crop`]);
//! [`Renderer::render_roi`] does exactly that.

mod ahead;
mod cpu;
#[cfg(feature = "gpu")]
mod gpu;
mod scene;
mod target;

pub use ahead::RenderAhead;
pub use cpu::CpuRenderer;
#[cfg(feature = "gpu")]
pub use gpu::GpuRenderer;
pub use scene::{
    BackgroundMesh, Lighting, MASK_BACKGROUND, MASK_EMPTY, NormalCoverage, Scene, SceneObject,
    surface_grid_stride,
};
pub use target::RenderTarget;

use crate::geometry::{CameraError, PinholeCamera, Roi};
use crate::mesh::Mesh;
use std::sync::Arc;

/// Handle of a mesh registered with a particular renderer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MeshId(pub(crate) u32);

/// The largest image a renderer accepts, in pixels (guards against absurd intrinsics allocating gigabytes).
pub const MAX_PIXELS: u64 = 1 << 26;

/// Why a render was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    /// The scene refers to a mesh this renderer does not know.
    #[error("unknown mesh handle {0:?} (not registered with this renderer)")]
    UnknownMesh(MeshId),
    /// An object id is reserved (0 = empty, 65535 = background).
    #[error("object id {0} is reserved: use 1..=65534")]
    ReservedObjectId(u16),
    /// A pose is not finite.
    #[error("pose of {what} is not finite")]
    NonFinitePose {
        /// Which instance (e.g. `object 3`, `background 0`).
        what: String,
    },
    /// The camera intrinsics are invalid.
    #[error(transparent)]
    Camera(#[from] CameraError),
    /// The image is larger than [`MAX_PIXELS`].
    #[error("image {width}x{height} exceeds the renderer's limit of {MAX_PIXELS} pixels")]
    ImageTooLarge {
        /// Width, pixels.
        width: u32,
        /// Height, pixels.
        height: u32,
    },
    /// More instances than the renderer can label.
    #[error("scene has {0} instances; at most 65535 are supported")]
    TooManyInstances(usize),
    /// The near clipping distance is not finite and positive.
    #[error("near clipping distance {0} must be finite and > 0")]
    InvalidNear(f64),
    /// A backend-specific failure (e.g. a GPU device error).
    #[error("renderer backend failed: {0}")]
    Backend(String),
    /// The requested backend cannot run here (no Vulkan adapter, or built without the `gpu` feature).
    #[error("renderer unavailable: {0}")]
    Unavailable(String),
}

/// Which renderer backend to use; in configuration files `"cpu"` or `"gpu"`.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum RendererKind {
    /// [`CpuRenderer`]: deterministic, no device needed (the default).
    #[default]
    Cpu,
    /// `GpuRenderer`: `wgpu` over Vulkan (a GPU, or Mesa's lavapipe on a CPU); needs the `gpu` feature.
    Gpu,
}

/// A renderer name that is neither `cpu` nor `gpu`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown renderer `{0}`: expected `cpu` or `gpu`")]
pub struct ParseRendererKindError(pub String);

impl std::str::FromStr for RendererKind {
    type Err = ParseRendererKindError;

    /// Parses `cpu` or `gpu` (case-insensitive, surrounding blanks ignored).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cpu" => Ok(Self::Cpu),
            "gpu" => Ok(Self::Gpu),
            _ => Err(ParseRendererKindError(s.to_owned())),
        }
    }
}

impl std::fmt::Display for RendererKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Cpu => "cpu",
            Self::Gpu => "gpu",
        })
    }
}

/// Creates a renderer of the given kind, ready to be moved to the tracker's thread.
///
/// `Gpu` fails with [`RenderError::Unavailable`] when there is no Vulkan adapter (install a driver, e.g. Debian's
/// `mesa-vulkan-drivers` for lavapipe) or when this build lacks the `gpu` feature.
pub fn create_renderer(kind: RendererKind) -> Result<Box<dyn Renderer + Send>, RenderError> {
    match kind {
        RendererKind::Cpu => Ok(Box::new(CpuRenderer::new())),
        #[cfg(feature = "gpu")]
        RendererKind::Gpu => Ok(Box::new(GpuRenderer::new()?)),
        #[cfg(not(feature = "gpu"))]
        RendererKind::Gpu => Err(RenderError::Unavailable(
            "the GPU renderer was not built: rebuild with the `gpu` cargo feature of eventtrack6d (on by default)"
                .into(),
        )),
    }
}

/// How a renderer's prefetched renders were used ([`Renderer::prefetch_roi`]).
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct PrefetchCounts {
    /// Renders started ahead of their request.
    pub started: u64,
    /// Of them, renders a later request took (the rest were replaced unread: the request differed).
    pub used: u64,
}

/// The hardware a renderer draws on, as the operator should know it: what a run reports, and whether the choice
/// is a slow one on this machine.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RenderDevice {
    /// [`CpuRenderer`]: the deterministic rasteriser, on the tracker's own threads.
    CpuRasteriser,
    /// `GpuRenderer`: a Vulkan adapter through `wgpu`.
    Vulkan {
        /// The adapter's name, driver and device type, as the driver reports them.
        adapter: String,
        /// Whether the driver rasterises on the CPU (Mesa's lavapipe): no GPU does the work.
        on_cpu: bool,
    },
}

impl RenderDevice {
    /// The warning an operator should see for this device, or `None`: a Vulkan driver that rasterises on the CPU
    /// is slower than the CPU renderer (BENCHMARKS.md, "One tracker tick: CPU against wgpu"), so choosing it is almost always a
    /// mistake (no GPU driver installed, or none found).
    pub fn warning(&self) -> Option<String> {
        match self {
            Self::Vulkan {
                adapter,
                on_cpu: true,
            } => Some(format!(
                "renderer \"gpu\" draws on {adapter}, a Vulkan driver that rasterises on this machine's CPU: no GPU \
                 is in use, and the \"cpu\" renderer is faster here (choose renderer \"cpu\", or install the GPU's \
                 Vulkan driver)"
            )),
            _ => None,
        }
    }
}

impl std::fmt::Display for RenderDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::CpuRasteriser => f.write_str("cpu (deterministic rasteriser)"),
            Self::Vulkan { adapter, on_cpu } => write!(
                f,
                "gpu: {adapter}{}",
                if *on_cpu {
                    " (rasterised on the CPU)"
                } else {
                    ""
                }
            ),
        }
    }
}

/// A renderer of posed triangle meshes. Object-safe: the tracker may hold a `Box<dyn Renderer>`.
pub trait Renderer {
    /// Registers a mesh (for a GPU backend: uploads it) and returns its handle for this renderer.
    fn add_mesh(&mut self, mesh: Arc<Mesh>) -> Result<MeshId, RenderError>;

    /// The hardware this renderer draws on.
    fn device(&self) -> RenderDevice;

    /// Renders `scene` as seen by `camera` into `target` (resized to the camera's image size). The output is a pure
    /// function of the scene, the camera and the registered meshes.
    fn render(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError>;

    /// Renders the region of interest `roi` of `camera`'s image at the ROI's output resolution.
    fn render_roi(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        roi: &Roi,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        self.render(scene, &camera.crop(roi), target)
    }

    /// Starts rendering the ROI `roi` of `camera` ahead of time (the tracker's next tick at its predicted pose), so a
    /// later [`Self::render_roi`] of the same scene, camera and ROI takes the finished image instead of rendering
    /// again; any other render is unaffected. Returns whether a render was started (or is already in flight); the
    /// default renders only on request and returns `false`. Prefetching never changes what a render returns.
    fn prefetch_roi(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        roi: &Roi,
    ) -> Result<bool, RenderError> {
        let _ = (scene, camera, roi);
        Ok(false)
    }

    /// Gives up the renders started ahead that no request took yet: no later request will (the tracker calls it
    /// before it prefetches the next tick's renders), so their buffers can be reused for the next ones instead of
    /// new ones being made. The default has nothing to give up.
    fn forget_prefetched(&mut self) {}

    /// Whether [`Self::prefetch_roi`] starts renders (the GPU backend, [`RenderAhead`]). The tracker wraps a
    /// renderer that does not in a [`RenderAhead`] when it prefetches renders.
    fn renders_ahead(&self) -> bool {
        false
    }

    /// Renders started by [`Self::prefetch_roi`] and taken by a later render, since the renderer was made.
    fn prefetch_counts(&self) -> PrefetchCounts {
        PrefetchCounts::default()
    }

    /// An independent renderer with the same meshes under the same handles, for another thread; `None` when the
    /// backend has no cheap way to make one (the GPU backend: one device queue). Both render identically.
    fn fork(&self) -> Option<Box<dyn Renderer + Send>> {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renderer_kind_parses_prints_and_deserialises_in_lower_case() {
        for (kind, name) in [(RendererKind::Cpu, "cpu"), (RendererKind::Gpu, "gpu")] {
            assert_eq!(kind.to_string(), name);
            assert_eq!(name.parse::<RendererKind>(), Ok(kind));
            assert_eq!(name.to_uppercase().parse::<RendererKind>(), Ok(kind));
            let json = format!("\"{name}\"");
            assert_eq!(serde_json::to_string(&kind).ok(), Some(json.clone()));
            assert_eq!(serde_json::from_str::<RendererKind>(&json).ok(), Some(kind));
        }
        let err = "vulkan".parse::<RendererKind>().unwrap_err();
        assert!(err.to_string().contains("`vulkan`"), "{err}");
        assert!(serde_json::from_str::<RendererKind>("\"Gpu\"").is_err());
        assert_eq!(RendererKind::default(), RendererKind::Cpu);
    }

    #[test]
    fn only_a_vulkan_driver_on_the_cpu_is_warned_about() {
        let lavapipe = RenderDevice::Vulkan {
            adapter: "llvmpipe (LLVM 15.0.6, 256 bits) (Mesa 22.3.6, Cpu)".into(),
            on_cpu: true,
        };
        let warning = lavapipe.warning().expect("lavapipe is warned about");
        assert!(warning.contains("llvmpipe (LLVM 15.0.6"), "{warning}");
        assert!(warning.contains("\"cpu\" renderer is faster"), "{warning}");
        assert_eq!(
            lavapipe.to_string(),
            "gpu: llvmpipe (LLVM 15.0.6, 256 bits) (Mesa 22.3.6, Cpu) (rasterised on the CPU)"
        );
        let hardware = RenderDevice::Vulkan {
            adapter: "NVIDIA H100 (NVIDIA 550.54, DiscreteGpu)".into(),
            on_cpu: false,
        };
        assert_eq!(hardware.warning(), None);
        assert_eq!(
            hardware.to_string(),
            "gpu: NVIDIA H100 (NVIDIA 550.54, DiscreteGpu)"
        );
        assert_eq!(RenderDevice::CpuRasteriser.warning(), None);
        let cpu = create_renderer(RendererKind::Cpu).expect("CPU renderer always exists");
        assert_eq!(cpu.device(), RenderDevice::CpuRasteriser);
        assert_eq!(
            RenderAhead::new(cpu).device(),
            RenderDevice::CpuRasteriser,
            "rendering ahead keeps the inner renderer's device"
        );
    }

    #[test]
    fn cpu_renderer_is_created_by_kind() {
        let mut r = create_renderer(RendererKind::Cpu).expect("CPU renderer always exists");
        let mut target = RenderTarget::new();
        let camera = PinholeCamera::new(100.0, 100.0, 15.5, 11.5, 32, 24).expect("camera");
        r.render(&Scene::objects(&[]), &camera, &mut target)
            .expect("empty scene");
        assert_eq!((target.width(), target.height()), (32, 24));
    }

    #[cfg(not(feature = "gpu"))]
    #[test]
    fn gpu_kind_without_the_feature_says_how_to_get_it() {
        let err = create_renderer(RendererKind::Gpu)
            .err()
            .expect("no GPU backend built");
        assert!(
            matches!(&err, RenderError::Unavailable(m) if m.contains("`gpu` cargo feature")),
            "{err}"
        );
    }
}

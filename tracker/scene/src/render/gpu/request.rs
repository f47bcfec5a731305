//! What one render's image depends on, and renders started ahead of the request that reads them (prefetch).
//!
//! The tracker asks, at the end of a tick, for the next tick's ROI at its predicted pose. The device rasterises
//! while the caller does other work (or waits for the next tick), and the next tick's identical request takes the
//! finished image instead of rendering again. An image is taken only for a bit-identical request, so prefetching
//! never changes what a render returns.

use super::frame::Targets;
use super::readback::{MapResult, Unpacked};
use crate::geometry::PinholeCamera;
use std::sync::Arc;

/// Renders kept in flight at most: enough for the objects of a typical scene, each with two renders ahead (the
/// tracker prefetches for the two whole microseconds its next tick may fall on).
pub(super) const PREFETCH_SLOTS: usize = 8;

/// One posed instance of a render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Instance {
    pub(super) mesh: usize,
    /// Cull sign used for this instance (0 for background meshes, which may surround the camera).
    pub(super) cull: i8,
}

/// Everything a render's image depends on besides the registered meshes: the camera, the frame uniform's bytes
/// (intrinsics, size, near plane, lighting, shading), the instance uniforms' bytes (poses as `f32`, mask labels)
/// and the meshes drawn with their culling. Equal requests give identical images.
#[derive(Debug, Default, PartialEq)]
pub(super) struct RenderRequest {
    pub(super) camera: Option<PinholeCamera>,
    pub(super) frame: Vec<u8>,
    pub(super) instances: Vec<u8>,
    pub(super) draws: Vec<Instance>,
    /// Whether intensity is shaded (the full pipelines), else geometry only.
    pub(super) shade_intensity: bool,
}

impl RenderRequest {
    /// Makes `self` equal to `other`, reusing its buffers.
    pub(super) fn assign(&mut self, other: &Self) {
        self.camera = other.camera;
        self.frame.clone_from(&other.frame);
        self.instances.clone_from(&other.instances);
        self.draws.clone_from(&other.draws);
        self.shade_intensity = other.shade_intensity;
    }

    /// The image size, pixels.
    pub(super) fn size(&self) -> (u32, u32) {
        self.camera.map_or((0, 0), |c| (c.width, c.height))
    }
}

/// A render started ahead of its request: its own output targets and readback buffer, the request it answers and
/// its image once the read-back thread has unpacked it.
#[derive(Debug, Default)]
pub(super) struct PrefetchSlot {
    pub(super) targets: Option<Targets>,
    pub(super) request: RenderRequest,
    pub(super) mapped: MapResult,
    pub(super) unpacked: Arc<Unpacked>,
    /// Whether the slot holds a render not yet taken (in flight, being unpacked or unpacked).
    pub(super) holds_render: bool,
}

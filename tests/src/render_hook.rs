//! A renderer wrapper that runs a hook around every render, for tests and benches that watch how a tracker
//! renders.

use scene::geometry::{PinholeCamera, Roi};
use scene::mesh::Mesh;
use scene::render::{
    MeshId, PrefetchCounts, RenderDevice, RenderError, RenderTarget, Renderer, Scene,
};
use std::sync::Arc;

/// Renders with `inner`, calling the hook first on every render (ROI renders included; prefetches, which render
/// nothing the caller sees yet, are passed on without it) and holding what it returns until that render is done, so a guard's `Drop` runs right after it; forks share the hook.
pub struct HookedRenderer<G = ()> {
    inner: Box<dyn Renderer + Send>,
    hook: Arc<dyn Fn() -> G + Send + Sync>,
}

impl<G: 'static> HookedRenderer<G> {
    /// `inner`, with `hook` run before each of its renders and its result dropped after it.
    pub fn new(
        inner: Box<dyn Renderer + Send>,
        hook: impl Fn() -> G + Send + Sync + 'static,
    ) -> Self {
        Self {
            inner,
            hook: Arc::new(hook),
        }
    }
}

impl<G: 'static> Renderer for HookedRenderer<G> {
    fn add_mesh(&mut self, mesh: Arc<Mesh>) -> Result<MeshId, RenderError> {
        self.inner.add_mesh(mesh)
    }

    fn device(&self) -> RenderDevice {
        self.inner.device()
    }

    fn render(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        let _during = (self.hook)();
        self.inner.render(scene, camera, target)
    }

    fn prefetch_roi(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        roi: &Roi,
    ) -> Result<bool, RenderError> {
        self.inner.prefetch_roi(scene, camera, roi)
    }

    fn prefetch_counts(&self) -> PrefetchCounts {
        self.inner.prefetch_counts()
    }

    fn forget_prefetched(&mut self) {
        self.inner.forget_prefetched();
    }

    fn renders_ahead(&self) -> bool {
        self.inner.renders_ahead()
    }

    fn fork(&self) -> Option<Box<dyn Renderer + Send>> {
        Some(Box::new(Self {
            inner: self.inner.fork()?,
            hook: self.hook.clone(),
        }))
    }
}

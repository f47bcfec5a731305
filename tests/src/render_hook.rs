//! A renderer wrapper that runs a hook before every render, for tests that watch how a tracker renders.

use std::sync::Arc;
use tracker::geometry::PinholeCamera;
use tracker::mesh::Mesh;
use tracker::render::{MeshId, RenderError, RenderTarget, Renderer, Scene};

/// Renders with `inner`, calling the hook first on every render (ROI renders included); forks share the hook.
pub struct HookedRenderer {
    inner: Box<dyn Renderer + Send>,
    hook: Arc<dyn Fn() + Send + Sync>,
}

impl HookedRenderer {
    /// `inner`, with `hook` run before each of its renders.
    pub fn new(inner: Box<dyn Renderer + Send>, hook: impl Fn() + Send + Sync + 'static) -> Self {
        Self {
            inner,
            hook: Arc::new(hook),
        }
    }
}

impl Renderer for HookedRenderer {
    fn add_mesh(&mut self, mesh: Arc<Mesh>) -> Result<MeshId, RenderError> {
        self.inner.add_mesh(mesh)
    }

    fn render(
        &mut self,
        scene: &Scene<'_>,
        camera: &PinholeCamera,
        target: &mut RenderTarget,
    ) -> Result<(), RenderError> {
        (self.hook)();
        self.inner.render(scene, camera, target)
    }

    fn fork(&self) -> Option<Box<dyn Renderer + Send>> {
        Some(Box::new(Self {
            inner: self.inner.fork()?,
            hook: self.hook.clone(),
        }))
    }
}

//! Caller-owned, reusable output buffers of a render.

use crate::geometry::PinholeCamera;

/// The outputs of one render, row-major, `width x height`, for the camera (or ROI camera) that was rendered.
///
/// Buffers keep their capacity between renders: rendering repeatedly at the same (or a smaller) size does not
/// allocate. Pixels where nothing was rendered hold depth 0, normal `[0, 0, 0]`, mask
/// [`MASK_EMPTY`](super::MASK_EMPTY) and intensity 0.
#[derive(Debug, Clone, Default)]
pub struct RenderTarget {
    pub(crate) camera: Option<PinholeCamera>,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) depth: Vec<f32>,
    pub(crate) normals: Vec<[f32; 3]>,
    pub(crate) mask: Vec<u16>,
    pub(crate) intensity: Vec<f32>,
}

impl RenderTarget {
    /// An empty target; buffers grow on first render.
    pub fn new() -> Self {
        Self::default()
    }

    /// A target with buffers preallocated for `width x height`.
    pub fn with_capacity(width: u32, height: u32) -> Self {
        let mut t = Self::default();
        t.reset(width, height);
        t
    }

    /// Resizes to `width x height` without clearing: pixels keep stale values until the caller writes them, so
    /// the caller must write every pixel (the CPU renderer's shading pass does, background included).
    pub(crate) fn resize_for_overwrite(&mut self, width: u32, height: u32) {
        let n = width as usize * height as usize;
        self.width = width;
        self.height = height;
        self.depth.resize(n, 0.0);
        self.intensity.resize(n, 0.0);
        self.normals.resize(n, [0.0; 3]);
        self.mask.resize(n, super::MASK_EMPTY);
    }

    /// Resizes to `width x height` and clears every pixel to "nothing rendered" (no reallocation when capacity allows).
    pub(crate) fn reset(&mut self, width: u32, height: u32) {
        let n = width as usize * height as usize;
        self.width = width;
        self.height = height;
        for (buf, v) in [(&mut self.depth, 0.0), (&mut self.intensity, 0.0)] {
            buf.clear();
            buf.resize(n, v);
        }
        self.normals.clear();
        self.normals.resize(n, [0.0; 3]);
        self.mask.clear();
        self.mask.resize(n, 0);
    }

    /// The camera (full or ROI intrinsics) of the last render, if any.
    pub fn camera(&self) -> Option<&PinholeCamera> {
        self.camera.as_ref()
    }
    /// Width, pixels.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Height, pixels.
    pub fn height(&self) -> u32 {
        self.height
    }
    /// Depth along the optical axis (z), metres; 0 where nothing was rendered.
    pub fn depth(&self) -> &[f32] {
        &self.depth
    }
    /// Unit surface normals in the camera frame, oriented towards the camera; zero where nothing was rendered.
    pub fn normals(&self) -> &[[f32; 3]] {
        &self.normals
    }
    /// Object ids ([`SceneObject::id`](super::SceneObject::id)), [`MASK_BACKGROUND`](super::MASK_BACKGROUND) or
    /// [`MASK_EMPTY`](super::MASK_EMPTY).
    pub fn mask(&self) -> &[u16] {
        &self.mask
    }
    /// Shaded linear intensity (albedo luminance times Lambertian + ambient lighting); 0 where nothing was rendered.
    pub fn intensity(&self) -> &[f32] {
        &self.intensity
    }
    /// Row-major index of pixel `(u, v)`, if inside.
    pub fn index(&self, u: u32, v: u32) -> Option<usize> {
        (u < self.width && v < self.height).then(|| v as usize * self.width as usize + u as usize)
    }
}

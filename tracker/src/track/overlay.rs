//! Overlay images: the reconstructed intensity `I_t` with each object's silhouette outline at its estimated pose,
//! for looking at what the tracker does.

use super::{PoseEstimate, TrackingState};
use crate::geometry::PinholeCamera;
use crate::mesh::Mesh;
use crate::recon::EventSurface;
use crate::render::{CpuRenderer, MeshId, RenderError, RenderTarget, Renderer, Scene, SceneObject};
use image::{Rgb, RgbImage};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Draws overlays with its own CPU renderer (the tracker's renderer stays untouched).
pub struct OverlayRenderer {
    camera: PinholeCamera,
    renderer: CpuRenderer,
    meshes: Vec<MeshId>,
    scene: Vec<SceneObject>,
    target: RenderTarget,
    /// Gray levels per unit of log intensity.
    pub gain: f32,
}

impl std::fmt::Debug for OverlayRenderer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OverlayRenderer")
            .field("camera", &self.camera)
            .finish_non_exhaustive()
    }
}

impl OverlayRenderer {
    /// An overlay renderer for `camera` (the event camera) and the tracked objects' meshes, in object order.
    pub fn new(camera: PinholeCamera, meshes: &[Arc<Mesh>]) -> Result<Self, RenderError> {
        let mut renderer = CpuRenderer::new();
        let ids = meshes
            .iter()
            .map(|m| renderer.add_mesh(m.clone()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            camera,
            renderer,
            scene: Vec::with_capacity(ids.len()),
            meshes: ids,
            target: RenderTarget::new(),
            gain: 160.0,
        })
    }

    /// The overlay at `t_us`: `I_t` from `surface` in gray, each object's outline at its estimate (green when
    /// tracking, yellow when degraded, red when lost).
    pub fn draw(
        &mut self,
        surface: &EventSurface,
        t_us: i64,
        estimates: &[PoseEstimate],
    ) -> Result<RgbImage, RenderError> {
        let (w, h) = (self.camera.width, self.camera.height);
        let mut img = RgbImage::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let l = surface.log_intensity_at(x, y, t_us);
                let g = (128.0 + self.gain * l).clamp(0.0, 255.0) as u8;
                img.put_pixel(x, y, Rgb([g, g, g]));
            }
        }
        self.scene.clear();
        for e in estimates {
            if let Some(&mesh) = self.meshes.get(e.object) {
                self.scene.push(SceneObject {
                    mesh,
                    pose: e.pose,
                    id: (e.object + 1) as u16,
                });
            }
        }
        self.renderer
            .render(&Scene::objects(&self.scene), &self.camera, &mut self.target)?;
        let mask = self.target.mask();
        let (wu, hu) = (w as usize, h as usize);
        for y in 0..hu {
            for x in 0..wu {
                let id = mask[y * wu + x];
                if id == 0 || id == u16::MAX {
                    continue;
                }
                let edge = x == 0
                    || y == 0
                    || x + 1 == wu
                    || y + 1 == hu
                    || mask[y * wu + x - 1] != id
                    || mask[y * wu + x + 1] != id
                    || mask[(y - 1) * wu + x] != id
                    || mask[(y + 1) * wu + x] != id;
                if !edge {
                    continue;
                }
                let state = estimates
                    .iter()
                    .find(|e| e.object + 1 == id as usize)
                    .map_or(TrackingState::Lost, |e| e.state);
                let colour = match state {
                    TrackingState::Tracking => Rgb([40, 230, 60]),
                    TrackingState::Degraded => Rgb([240, 210, 30]),
                    TrackingState::Lost => Rgb([240, 40, 40]),
                };
                img.put_pixel(x as u32, y as u32, colour);
            }
        }
        Ok(img)
    }
}

/// Writes every `every`-th tick's overlay as `DIR/overlay_<tick>.png`.
#[derive(Debug)]
pub struct OverlayWriter {
    dir: PathBuf,
    every: u64,
    renderer: OverlayRenderer,
    written: u64,
}

impl OverlayWriter {
    /// A writer into `dir` (created if missing) drawing one tick in `every` (at least 1).
    pub fn new(dir: &Path, every: u64, renderer: OverlayRenderer) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        Ok(Self {
            dir: dir.to_path_buf(),
            every: every.max(1),
            renderer,
            written: 0,
        })
    }

    /// Overlays written so far.
    pub fn written(&self) -> u64 {
        self.written
    }

    /// Draws and writes tick `index` if it is one of the drawn ticks.
    pub fn tick(
        &mut self,
        index: u64,
        surface: &EventSurface,
        t_us: i64,
        estimates: &[PoseEstimate],
    ) -> Result<(), String> {
        if index % self.every != 0 {
            return Ok(());
        }
        let img = self
            .renderer
            .draw(surface, t_us, estimates)
            .map_err(|e| format!("overlay render: {e}"))?;
        let path = self.dir.join(format!("overlay_{index:06}.png"));
        img.save(&path)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        self.written += 1;
        Ok(())
    }
}

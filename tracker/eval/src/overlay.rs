//! Overlay images: the reconstructed intensity `I_t` with each object's silhouette outline at its estimated pose,
//! for looking at what the tracker does.

use image::{Rgb, RgbImage};
use scene::geometry::PinholeCamera;
use scene::mesh::Mesh;
use scene::render::{CpuRenderer, MeshId, RenderError, RenderTarget, Renderer, Scene, SceneObject};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tracker::recon::EventSurface;
use tracker::recording::{PoseRecord, recording_object, recording_rig};
use tracker::track::{DepthHandling, PoseEstimate, PoseTracker, TrackingState, track_recording};

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
    /// A writer into `dir` (created if missing) drawing one tick in `every` (at least 1). The error names the
    /// directory.
    pub fn new(dir: &Path, every: u64, renderer: OverlayRenderer) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir).map_err(|e| {
            std::io::Error::new(
                e.kind(),
                format!("cannot create the overlay directory {}: {e}", dir.display()),
            )
        })?;
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
        if !index.is_multiple_of(self.every) {
            return Ok(());
        }
        if !surface.reconstructs_intensity() {
            return Err(
                "the tracker keeps no intensity I_t to draw (set its `intensity.always = true`)"
                    .into(),
            );
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

/// Replays a pose file over its recording and plays back the poses as a tracker would report them (nearest
/// record at or before each tick), so the offline driver can draw overlays of any method's output.
struct PosePlayback {
    names: Vec<String>,
    /// Per object, its records in time order.
    records: Vec<Vec<(i64, PoseEstimate)>>,
    surface: EventSurface,
}

impl PoseTracker for PosePlayback {
    fn objects(&self) -> &[String] {
        &self.names
    }
    fn push_events(&mut self, events: &[drivers::event::CdEvent]) {
        self.surface.integrate(events);
    }
    fn push_depth(
        &mut self,
        _t_us: i64,
        _frame: &mut drivers::recording::DepthFrame,
        _handling: DepthHandling,
    ) {
    }
    fn tick(&mut self, tick: &drivers::timeline::Tick, out: &mut Vec<PoseEstimate>) {
        for k in 0..self.names.len() {
            if let Some(e) = self.pose_at(k, tick.t_us) {
                out.push(e);
            }
        }
    }
    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        let r = self.records.get(object)?;
        let i = r.partition_point(|(t, _)| *t <= t_us);
        r.get(i.checked_sub(1)?)
            .map(|(_, e)| PoseEstimate { t_us, ..*e })
    }
    fn event_surface(&self) -> Option<&EventSurface> {
        Some(&self.surface)
    }
}

/// An image strip of `frames` overlays spread over `recording`, each cropped to `crop` pixels around the first
/// object: the reconstructed intensity with every object's outline at the pose `poses` gives at that tick.
pub fn overlay_strip(
    recording: &drivers::recording::Recording,
    poses: &[PoseRecord],
    frames: usize,
    crop: u32,
) -> Result<RgbImage, String> {
    let mut names: Vec<String> = Vec::new();
    for p in poses {
        if !names.contains(&p.object) {
            names.push(p.object.clone());
        }
    }
    if names.is_empty() || frames == 0 {
        return Err("no poses to draw".into());
    }
    let mut records = vec![Vec::new(); names.len()];
    for p in poses {
        let k = names.iter().position(|n| n == &p.object).unwrap_or(0);
        let state = match p.state.as_str() {
            "lost" => TrackingState::Lost,
            "degraded" => TrackingState::Degraded,
            _ => TrackingState::Tracking,
        };
        records[k].push((
            p.t_us,
            PoseEstimate {
                object: k,
                t_us: p.t_us,
                pose: p.pose,
                quality: p.quality as f32,
                state,
            },
        ));
    }
    for r in &mut records {
        r.sort_by_key(|(t, _)| *t);
    }
    let rig = recording_rig(recording).map_err(|e| e.to_string())?;
    let meshes = names
        .iter()
        .map(|n| {
            recording_object(recording, n, 0, nalgebra::Isometry3::identity())
                .map(|o| o.mesh)
                .map_err(|e| e.to_string())
        })
        .collect::<Result<Vec<_>, _>>()?;
    let cam = rig.event_camera;
    let mut renderer = OverlayRenderer::new(cam, &meshes).map_err(|e| e.to_string())?;
    let t_first = records[0].first().map_or(0, |(t, _)| *t);
    let t_last = records[0].last().map_or(0, |(t, _)| *t);
    let wanted: Vec<i64> = (0..frames)
        .map(|i| t_first + (t_last - t_first) * (2 * i as i64 + 1) / (2 * frames as i64))
        .collect();
    let mut playback = PosePlayback {
        names,
        records,
        surface: EventSurface::new(cam.width, cam.height, Default::default()),
    };
    let side = crop.min(cam.width).min(cam.height);
    let mut strip = RgbImage::new(side * frames as u32, side);
    let mut next = 0usize;
    let mut error = None;
    track_recording(
        recording,
        &mut playback,
        t_first,
        |tick, estimates, t| {
            if next >= wanted.len() || tick.t_us < wanted[next] || error.is_some() {
                return;
            }
            let Some(surface) = t.event_surface() else {
                return;
            };
            match renderer.draw(surface, tick.t_us, estimates) {
                Ok(img) => {
                    let center = estimates
                        .first()
                        .and_then(|e| cam.project(&(e.pose * nalgebra::Point3::origin())))
                        .unwrap_or(nalgebra::Point2::new(cam.cx, cam.cy));
                    let x0 = (center.x as i64 - i64::from(side) / 2)
                        .clamp(0, i64::from(cam.width - side)) as u32;
                    let y0 = (center.y as i64 - i64::from(side) / 2)
                        .clamp(0, i64::from(cam.height - side)) as u32;
                    for y in 0..side {
                        for x in 0..side {
                            strip.put_pixel(
                                next as u32 * side + x,
                                y,
                                *img.get_pixel(x0 + x, y0 + y),
                            );
                        }
                    }
                }
                Err(e) => error = Some(e.to_string()),
            }
            next += 1;
        },
        |_| {},
    )
    .map_err(|e| e.to_string())?;
    if let Some(e) = error {
        return Err(e);
    }
    Ok(strip)
}

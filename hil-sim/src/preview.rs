//! Pictures of a recording for a person to look at: accumulated events with the ground-truth contour, and the
//! depth frame, at chosen times.

use drivers::event::{CdEvent, EventSink, TriggerEdge};
use drivers::recording::{Recording, RecordingError};
use image::{Rgb, RgbImage};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use scene::geometry::PinholeCamera;
use scene::mesh::{MeshLoadOptions, load_obj};
use scene::render::{CpuRenderer, RenderTarget, Renderer, Scene, SceneObject};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Length of the event window shown before each time, microseconds.
pub const EVENT_WINDOW_US: i64 = 5_000;

/// Why a preview failed.
#[derive(Debug, thiserror::Error)]
pub enum PreviewError {
    /// The recording is unreadable.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The object's mesh is unreadable.
    #[error(transparent)]
    Mesh(#[from] scene::mesh::MeshError),
    /// Rendering the contour failed.
    #[error(transparent)]
    Render(#[from] scene::render::RenderError),
    /// Writing a picture failed.
    #[error("{path}: {reason}")]
    Write {
        /// The picture.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// A requested time is outside the recording.
    #[error("time {t_s} s is outside the recording (0 .. {end_s:.3} s)")]
    TimeOutside {
        /// Requested time, seconds.
        t_s: f64,
        /// Last event time, seconds.
        end_s: f64,
    },
}

struct Windows<'a> {
    windows: &'a [(i64, i64)],
    images: Vec<RgbImage>,
    width: u32,
    last_t: i64,
}

impl EventSink for Windows<'_> {
    fn cd(&mut self, e: CdEvent) {
        self.last_t = self.last_t.max(e.t_us);
        for (k, &(a, b)) in self.windows.iter().enumerate() {
            if e.t_us > a && e.t_us <= b && u32::from(e.x) < self.width {
                let px = self.images[k].get_pixel_mut(u32::from(e.x), u32::from(e.y));
                *px = if e.polarity {
                    Rgb([235, 60, 40])
                } else {
                    Rgb([40, 90, 235])
                };
            }
        }
    }

    fn trigger(&mut self, _: TriggerEdge) {}
}

/// Writes `events_<ms>.png` (events of the last 5 ms in red = ON / blue = OFF on white, ground-truth contour
/// in green) and `depth_<ms>.png` (the latest depth frame at or before the time, near = bright) for each time
/// into `out`. Returns the written files.
pub fn write_previews(
    dir: &Path,
    times_s: &[f64],
    out: &Path,
) -> Result<Vec<PathBuf>, PreviewError> {
    let rec = Recording::open(dir)?;
    let ev = &rec.rig.event_camera;
    let windows: Vec<(i64, i64)> = times_s
        .iter()
        .map(|t| {
            (
                (t * 1e6).round() as i64 - EVENT_WINDOW_US,
                (t * 1e6).round() as i64,
            )
        })
        .collect();
    let mut sink = Windows {
        windows: &windows,
        images: windows
            .iter()
            .map(|_| RgbImage::from_pixel(ev.width, ev.height, Rgb([255, 255, 255])))
            .collect(),
        width: ev.width,
        last_t: 0,
    };
    rec.events()?
        .read_all(&mut sink)
        .map_err(|e| RecordingError {
            path: dir.join("events.raw"),
            problem: e.to_string(),
        })?;
    for &t in times_s {
        if !t.is_finite() || t < 0.0 || t * 1e6 > sink.last_t as f64 + 1.0 {
            return Err(PreviewError::TimeOutside {
                t_s: t,
                end_s: sink.last_t as f64 * 1e-6,
            });
        }
    }
    let camera = PinholeCamera {
        fx: ev.fx,
        fy: ev.fy,
        cx: ev.cx,
        cy: ev.cy,
        width: ev.width,
        height: ev.height,
    };
    let mut renderer = CpuRenderer::new();
    let mut meshes = Vec::new();
    for m in &rec.models {
        let mesh = load_obj(&rec.mesh_path(&m.name), &MeshLoadOptions::default())?.mesh;
        meshes.push((m.name.clone(), renderer.add_mesh(Arc::new(mesh))?));
    }
    std::fs::create_dir_all(out).map_err(|e| PreviewError::Write {
        path: out.into(),
        reason: e.to_string(),
    })?;
    let mut written = Vec::new();
    let mut target = RenderTarget::new();
    for (k, &t) in times_s.iter().enumerate() {
        let t_us = windows[k].1;
        let mut img = std::mem::take(&mut sink.images[k]);
        if let Some(gt) = &rec.ground_truth {
            let mut objects = Vec::new();
            for (i, (name, mesh)) in meshes.iter().enumerate() {
                let nearest = gt
                    .iter()
                    .filter(|p| &p.object == name)
                    .min_by_key(|p| (p.t_us - t_us).abs());
                if let Some(p) = nearest {
                    let [qx, qy, qz, qw] = p.rotation_xyzw;
                    let pose = Isometry3::from_parts(
                        Translation3::new(p.translation[0], p.translation[1], p.translation[2]),
                        UnitQuaternion::from_quaternion(Quaternion::new(qw, qx, qy, qz)),
                    );
                    objects.push(SceneObject {
                        mesh: *mesh,
                        pose,
                        id: i as u16 + 1,
                    });
                }
            }
            renderer.render(&Scene::objects(&objects), &camera, &mut target)?;
            draw_contour(&mut img, target.mask(), Rgb([20, 170, 40]));
        }
        let name = out.join(format!("events_{:07.1}ms.png", t * 1e3));
        img.save(&name).map_err(|e| PreviewError::Write {
            path: name.clone(),
            reason: e.to_string(),
        })?;
        written.push(name);

        let depth_ticks = rec.meta.trigger.ticks_per_depth as f64 / rec.meta.trigger.tick_rate_hz;
        let wanted = (t / depth_ticks).floor().max(0.0) as u64;
        if let Some(&n) = rec.depth_frames.iter().rev().find(|&&n| n <= wanted) {
            let d = rec.depth_frame(n)?;
            let mut dimg = RgbImage::new(d.width, d.height);
            for (i, z) in d.depth_m.iter().enumerate() {
                let v = if *z > 0.0 {
                    (255.0 * (1.0 - ((z - 0.3) / 2.0).clamp(0.0, 1.0))) as u8
                } else {
                    0
                };
                let px = if *z > 0.0 {
                    Rgb([v, v, v])
                } else {
                    Rgb([90, 0, 90])
                };
                dimg.put_pixel(i as u32 % d.width, i as u32 / d.width, px);
            }
            let name = out.join(format!("depth_{:07.1}ms.png", t * 1e3));
            dimg.save(&name).map_err(|e| PreviewError::Write {
                path: name.clone(),
                reason: e.to_string(),
            })?;
            written.push(name);
        }
    }
    Ok(written)
}

fn draw_contour(img: &mut RgbImage, mask: &[u16], colour: Rgb<u8>) {
    let (w, h) = (img.width() as usize, img.height() as usize);
    for y in 0..h {
        for x in 0..w {
            let m = mask[y * w + x];
            if m == 0 {
                continue;
            }
            let edge = [
                (x.wrapping_sub(1), y),
                (x + 1, y),
                (x, y.wrapping_sub(1)),
                (x, y + 1),
            ]
            .iter()
            .any(|&(a, b)| a >= w || b >= h || mask[b * w + a] != m);
            if edge {
                img.put_pixel(x as u32, y as u32, colour);
            }
        }
    }
}

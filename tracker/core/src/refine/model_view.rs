//! What refinement needs from one render of the model at the hypothesis: sparse visible surface points with normals
//! and silhouette (contour) points with outward image normals, stored in the object frame so every iteration can
//! move them with the current pose without re-rendering.

use nalgebra::{Isometry3, Point2, Point3, Vector3};
use scene::geometry::PinholeCamera;
use scene::render::{MASK_BACKGROUND, MASK_EMPTY, RenderTarget, surface_grid_stride};

/// A visible surface point of the model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Position, object frame, metres.
    pub position: Point3<f64>,
    /// Unit outward normal, object frame.
    pub normal: Vector3<f64>,
}

/// A point on the model's silhouette.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContourPoint {
    /// Position, object frame, metres.
    pub position: Point3<f64>,
    /// Unit outward normal of the silhouette in the image (pixels, x right, y down).
    pub normal_2d: [f64; 2],
}

/// The sparse model view of one render.
#[derive(Debug, Clone, Default)]
pub struct ModelView {
    /// Visible surface samples.
    pub surface: Vec<SurfacePoint>,
    /// Silhouette samples (occlusion boundaries with nearer objects excluded).
    pub contour: Vec<ContourPoint>,
    /// Pixels of the object in the render (after occlusion by other objects).
    pub visible_pixels: usize,
    /// Scratch: indices of the render's silhouette pixels, in raster order.
    silhouette: Vec<u32>,
}

impl ModelView {
    /// An empty view with room for `surface` and `contour` samples.
    pub fn with_capacity(surface: usize, contour: usize) -> Self {
        Self {
            surface: Vec::with_capacity(surface),
            contour: Vec::with_capacity(contour),
            visible_pixels: 0,
            silhouette: Vec::new(),
        }
    }

    /// Extracts at most `max_surface` surface and `max_contour` contour samples of object `id` from `target`, a
    /// render with camera `camera` of the scene with the object at `pose`.
    pub fn extract(
        &mut self,
        target: &RenderTarget,
        camera: &PinholeCamera,
        id: u16,
        pose: &Isometry3<f64>,
        max_surface: usize,
        max_contour: usize,
    ) {
        self.surface.clear();
        self.contour.clear();
        let (w, h) = (target.width() as usize, target.height() as usize);
        let mask = target.mask();
        let depth = target.depth();
        let normals = target.normals();
        let inv = pose.inverse();
        // Sized once for the largest render, so steady-state ticks do not allocate.
        self.silhouette.clear();
        self.silhouette.reserve(w * h);
        let mut visible = 0usize;
        for v in 0..h {
            for u in 0..w {
                let i = v * w + u;
                if mask[i] != id {
                    continue;
                }
                visible += 1;
                if is_silhouette(mask, depth, w, h, u, v, id) {
                    self.silhouette.push(i as u32);
                }
            }
        }
        self.visible_pixels = visible;
        if visible == 0 {
            return;
        }
        let unproject = |i: usize| {
            let (u, v) = (i % w, i / w);
            camera.unproject(&Point2::new(u as f64, v as f64), f64::from(depth[i]))
        };
        // Surface samples on a grid whose pitch keeps them under `max_surface`.
        let stride = surface_grid_stride(visible, max_surface);
        'rows: for v in (0..h).step_by(stride) {
            for u in (0..w).step_by(stride) {
                if self.surface.len() >= max_surface {
                    break 'rows;
                }
                let i = v * w + u;
                if mask[i] != id {
                    continue;
                }
                let n = normals[i];
                let n_cam = Vector3::new(f64::from(n[0]), f64::from(n[1]), f64::from(n[2]));
                if n_cam.norm_squared() > 0.5 {
                    self.surface.push(SurfacePoint {
                        position: inv * unproject(i),
                        normal: inv.rotation * n_cam,
                    });
                }
            }
        }
        // Every `contour_step`-th silhouette pixel, in raster order.
        let contour_step = self.silhouette.len().div_ceil(max_contour).max(1);
        for &i in self.silhouette.iter().step_by(contour_step) {
            if self.contour.len() >= max_contour {
                break;
            }
            let i = i as usize;
            if let Some(n2) = outward_normal(mask, w, h, i % w, i / w, id) {
                self.contour.push(ContourPoint {
                    position: inv * unproject(i),
                    normal_2d: n2,
                });
            }
        }
    }
}

impl ModelView {
    /// Drops the silhouette samples that `measured` (a depth image in `camera`, metres, 0 = none) shows hidden at
    /// `pose`: a measurement nearer than the sample by more than `gap` metres is an occluder in front of it (a
    /// hand gripping the object), so no event can come from that part of the outline. When more than
    /// `max_hidden_share` (0..=1) of the samples would go, none is dropped: what would be left is too little to
    /// hold the pose, and the full outline is the better guess. Returns how many were dropped.
    pub fn hide_occluded_contour(
        &mut self,
        measured: &crate::recon::DepthImage,
        camera: &PinholeCamera,
        pose: &Isometry3<f64>,
        gap: f64,
        max_hidden_share: f64,
    ) -> usize {
        let hidden = |c: &ContourPoint| {
            let p = pose * c.position;
            if p.z <= 0.01 {
                return false;
            }
            let u = (camera.fx * p.x / p.z + camera.cx).round() as i32;
            let v = (camera.fy * p.y / p.z + camera.cy).round() as i32;
            let zm = f64::from(measured.at(u, v));
            zm > 0.0 && zm < p.z - gap
        };
        let before = self.contour.len();
        let count = self.contour.iter().filter(|c| hidden(c)).count();
        if count == 0 || count as f64 > max_hidden_share * before as f64 {
            return 0;
        }
        self.contour.retain(|c| !hidden(c));
        count
    }
}

/// Whether object pixel `(u, v)` lies on the silhouette: a 4-neighbour is empty, background or a farther object
/// (a neighbour that is a nearer object is an occlusion boundary, not the object's own outline).
fn is_silhouette(
    mask: &[u16],
    depth: &[f32],
    w: usize,
    h: usize,
    u: usize,
    v: usize,
    id: u16,
) -> bool {
    let i = v * w + u;
    let z = depth[i];
    let check = |j: usize| {
        let m = mask[j];
        m != id && (m == MASK_EMPTY || m == MASK_BACKGROUND || depth[j] > z)
    };
    (u == 0 || check(i - 1))
        || (u + 1 == w || check(i + 1))
        || (v == 0 || check(i - w))
        || (v + 1 == h || check(i + w))
}

/// Outward image normal at a silhouette pixel from the 5x5 neighbourhood's non-object pixels.
fn outward_normal(
    mask: &[u16],
    w: usize,
    h: usize,
    u: usize,
    v: usize,
    id: u16,
) -> Option<[f64; 2]> {
    let (mut nx, mut ny) = (0.0f64, 0.0f64);
    for dv in -2i64..=2 {
        for du in -2i64..=2 {
            let x = u as i64 + du;
            let y = v as i64 + dv;
            let outside = x < 0
                || y < 0
                || x >= w as i64
                || y >= h as i64
                || mask[y as usize * w + x as usize] != id;
            if outside {
                nx += du as f64;
                ny += dv as f64;
            }
        }
    }
    let n = (nx * nx + ny * ny).sqrt();
    (n > 1e-9).then(|| [nx / n, ny / n])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::recon::DepthImage;

    #[test]
    fn outline_behind_a_nearer_surface_is_hidden_and_the_rest_kept() {
        let camera = PinholeCamera::new(100.0, 100.0, 20.0, 20.0, 40, 40).unwrap();
        let pose = Isometry3::translation(0.0, 0.0, 0.6);
        // Four outline samples at 0.6 m, projecting to columns 5, 15, 25 and 35 of row 20.
        let mut view = ModelView::default();
        for x in [-0.09, -0.03, 0.03, 0.09] {
            view.contour.push(ContourPoint {
                position: Point3::new(x, 0.0, 0.0),
                normal_2d: [1.0, 0.0],
            });
        }
        // Columns 0-9: a hand 4 cm in front; 10-19: 1 cm in front (within the gap); 20-29: nothing measured;
        // 30-39: the wall behind.
        let mut measured = DepthImage::default();
        measured.reset(40, 40);
        for v in 0..40 {
            for u in 0..40 {
                measured.z[v * 40 + u] = match u {
                    0..=9 => 0.56,
                    10..=19 => 0.59,
                    20..=29 => 0.0,
                    _ => 1.5,
                };
            }
        }
        assert_eq!(
            view.hide_occluded_contour(&measured, &camera, &pose, 0.025, 1.0),
            1
        );
        let left: Vec<f64> = view.contour.iter().map(|c| c.position.x).collect();
        assert_eq!(left, vec![-0.03, 0.03, 0.09]);
        // A smaller gap takes the surface 1 cm in front for an occluder too: one of three samples, more than a
        // cap of 30 % leaves the outline whole, and no cap drops it.
        assert_eq!(
            view.hide_occluded_contour(&measured, &camera, &pose, 0.005, 0.3),
            0
        );
        assert_eq!(view.contour.len(), 3);
        assert_eq!(
            view.hide_occluded_contour(&measured, &camera, &pose, 0.005, 1.0),
            1
        );
        assert_eq!(view.contour.len(), 2);
    }
}

//! Contrast maximisation ([`EventTermKind::ContrastMax`](super::EventTermKind)): the window's
//! events, each lifted to 3D with the rendered depth, are carried to the tick time by a candidate object velocity;
//! the velocity whose image of warped events is sharpest (largest sum of squared bin counts) is the motion.

use super::bins::EventBins;
use crate::recon::EventSurface;
use nalgebra::{Point2, Point3, Vector3, Vector6};
use scene::geometry::{PinholeCamera, Roi};

/// One event for contrast maximisation: camera-frame point at the render's depth, and its age, seconds.
#[derive(Debug, Clone, Copy)]
struct LiftedEvent {
    point: Point3<f64>,
    age_s: f64,
}

/// The window's events lifted to 3D, and the image of warped events, reused from tick to tick.
#[derive(Debug, Clone, Default)]
pub(super) struct ContrastMax {
    /// The window's events lifted to 3D.
    lifted: Vec<LiftedEvent>,
    /// Scratch: the image of warped events on the ROI grid.
    warped: Vec<f32>,
}

impl ContrastMax {
    /// Lifts the kept events of `bins` to 3D: each pixel's latest event in the window at
    /// the depth the render (`depth`, `mask` on the ROI grid, object `id`) has at its bin, or at `center_z` where
    /// the render shows no object. At most `max_events`, evenly strided.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn lift_events(
        &mut self,
        bins: &EventBins,
        surface: &EventSurface,
        camera: &PinholeCamera,
        depth: &[f32],
        mask: &[u16],
        id: u16,
        t_us: i64,
        window_us: i64,
        center_z: f64,
        max_events: usize,
    ) {
        self.lifted.clear();
        self.lifted.reserve(max_events + 1);
        let Some(roi) = bins.roi else { return };
        let (w, h) = (bins.width as usize, bins.height as usize);
        let sx = bins.width as f64 / roi.width;
        let sy = bins.height as f64 / roi.height;
        let x0 = roi.x.floor().max(0.0) as u32;
        let y0 = roi.y.floor().max(0.0) as u32;
        let x1 = ((roi.x + roi.width).ceil().max(0.0) as u32).min(surface.width());
        let y1 = ((roi.y + roi.height).ceil().max(0.0) as u32).min(surface.height());
        let since = t_us - window_us;
        let total = bins.kept_bins.max(1) * 4;
        let stride = total.div_ceil(max_events.max(1)).max(1);
        let mut seen = 0usize;
        for y in y0..y1 {
            let j = ((f64::from(y) + 0.5 - roi.y) * sy) as usize;
            if j >= h {
                continue;
            }
            for x in surface.recent_in_row(y, x0, x1, 1, since, t_us) {
                let i = ((f64::from(x) + 0.5 - roi.x) * sx) as usize;
                if i >= w || !bins.kept[j * w + i] {
                    continue;
                }
                seen += 1;
                if !(seen - 1).is_multiple_of(stride) || self.lifted.len() >= max_events {
                    continue;
                }
                let Some(t_e) = surface.last_event_us(x, y) else {
                    continue;
                };
                let k = j * w + i;
                let z = if mask.get(k) == Some(&id) && depth[k] > 0.0 {
                    f64::from(depth[k])
                } else {
                    center_z
                };
                self.lifted.push(LiftedEvent {
                    point: camera.unproject(&Point2::new(f64::from(x), f64::from(y)), z),
                    age_s: (t_us - t_e) as f64 * 1e-6,
                });
            }
        }
    }

    /// Sum of squared bin counts of the image of warped events (ROI grid, bilinear votes) under object velocity
    /// `xi` (centre m/s, angular rad/s, camera frame) about `center`.
    fn warped_contrast(
        &mut self,
        bins: &EventBins,
        camera: &PinholeCamera,
        roi: &Roi,
        center: &Point3<f64>,
        xi: &Vector6<f64>,
    ) -> f64 {
        let (w, h) = (bins.width as usize, bins.height as usize);
        self.warped.clear();
        self.warped.resize(w * h, 0.0);
        let sx = bins.width as f64 / roi.width;
        let sy = bins.height as f64 / roi.height;
        let v = Vector3::new(xi[0], xi[1], xi[2]);
        let omega = Vector3::new(xi[3], xi[4], xi[5]);
        for e in &self.lifted {
            let moved = e.point + (v + omega.cross(&(e.point - center))) * e.age_s;
            let Some(uv) = camera.project(&moved) else {
                continue;
            };
            let fi = (uv.x + 0.5 - roi.x) * sx - 0.5;
            let fj = (uv.y + 0.5 - roi.y) * sy - 0.5;
            if !(fi >= 0.0 && fj >= 0.0) {
                continue;
            }
            let (i, j) = (fi as usize, fj as usize);
            if i + 1 >= w || j + 1 >= h {
                continue;
            }
            let (a, b) = ((fi - i as f64) as f32, (fj - j as f64) as f32);
            let k = j * w + i;
            self.warped[k] += (1.0 - a) * (1.0 - b);
            self.warped[k + 1] += a * (1.0 - b);
            self.warped[k + w] += (1.0 - a) * b;
            self.warped[k + w + 1] += a * b;
        }
        self.warped.iter().map(|&c| f64::from(c * c)).sum()
    }

    /// The object velocity (centre m/s, angular rad/s, camera frame, about `center`) that maximises the contrast
    /// of the lifted events, found by a pattern search from `start` (steps halve `rounds` times). Returns `start`
    /// when there are no events.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn maximise_contrast(
        &mut self,
        bins: &EventBins,
        camera: &PinholeCamera,
        center: &Point3<f64>,
        start: &Vector6<f64>,
        step_translation: f64,
        step_rotation: f64,
        rounds: u32,
    ) -> Vector6<f64> {
        let Some(roi) = bins.roi else { return *start };
        if self.lifted.len() < 10 {
            return *start;
        }
        let mut best = *start;
        let mut score = self.warped_contrast(bins, camera, &roi, center, &best);
        let mut steps = [
            step_translation,
            step_translation,
            step_translation,
            step_rotation,
            step_rotation,
            step_rotation,
        ];
        for _ in 0..rounds {
            for k in 0..6 {
                for sign in [1.0, -1.0] {
                    let mut trial = best;
                    trial[k] += sign * steps[k];
                    let s = self.warped_contrast(bins, camera, &roi, center, &trial);
                    if s > score {
                        score = s;
                        best = trial;
                        break;
                    }
                }
            }
            for s in &mut steps {
                *s *= 0.5;
            }
        }
        best
    }

    /// Events lifted by the last [`Self::lift_events`].
    pub(super) fn lifted_events(&self) -> usize {
        self.lifted.len()
    }
}

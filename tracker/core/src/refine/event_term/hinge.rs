//! Silhouette hinge residuals ([`super::EventTermKind::Hinge`]): events outside the
//! silhouette push it outwards, contour points with no event under them are pulled in to the event cloud.

use super::bins::EventBins;
use super::term::{EventTerm, grid_index};
use crate::refine::{ModelView, NormalEquations, normal_offset};
use nalgebra::{Isometry3, Vector3};
use scene::geometry::PinholeCamera;

/// The hinge's matches: each candidate's nearest contour point, and each contour point's nearest kept event bin
/// inwards along its image normal.
#[derive(Debug, Clone, Default)]
pub(super) struct HingeMatches {
    /// Nearest contour point index per candidate (`u32::MAX` = none within range).
    association: Vec<u32>,
    /// Per contour point, the nearest kept event bin along its image normal (full-image pixels), if any.
    contour_match: Vec<Option<[f64; 2]>>,
    /// Contour points projected at the association pose, full-image pixels (NaN behind the camera).
    projected: Vec<[f64; 2]>,
}

impl HingeMatches {
    /// Sizes the candidates' associations for `max_candidates`, so that steady-state ticks do not allocate.
    pub(super) fn reserve(&mut self, max_candidates: usize) {
        self.association.reserve(max_candidates + 1);
    }

    /// Associates every candidate with its nearest contour point of `view` at `pose` (within the term's range),
    /// and every contour point with the nearest kept event bin inwards along its image normal.
    pub(super) fn associate(
        &mut self,
        bins: &EventBins,
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
    ) {
        self.association.clear();
        self.contour_match.clear();
        self.contour_match.reserve(view.contour.capacity());
        if let Some(roi) = bins.roi {
            let sx = f64::from(bins.width) / roi.width;
            let sy = f64::from(bins.height) / roi.height;
            let (wi, hi) = (i64::from(bins.width), i64::from(bins.height));
            let reach = (term.match_distance_px * sx).ceil() as i64;
            for cp in &view.contour {
                let p = pose * cp.position;
                let found = camera.project(&p).and_then(|uv| {
                    let fi = (uv.x + 0.5 - roi.x) * sx - 0.5;
                    let fj = (uv.y + 0.5 - roi.y) * sy - 0.5;
                    let [mx, my] = cp.normal_2d;
                    // Walk inwards: the first kept bin is where the event cloud's outer boundary lies.
                    for k in 0..=reach {
                        let i = grid_index(fi - k as f64 * mx);
                        let j = grid_index(fj - k as f64 * my);
                        if i >= 0 && j >= 0 && i < wi && j < hi && bins.kept[(j * wi + i) as usize]
                        {
                            return Some([
                                roi.x - 0.5 + (i as f64 + 0.5) / sx,
                                roi.y - 0.5 + (j as f64 + 0.5) / sy,
                            ]);
                        }
                    }
                    None
                });
                self.contour_match.push(found);
            }
        }
        let max_d2 = term.max_distance_px * term.max_distance_px;
        self.projected.clear();
        self.projected.reserve(view.contour.capacity());
        for cp in &view.contour {
            let p = pose * cp.position;
            self.projected.push(if p.z > 0.01 {
                [
                    camera.fx * p.x / p.z + camera.cx,
                    camera.fy * p.y / p.z + camera.cy,
                ]
            } else {
                [f64::NAN, f64::NAN]
            });
        }
        for e in &bins.candidates {
            let mut best = (u32::MAX, max_d2);
            for (k, q) in self.projected.iter().enumerate() {
                let du = q[0] - e[0];
                let dv = q[1] - e[1];
                let d2 = du * du + dv * dv;
                // NaN (behind the camera) never compares smaller.
                if d2 < best.1 {
                    best = (k as u32, d2);
                }
            }
            self.association.push(best.0);
        }
    }

    /// Accumulates the hinge residuals of the associated candidates, and the pull of contour points in to the
    /// event cloud, at `pose` into `ne`; `sweep` is each contour point's predicted sweep (full-image pixels along
    /// its outward normal). Returns how many candidates were active.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn accumulate(
        &self,
        bins: &EventBins,
        sweep: &[f64],
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        camera: &PinholeCamera,
        ne: &mut NormalEquations,
    ) -> usize {
        let c = pose * nalgebra::Point3::from(*center_obj);
        let mut active = 0;
        let cutoff = 3.0 * term.sigma_px;
        for (e, &a) in bins.candidates.iter().zip(&self.association) {
            let Some(cp) = view.contour.get(a as usize) else {
                continue;
            };
            // Behind a trailing edge the object has just uncovered the background: events there are expected.
            let allowance = (-sweep.get(a as usize).copied().unwrap_or(0.0)).max(0.0);
            let p = pose * cp.position;
            let Some((offset, grad)) = normal_offset(camera, &p, cp.normal_2d, e) else {
                continue;
            };
            let r = offset - allowance - term.edge_tolerance_px;
            if r <= 0.0 || r > term.max_distance_px {
                continue;
            }
            active += 1;
            // Cauchy-like weight: full within a few sigma, fading beyond.
            let robust = 1.0 / (1.0 + (r / cutoff).powi(2));
            ne.add_point(
                &grad,
                &(p - c),
                r,
                term.hinge_weight * robust / (term.sigma_px * term.sigma_px),
            );
        }
        // The counterpart of the hinge: a moving textured object fills its silhouette with events, so a contour
        // point with no event under it but events a little inwards lies outside the object: pull it in to the
        // event cloud's boundary (keeps the outline from growing to cover everything).
        let s2 = term.sigma_px * term.sigma_px;
        let moving = sweep.iter().any(|s| s.abs() >= term.min_sweep_px);
        for ((cp, m), &swept) in view.contour.iter().zip(&self.contour_match).zip(sweep) {
            let Some(e) = m else {
                continue;
            };
            // Only a moving object fills its silhouette with events.
            if !moving || swept.is_nan() {
                continue;
            }
            let p = pose * cp.position;
            let Some((r, grad)) = normal_offset(camera, &p, cp.normal_2d, e) else {
                continue;
            };
            if r >= 0.0 || r.abs() > 2.0 * term.match_distance_px {
                continue;
            }
            let robust = 1.0 / (1.0 + (r / cutoff).powi(2));
            ne.add_point(&grad, &(p - c), r, term.match_weight * robust / s2);
        }
        active
    }
}

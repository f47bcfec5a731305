//! Correspondence lines ([`super::EventTermKind::Lines`]): the events-to-no-events step along each contour
//! normal and its residuals.

use super::bins::EventBins;
use super::term::{EventTerm, grid_index};
use crate::refine::{ContourResiduals, ModelView, NormalEquations};
use nalgebra::{Isometry3, Vector3};
use scene::geometry::PinholeCamera;

/// The outline step found on each contour point's correspondence line.
#[derive(Debug, Clone, Default)]
pub(super) struct LineMatches {
    /// Per contour point, the outline step found on its correspondence line (full-image pixels) and its contrast.
    line_match: Vec<Option<([f64; 2], f64)>>,
    /// Scratch: one correspondence line's occupancy samples (1 event, 0 none, -1 outside the ROI).
    line_samples: Vec<i8>,
}

impl LineMatches {
    /// Forgets the matches (a term of another kind finds none).
    pub(super) fn clear(&mut self) {
        self.line_match.clear();
    }

    /// Finds, for every contour point of `view` at `pose`, the outline step on its correspondence line; `sweep` is
    /// each contour point's predicted sweep (full-image pixels along its outward normal).
    pub(super) fn find_steps(
        &mut self,
        bins: &EventBins,
        sweep: &[f64],
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
    ) {
        self.line_match.clear();
        self.line_match.reserve(view.contour.capacity());
        let Some(roi) = bins.roi else {
            self.line_match.resize(view.contour.len(), None);
            return;
        };
        let sx = f64::from(bins.width) / roi.width;
        let sy = f64::from(bins.height) / roi.height;
        let (wi, hi) = (i64::from(bins.width), i64::from(bins.height));
        let k = term.line_box_bins.max(1) as i64;
        for (cp, &sweep) in view.contour.iter().zip(sweep) {
            let p = pose * cp.position;
            let Some(uv) = camera.project(&p) else {
                self.line_match.push(None);
                continue;
            };
            let fi = (uv.x + 0.5 - roi.x) * sx - 0.5;
            let fj = (uv.y + 0.5 - roi.y) * sy - 0.5;
            let [mx, my] = cp.normal_2d;
            // The search reaches the largest expected offset plus the trailing band.
            let reach = ((term.max_distance_px + sweep.abs()) * sx).ceil() as i64 + k;
            // Occupancy along the line, sampled once: samples -reach-k..reach+k (-1 outside the ROI).
            let first = -reach - k;
            self.line_samples.clear();
            self.line_samples.extend((first..reach + k).map(|t| {
                let i = grid_index(fi + t as f64 * mx);
                let j = grid_index(fj + t as f64 * my);
                if i >= 0 && j >= 0 && i < wi && j < hi {
                    i8::from(bins.kept[(j * wi + i) as usize])
                } else {
                    -1
                }
            }));
            let expected = (-sweep).max(0.0) * sx;
            let best = best_step(
                &self.line_samples,
                reach,
                k,
                expected,
                term.line_min_contrast,
            );
            self.line_match.push(best.map(|(contrast, at)| {
                let (i, j) = (fi + at * mx, fj + at * my);
                (
                    [roi.x - 0.5 + (i + 0.5) / sx, roi.y - 0.5 + (j + 0.5) / sy],
                    contrast,
                )
            }));
        }
    }

    /// Accumulates the correspondence-line residuals at `pose` into `ne`. Returns how many contributed.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn accumulate(
        &self,
        sweep: &[f64],
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        camera: &PinholeCamera,
        ne: &mut NormalEquations,
    ) -> usize {
        let residuals = ContourResiduals {
            camera,
            center: pose * nalgebra::Point3::from(*center_obj),
            sigma_px: term.sigma_px,
            max_px: term.max_distance_px,
        };
        let mut active = 0;
        for ((cp, m), &sweep) in view.contour.iter().zip(&self.line_match).zip(sweep) {
            let Some((e, contrast)) = m else {
                continue;
            };
            let p = pose * cp.position;
            if residuals.add(
                ne,
                &p,
                cp.normal_2d,
                e,
                (-sweep).max(0.0),
                contrast.min(1.0),
            ) {
                active += 1;
            }
        }
        active
    }
}

/// The outline step on one correspondence line: `samples` holds its occupancy at offsets `-reach - k` to
/// `reach + k - 1` (1 event, 0 none, -1 outside the ROI), `k` the length of each side of the step detector. The
/// step is between samples `b - 1` and `b` for `b` within `reach`, with at least `min_contrast` (fraction of
/// occupied bins inside less outside); of equal contrasts the one nearest `expected` (bins) wins. Returns its
/// contrast and the contour position it gives (`b - 1`).
fn best_step(
    samples: &[i8],
    reach: i64,
    k: i64,
    expected: f64,
    min_contrast: f64,
) -> Option<(f64, f64)> {
    let first = -reach - k;
    let occ = |t: i64| -> Option<u8> {
        let s = samples[(t - first) as usize];
        (s >= 0).then_some(s as u8)
    };
    let mut best: Option<(f64, f64)> = None;
    // A step between samples b-1 and b: inside = [b-k, b), outside = [b, b+k).
    let mut inside = 0i64;
    let mut outside = 0i64;
    let mut valid = true;
    for t in -reach - k..-reach {
        match occ(t) {
            Some(v) => inside += i64::from(v),
            None => valid = false,
        }
    }
    for t in -reach..-reach + k {
        match occ(t) {
            Some(v) => outside += i64::from(v),
            None => valid = false,
        }
    }
    let mut invalid_until = if valid { i64::MIN } else { -reach + k };
    for b in -reach..=reach {
        if b > -reach {
            // slide: sample b-1 moves from outside to inside, b-1-k leaves inside, b+k-1 enters outside
            let (leave, mid, enter) = (occ(b - 1 - k), occ(b - 1), occ(b + k - 1));
            match (leave, mid, enter) {
                (Some(l), Some(m), Some(e)) => {
                    inside += i64::from(m) - i64::from(l);
                    outside += i64::from(e) - i64::from(m);
                }
                _ => {
                    invalid_until = b + 2 * k;
                    // recompute from scratch once the window is back inside the ROI
                    inside = (b - k..b).filter_map(occ).map(i64::from).sum();
                    outside = (b..b + k).filter_map(occ).map(i64::from).sum();
                }
            }
        }
        if b < invalid_until {
            continue;
        }
        let contrast = (inside - outside) as f64 / k as f64;
        if contrast < min_contrast {
            continue;
        }
        // The step lies between samples b-1 and b; the contour point is the centre of the silhouette's
        // last pixel, half a bin inside the outline, so the matching contour position is b - 1.
        let at = b as f64 - 1.0;
        let better = match best {
            None => true,
            Some((c, a)) => {
                contrast > c + 1e-9
                    || ((contrast - c).abs() <= 1e-9
                        && (at - expected).abs() < (a - expected).abs())
            }
        };
        if better {
            best = Some((contrast, at));
        }
    }
    best
}

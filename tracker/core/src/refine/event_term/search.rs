//! The outline shift search: a coarse-to-fine search over image shifts of the whole outline, which reaches
//! motions larger than the residuals' range.

use super::bins::EventBins;
use super::term::EventTerm;
use crate::refine::ModelView;
use nalgebra::Isometry3;
use scene::geometry::{PinholeCamera, Roi};

/// The shift search's buffers, reused from tick to tick.
#[derive(Debug, Clone, Default)]
pub(super) struct ShiftSearch {
    /// Contour points' inside and outside probe bins of the shift search (ROI grid).
    probes: Vec<[[i32; 2]; 4]>,
    /// The probes as indices into [`Self::padded`].
    probe_index: Vec<[usize; 4]>,
    /// The kept bins (1, else 0) inside a border of zeros wide enough that every shifted probe reads inside it.
    padded: Vec<u8>,
    /// The coarse grid's scores and shifts (ROI bins).
    shift_scores: Vec<(i64, i64, i64)>,
}

impl ShiftSearch {
    /// Searches image shifts of `view`'s outline at `pose` (within the term's search range) for the one whose
    /// contour points best separate events inside from no events outside, up to `range_px` (full-image pixels).
    /// `motion_dir` is the unit image direction the object is predicted to move in, if known: near-best shifts
    /// are then told apart by how far they move the outline across it
    /// ([`EventTerm::search_aperture_tolerance`]). Returns the shift in full-image pixels if it beats the
    /// unshifted outline clearly, else `None`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn search(
        &mut self,
        bins: &EventBins,
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
        range_px: f64,
        motion_dir: Option<[f64; 2]>,
    ) -> Option<[f64; 2]> {
        let roi = bins.roi?;
        if range_px <= 0.0 || view.contour.is_empty() || bins.width == 0 || bins.height == 0 {
            return None;
        }
        let sx = f64::from(bins.width) / roi.width;
        let sy = f64::from(bins.height) / roi.height;
        let (wi, hi) = (i64::from(bins.width), i64::from(bins.height));
        self.place_probes(view, pose, camera, &roi, sx, sy);
        if self.probes.is_empty() {
            return None;
        }
        // A shift past the grid's size cannot bring an outline onto it: the bound keeps a tiny ROI (an object
        // estimated far away, many grid bins per pixel) from asking for a search of millions of shifts.
        let range = ((range_px * sx).round() as i64).min(wi.max(hi));
        let wp = self.pad_grid(bins, range);
        let base = score(&self.padded, &self.probe_index, wp, 0, 0);
        let coarse = 3i64;
        let slack = (term.search_aperture_tolerance * (2 * self.probes.len()) as f64) as i64;
        let mut best = self.coarse_scan(range, coarse, wp, base, slack, motion_dir, (sx, sy));
        let (ci, cj) = (best.1, best.2);
        for dj in (cj - coarse + 1).max(-range)..(cj + coarse).min(range + 1) {
            for di in (ci - coarse + 1).max(-range)..(ci + coarse).min(range + 1) {
                let v = score(&self.padded, &self.probe_index, wp, di, dj);
                if v > best.0 {
                    best = (v, di, dj);
                }
            }
        }
        let gain = (best.0 - base) as f64 / (2 * self.probes.len()) as f64;
        (gain >= term.search_min_gain && (best.1, best.2) != (0, 0))
            .then(|| [best.1 as f64 / sx, best.2 as f64 / sy])
    }

    /// The contour points of `view` at `pose` on the ROI grid (`sx`, `sy` bins per full-image pixel), each with its
    /// inside and outside probe bins (two each way along its normal), into `self.probes`.
    fn place_probes(
        &mut self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
        roi: &Roi,
        sx: f64,
        sy: f64,
    ) {
        self.probes.clear();
        self.probes.reserve(view.contour.capacity());
        for cp in &view.contour {
            let Some(uv) = camera.project(&(pose * cp.position)) else {
                continue;
            };
            let fi = (uv.x + 0.5 - roi.x) * sx - 0.5;
            let fj = (uv.y + 0.5 - roi.y) * sy - 0.5;
            let [mx, my] = cp.normal_2d;
            let at = |d: f64| [(fi + d * mx).round() as i32, (fj + d * my).round() as i32];
            self.probes.push([at(-1.0), at(-2.0), at(1.0), at(2.0)]);
        }
    }

    /// Copies the kept bins into a zero-padded grid so that no shift up to `range` needs a bounds check, and
    /// indexes the probes into it; returns the padded grid's width. The border covers the probes' overshoot past
    /// the grid plus the range. A probe farther out than `range + 3` is moved in to that distance: no shift in
    /// range brings it onto the grid either way.
    fn pad_grid(&mut self, bins: &EventBins, range: i64) -> i64 {
        let (wi, hi) = (i64::from(bins.width), i64::from(bins.height));
        let overshoot = self
            .probes
            .iter()
            .flatten()
            .map(|&[i, j]| {
                let (i, j) = (i64::from(i), i64::from(j));
                (-i).max(i - (wi - 1)).max(-j).max(j - (hi - 1))
            })
            .max()
            .unwrap_or(0);
        let margin = overshoot.max(3).min(range + 3);
        let pad = range + margin;
        let (wp, hp) = (wi + 2 * pad, hi + 2 * pad);
        self.padded.clear();
        self.padded.resize((wp * hp) as usize, 0);
        for (src, dst) in bins
            .kept
            .chunks_exact(wi as usize)
            .zip(self.padded[(pad * wp) as usize..].chunks_exact_mut(wp as usize))
        {
            for (d, &k) in dst[pad as usize..].iter_mut().zip(src) {
                *d = u8::from(k);
            }
        }
        self.probe_index.clear();
        self.probe_index.extend(self.probes.iter().map(|q| {
            q.map(|[i, j]| {
                let i = i64::from(i).clamp(-margin, wi - 1 + margin);
                let j = i64::from(j).clamp(-margin, hi - 1 + margin);
                ((j + pad) * wp + i + pad) as usize
            })
        }));
        wp
    }

    /// The best of the shifts every `coarse` bins up to `range` (score, shift in bins), the unshifted outline
    /// scoring `base`. With a known motion direction `motion_dir` and a `slack` above 0, among the shifts within
    /// `slack` of the best the one that moves the outline least across the motion (then least along it) wins;
    /// `scale` is the grid's bins per full-image pixel (x, y).
    #[allow(clippy::too_many_arguments)]
    fn coarse_scan(
        &mut self,
        range: i64,
        coarse: i64,
        wp: i64,
        base: i64,
        slack: i64,
        motion_dir: Option<[f64; 2]>,
        (sx, sy): (f64, f64),
    ) -> (i64, i64, i64) {
        let mut best = (base, 0i64, 0i64);
        let keep_scores = slack > 0 && motion_dir.is_some();
        let side = (2 * range / coarse + 2) as usize;
        self.shift_scores.clear();
        if keep_scores {
            self.shift_scores.reserve(side * side);
        }
        let mut dj = -range;
        while dj <= range {
            let mut di = -range;
            while di <= range {
                let v = score(&self.padded, &self.probe_index, wp, di, dj);
                if keep_scores {
                    self.shift_scores.push((v, di, dj));
                }
                if v > best.0 {
                    best = (v, di, dj);
                }
                di += coarse;
            }
            dj += coarse;
        }
        if let Some([mx, my]) = motion_dir.filter(|_| keep_scores) {
            let floor = best.0 - slack;
            // Squared image distance across the motion, plus a hundredth of the squared distance along it.
            let cost = |di: i64, dj: i64| {
                let (x, y) = (di as f64 / sx, dj as f64 / sy);
                let along = x * mx + y * my;
                let across = x * my - y * mx;
                across * across + 0.01 * along * along
            };
            if base >= floor && cost(0, 0) < cost(best.1, best.2) {
                best = (base, 0, 0);
            }
            for &(v, di, dj) in &self.shift_scores {
                if v >= floor && cost(di, dj) < cost(best.1, best.2) {
                    best = (v, di, dj);
                }
            }
        }
        best
    }
}

/// How well the outline shifted by (`di`, `dj`) bins separates events inside from none outside: the inside probes'
/// kept bins less the outside ones', over every contour point (`probe_index` into `padded`, `wp` wide).
fn score(padded: &[u8], probe_index: &[[usize; 4]], wp: i64, di: i64, dj: i64) -> i64 {
    let off = dj * wp + di;
    let at = |k: usize| i64::from(padded[(k as i64 + off) as usize]);
    probe_index
        .iter()
        .map(|q| at(q[0]) + at(q[1]) - at(q[2]) - at(q[3]))
        .sum()
}

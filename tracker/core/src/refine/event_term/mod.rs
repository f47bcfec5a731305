//! The event modality. The static background produces no events; the tracked object (its outline sweeping over
//! the background and its texture) does, and so do hands and other moving things.
//!
//! Default ([`EventTermKind::Lines`]): along each contour point's image normal, the events of the short window
//! `[t - dt, t]` (binned on the ROI grid, isolated bins removed) should change from "present" (inside: texture and
//! the band the outline swept) to "absent" (outside: background) at the outline. The step found on that line,
//! less the band a trailing edge leaves behind (predicted from the velocity), gives the residual; its contrast is
//! its weight, so a line with events on both sides (a holding hand) gives none. Before refining,
//! [`EventEdges::search_shift`] looks for the image shift of the whole outline that best separates events inside
//! from none outside, which reaches motions of a fast object (tens of pixels per tick) the residuals cannot.
//!
//! Alternative ([`EventTermKind::Hinge`]): events outside the silhouette contribute the hinge residual
//! `max(0, m . (e - pi(P)))` and contour points with no event under them are pulled in to the event cloud. It is
//! biased by events next to the object (see BENCHMARKS.md, "How the event term was chosen").
//!
//! Alternative ([`EventTermKind::ContrastMax`]): no residuals; the object velocity that sharpens the window's
//! events (lifted to 3D at the rendered depth) moves the previous estimate to the refinement's start. It measures
//! motion only and scored far below the lines on the dev suite.

mod collect;
mod contrast;
mod hinge;
mod lines;
mod search;

use super::{ModelView, NormalEquations};
use crate::recon::EventSurface;
pub use collect::BinnedWindow;
use nalgebra::{Isometry3, Vector3, Vector6};
use scene::geometry::{PinholeCamera, Roi};
use scene::render::MASK_EMPTY;

/// Nearest grid index of a sample position, `floor(x + 0.5)`, without the libm call `f64::round` makes on targets
/// without SSE4.1 (it differs from `round` only at negative halves). Every negative index is out of range, so all
/// of them map to -1.
#[inline]
fn grid_index(x: f64) -> i64 {
    let v = x + 0.5;
    if v >= 0.0 { v as i64 } else { -1 }
}

/// How events become residuals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum EventTermKind {
    /// Correspondence lines: along each contour point's image normal, the step from "events" (inside: the object's
    /// texture and its swept band) to "no events" (the static background) is the outline; the residual is that
    /// step's offset from the projected contour, less the band a trailing edge leaves. Lines whose outside is
    /// full of events too (a hand, another object) find no step and drop out.
    Lines,
    /// Silhouette hinge: events outside the silhouette push it outwards, contour points with no event under
    /// them are pulled in to the event cloud (biased by events next to the object, e.g. a holding hand).
    Hinge,
    /// Contrast maximisation with rendered depth: the window's events, lifted to 3D at the rendered depth, are
    /// warped to the tick time by a candidate velocity; the sharpest image of warped events gives the motion,
    /// which moves the previous estimate to the refinement's start (no event residuals in the refinement).
    ContrastMax,
}

/// Parameters of the event term.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EventTerm {
    /// Which residual the events give.
    pub kind: EventTermKind,
    /// Correspondence lines: length of each side of the step detector, ROI bins.
    pub line_box_bins: u32,
    /// Correspondence lines: smallest step contrast (fraction of occupied bins inside minus outside) accepted.
    pub line_min_contrast: f64,
    /// Residual scale, full-image pixels.
    pub sigma_px: f64,
    /// Events farther than this from the silhouette (full-image pixels) are ignored.
    pub max_distance_px: f64,
    /// Minimum number of event bins in a 3x3 neighbourhood for a bin to count (noise filter).
    pub min_neighbours: u8,
    /// How far along its normal a contour point looks for an event edge, full-image pixels.
    pub match_distance_px: f64,
    /// Weight of the contour-to-edge pull relative to the uncovered-event hinge.
    pub match_weight: f64,
    /// Contour points whose predicted sweep in the window is below this (full-image pixels) expect no edge events
    /// and take no part in the contour-to-edge pull.
    pub min_sweep_px: f64,
    /// Events up to this far outside the silhouette (full-image pixels) count as on it: the outline's own
    /// anti-aliased pixels and the binning blur the edge by about a pixel.
    pub edge_tolerance_px: f64,
    /// Weight of the uncovered-event hinge.
    pub hinge_weight: f64,
    /// Before refining, the outline is searched for over image shifts up to this far (full-image pixels) for
    /// the shift whose contour best separates events inside from none outside; 0 disables the search. Once the
    /// motion is known the range shrinks to [`Self::search_speed_factor`] times the predicted image motion per
    /// tick, but not below [`Self::search_min_px`].
    pub search_px: f64,
    /// Smallest search range, full-image pixels.
    pub search_min_px: f64,
    /// Search range as a multiple of the predicted image motion per tick.
    pub search_speed_factor: f64,
    /// A searched shift replaces the prediction only if its score beats the unshifted outline's by this
    /// fraction of the contour points.
    pub search_min_gain: f64,
    /// Once the object's image motion is known (from the third depth frame on) and it slides more than it turns
    /// (its centre moves 2 px per tick or more, and at least as far as turning moves its ends), of the
    /// shifts that score within this fraction of twice the contour points of the best, the search takes the one
    /// that moves the outline least across that motion (then least along it). An edge along the motion fires
    /// no events, so the events hardly tell where the outline is across the motion: a long object moving
    /// sideways scores alike at every shift along its length. 0 (default) takes the best score, the first of
    /// equal ones in scan order; 0.05 measured dev +2.3 and holdout -1.9 ADD-S (BENCHMARKS.md, thirteenth round).
    pub search_aperture_tolerance: f64,
    /// Contrast maximisation: first step of the pattern search over the centre's velocity, m/s.
    pub contrast_step_translation: f64,
    /// Contrast maximisation: first step of the pattern search over the angular velocity, rad/s.
    pub contrast_step_rotation: f64,
    /// Contrast maximisation: halvings of the pattern search's steps.
    pub contrast_rounds: u32,
}

impl Default for EventTerm {
    fn default() -> Self {
        Self {
            kind: EventTermKind::Lines,
            line_box_bins: 3,
            line_min_contrast: 0.5,
            sigma_px: 1.5,
            max_distance_px: 12.0,
            min_neighbours: 2,
            match_distance_px: 6.0,
            match_weight: 0.5,
            min_sweep_px: 0.7,
            edge_tolerance_px: 0.0,
            hinge_weight: 1.0,
            search_px: 30.0,
            search_min_px: 8.0,
            search_speed_factor: 2.0,
            search_min_gain: 0.1,
            search_aperture_tolerance: 0.0,
            contrast_step_translation: 0.25,
            contrast_step_rotation: 3.0,
            contrast_rounds: 5,
        }
    }
}

/// What the event term saw in one evaluation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EventTermStats {
    /// Event bins kept in the ROI after the noise filter.
    pub bins: usize,
    /// Kept bins outside the predicted silhouette (candidates).
    pub outside: usize,
    /// Candidates that contributed a non-zero residual.
    pub active: usize,
}

/// The recent events of one ROI, binned on the ROI grid.
#[derive(Debug, Clone, Default)]
pub struct EventEdges {
    width: u32,
    height: u32,
    hits: Vec<u8>,
    kept: Vec<bool>,
    /// Centres of kept bins outside the predicted silhouette, full-image pixel coordinates.
    candidates: Vec<[f64; 2]>,
    /// Nearest contour point index per candidate (`u32::MAX` = none within range).
    association: Vec<u32>,
    /// Per contour point, the nearest kept event bin along its image normal (full-image pixels), if any.
    contour_match: Vec<Option<[f64; 2]>>,
    /// Per contour point, the outline step found on its correspondence line (full-image pixels) and its contrast.
    line_match: Vec<Option<([f64; 2], f64)>>,
    /// Scratch: one correspondence line's occupancy samples (1 event, 0 none, -1 outside the ROI).
    line_samples: Vec<i8>,
    /// Scratch: ROI column of each image column of the binning box (-1 outside).
    column_bins: Vec<i32>,
    /// Scratch: per bin, occupied bins among itself and its left and right neighbours.
    row_counts: Vec<u8>,
    /// Contrast maximisation: the window's events lifted to 3D.
    lifted: Vec<contrast::LiftedEvent>,
    /// Contrast maximisation scratch: the image of warped events on the ROI grid.
    warped: Vec<f32>,
    /// Contour points' inside and outside probe bins of the shift search (ROI grid).
    probes: Vec<[[i32; 2]; 4]>,
    /// Shift search scratch: the probes as indices into [`Self::padded`].
    probe_index: Vec<[usize; 4]>,
    /// Shift search scratch: the kept bins (1, else 0) inside a border of zeros wide enough that every shifted
    /// probe reads inside it.
    padded: Vec<u8>,
    /// Shift search scratch: the coarse grid's scores and shifts (ROI bins).
    shift_scores: Vec<(i64, i64, i64)>,
    /// Contour points projected at the association pose, full-image pixels (NaN behind the camera).
    projected: Vec<[f64; 2]>,
    /// Per contour point, how far (full-image pixels, along its outward normal) the predicted motion swept it
    /// during the event window: positive on leading edges, negative on trailing edges.
    sweep: Vec<f64>,
    roi: Option<Roi>,
    stats: EventTermStats,
    /// The window [`Self::bin_ahead`] binned, until [`Self::collect`] or [`Self::take_prebinned`].
    prebinned: Option<BinnedWindow>,
}

impl EventEdges {
    /// Statistics of the last collection / accumulation.
    pub fn stats(&self) -> EventTermStats {
        self.stats
    }

    /// Matches the events to `view`'s contour at `pose` as the term's kind needs: the outline step on each
    /// correspondence line, or the hinge's candidate and contour associations. `motion` is the object's
    /// predicted velocity (centre m/s, angular rad/s, camera frame) about `center_obj`, `window_s` the event window:
    /// together they say how wide a band of events each edge leaves behind.
    #[allow(clippy::too_many_arguments)]
    pub fn associate(
        &mut self,
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        camera: &PinholeCamera,
        motion: &Vector6<f64>,
        window_s: f64,
    ) {
        self.association.clear();
        self.contour_match.clear();
        self.sweep.clear();
        self.contour_match.reserve(view.contour.capacity());
        self.sweep.reserve(view.contour.capacity());
        let c = pose * nalgebra::Point3::from(*center_obj);
        let v = Vector3::new(motion[0], motion[1], motion[2]);
        let w = Vector3::new(motion[3], motion[4], motion[5]);
        for cp in &view.contour {
            let p = pose * cp.position;
            if p.z <= 0.01 {
                self.sweep.push(0.0);
                continue;
            }
            let dp = v + w.cross(&(p - c));
            let iz = 1.0 / p.z;
            let du = camera.fx * (dp.x - p.x * iz * dp.z) * iz;
            let dv = camera.fy * (dp.y - p.y * iz * dp.z) * iz;
            self.sweep
                .push((cp.normal_2d[0] * du + cp.normal_2d[1] * dv) * window_s);
        }
        self.line_match.clear();
        if term.kind == EventTermKind::ContrastMax {
            // No residuals: the motion comes from `maximise_contrast`.
            return;
        }
        if term.kind == EventTermKind::Lines {
            self.find_steps(term, view, pose, camera);
            return;
        }
        self.associate_hinge(term, view, pose, camera);
    }

    /// Accumulates the event residuals of the term's kind at `pose` into `ne` (camera: the full event camera):
    /// the correspondence lines, or the hinge residuals of the associated candidates. Returns how many were
    /// active.
    pub fn accumulate(
        &mut self,
        term: &EventTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        camera: &PinholeCamera,
        ne: &mut NormalEquations,
    ) -> usize {
        match term.kind {
            EventTermKind::Lines => {
                return self.accumulate_lines(term, view, pose, center_obj, camera, ne);
            }
            EventTermKind::ContrastMax => {
                self.stats.active = 0;
                return 0;
            }
            EventTermKind::Hinge => {}
        }
        self.accumulate_hinge(term, view, pose, center_obj, camera, ne)
    }

    /// Fraction of `view`'s contour points at `pose` that have a kept event bin within two bins (event support of
    /// a moving outline); `None` without contour.
    pub fn contour_support(
        &self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
    ) -> Option<f64> {
        let roi = self.roi?;
        if view.contour.is_empty() {
            return None;
        }
        let sx = f64::from(self.width) / roi.width;
        let sy = f64::from(self.height) / roi.height;
        let (wi, hi) = (i64::from(self.width), i64::from(self.height));
        let mut supported = 0usize;
        for cp in &view.contour {
            let p = pose * cp.position;
            let Some(uv) = camera.project(&p) else {
                continue;
            };
            let i = ((uv.x + 0.5 - roi.x) * sx) as i64;
            let j = ((uv.y + 0.5 - roi.y) * sy) as i64;
            let mut hit = false;
            'search: for dj in -2..=2 {
                for di in -2..=2 {
                    let (a, b) = (i + di, j + dj);
                    if a >= 0 && b >= 0 && a < wi && b < hi && self.kept[(b * wi + a) as usize] {
                        hit = true;
                        break 'search;
                    }
                }
            }
            supported += usize::from(hit);
        }
        Some(supported as f64 / view.contour.len() as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::grid_index;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn grid_index_is_the_nearest_index_or_negative(x in -1e6f64..1e6) {
            let nearest = (x + 0.5).floor() as i64;
            let g = grid_index(x);
            if nearest >= 0 {
                prop_assert_eq!(g, nearest);
            } else {
                prop_assert!(g < 0);
            }
        }
    }
}

//! The event term's parameters ([`EventTerm`]), its kinds and statistics, and the grid rounding every event
//! matcher shares.

/// Nearest grid index of a sample position, `floor(x + 0.5)`, without the libm call `f64::round` makes on targets
/// without SSE4.1 (it differs from `round` only at negative halves). Every negative index is out of range, so all
/// of them map to -1.
#[inline]
pub(super) fn grid_index(x: f64) -> i64 {
    let v = x + 0.5;
    if v >= 0.0 { v as i64 } else { -1 }
}

/// How events become residuals.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
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
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
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
    /// equal ones in scan order; 0.05 measured dev +2.3 and holdout -1.9 ADD-S (docs/history/tuning.md, thirteenth round).
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

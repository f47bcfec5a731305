//! The intensity-edge modality: the model's outline against edges of the reconstructed intensity `I_t`.
//!
//! `I_t` is the event-driven log-intensity estimate (high-passed, see [`crate::recon`]). Where the object has just
//! covered background, `I_t` holds the object-minus-background contrast; where it has just uncovered background,
//! the opposite; the static background stays near 0. Either way `I_t` changes most sharply at the object's
//! outline at time `t`, on leading and trailing edges alike, with no trailing band to predict (unlike the event
//! term, whose window leaves one). Along each contour point's image normal the strongest step of `I_t` within
//! reach is the observed outline; its offset from the projected contour is the residual.

use super::contour::ContourResiduals;
use super::modality::Modality;
use super::model_view::ModelView;
use super::normal_equations::NormalEquations;
use crate::recon::EventSurface;
use nalgebra::{Isometry3, Vector3};
use scene::geometry::PinholeCamera;

/// Parameters of the intensity-edge term.
#[derive(
    Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields, default)]
pub struct IntensityTerm {
    /// Weight relative to the depth term; 0 switches the term off.
    pub weight: f64,
    /// Length of each side of the step detector, full-image pixels.
    pub box_px: u32,
    /// Smallest log-intensity step (mean inside minus mean outside, absolute) accepted as an edge.
    pub min_step: f64,
    /// Step that earns full weight; smaller steps are weighted in proportion.
    pub full_step: f64,
    /// How far along the normal (each way) the edge is looked for, full-image pixels.
    pub max_distance_px: f64,
    /// Residual scale, full-image pixels.
    pub sigma_px: f64,
}

impl Default for IntensityTerm {
    fn default() -> Self {
        Self {
            weight: 0.0,
            box_px: 2,
            min_step: 0.1,
            full_step: 0.3,
            max_distance_px: 8.0,
            sigma_px: 1.5,
        }
    }
}

/// Per-contour-point intensity edges found at the association pose, and the scratch the search reuses.
#[derive(Debug, Clone, Default)]
pub struct IntensityEdges {
    /// Per contour point: the observed outline point (full-image pixels) and the step's strength.
    matches: Vec<Option<([f64; 2], f64)>>,
    /// Scratch: `I_t` along one normal (NaN outside the sensor).
    samples: Vec<f32>,
    /// Residuals that contributed to the last accumulation.
    active: usize,
}

impl IntensityEdges {
    /// Finds, for every contour point of `view` at `pose`, the strongest `I_t` step on its normal. `roi_bin_px` is
    /// the render's pixel size in full-image pixels: contour points sit on the centre of the silhouette's last
    /// pixel, half of that inside the outline.
    #[allow(clippy::too_many_arguments)]
    pub fn associate(
        &mut self,
        term: &IntensityTerm,
        view: &ModelView,
        pose: &Isometry3<f64>,
        camera: &PinholeCamera,
        surface: &EventSurface,
        t_us: i64,
        roi_bin_px: f64,
    ) {
        self.matches.clear();
        self.matches.reserve(view.contour.capacity());
        let k = i64::from(term.box_px.max(1));
        let reach = term.max_distance_px.max(0.0).ceil() as i64;
        let first = -reach - k;
        let (w, h) = (i64::from(surface.width()), i64::from(surface.height()));
        for cp in &view.contour {
            let Some(uv) = camera.project(&(pose * cp.position)) else {
                self.matches.push(None);
                continue;
            };
            let [mx, my] = cp.normal_2d;
            self.samples.clear();
            self.samples.extend((first..reach + k).map(|t| {
                let x = (uv.x + t as f64 * mx + 0.5).floor() as i64;
                let y = (uv.y + t as f64 * my + 0.5).floor() as i64;
                if x >= 0 && y >= 0 && x < w && y < h {
                    surface.log_intensity_at(x as u32, y as u32, t_us)
                } else {
                    f32::NAN
                }
            }));
            let mean = |from: i64, to: i64| -> f64 {
                let s = &self.samples[(from - first) as usize..(to - first) as usize];
                s.iter().map(|&v| f64::from(v)).sum::<f64>() / s.len() as f64
            };
            let mut best: Option<(f64, i64)> = None;
            for b in -reach..=reach {
                // A step between samples b-1 and b: inside = [b-k, b), outside = [b, b+k). NaN never wins.
                let step = (mean(b - k, b) - mean(b, b + k)).abs();
                if step.is_nan() || step < term.min_step {
                    continue;
                }
                let better = match best {
                    None => true,
                    Some((s, at)) => {
                        step > s + 1e-9 || ((step - s).abs() <= 1e-9 && b.abs() < at.abs())
                    }
                };
                if better {
                    best = Some((step, b));
                }
            }
            self.matches.push(best.map(|(step, b)| {
                // The step lies half a sample before b; the matching contour position is half a render pixel
                // further in.
                let at = b as f64 - 0.5 - 0.5 * roi_bin_px;
                ([uv.x + at * mx, uv.y + at * my], step)
            }));
        }
    }

    /// Accumulates the intensity-edge residuals at `pose` into `ne`. Returns how many contributed.
    pub fn accumulate(
        &mut self,
        term: &IntensityTerm,
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
            max_px: term.max_distance_px + 1.0,
        };
        let full = term.full_step.max(f64::MIN_POSITIVE);
        let mut active = 0;
        for (cp, m) in view.contour.iter().zip(&self.matches) {
            let Some((e, step)) = m else {
                continue;
            };
            let p = pose * cp.position;
            if residuals.add(ne, &p, cp.normal_2d, e, 0.0, (step / full).min(1.0)) {
                active += 1;
            }
        }
        self.active = active;
        active
    }

    /// Residuals that contributed to the last accumulation.
    pub fn active(&self) -> usize {
        self.active
    }
}

/// The intensity-edge term as a [`Modality`] for one refinement: the outline against the edges of `I_t` in
/// `surface` at `t_us`, seen by the full event `camera`.
#[derive(Debug)]
pub struct IntensityModality<'a> {
    /// Whether it takes part in this refinement.
    pub active: bool,
    /// Parameters (its weight is the term's scale in the sum).
    pub term: &'a IntensityTerm,
    /// The matches and scratch, reused from tick to tick.
    pub edges: &'a mut IntensityEdges,
    /// The full event camera.
    pub camera: &'a PinholeCamera,
    /// The event state holding `I_t`.
    pub surface: &'a EventSurface,
    /// The tick time, microseconds.
    pub t_us: i64,
    /// The ROI render's pixel size in full-image pixels.
    pub roi_bin_px: f64,
}

impl Modality for IntensityModality<'_> {
    fn name(&self) -> &'static str {
        "intensity"
    }

    fn is_active(&self) -> bool {
        self.active
    }

    fn weight(&self) -> f64 {
        self.term.weight
    }

    fn correspond(&mut self, view: &ModelView, pose: &Isometry3<f64>) {
        self.edges.associate(
            self.term,
            view,
            pose,
            self.camera,
            self.surface,
            self.t_us,
            self.roi_bin_px,
        );
    }

    fn accumulate(
        &mut self,
        view: &ModelView,
        pose: &Isometry3<f64>,
        center_obj: &Vector3<f64>,
        ne: &mut NormalEquations,
    ) {
        self.edges
            .accumulate(self.term, view, pose, center_obj, self.camera, ne);
    }
}

//! Tracker parameters and the method presets (`eventtrack6d`, `depth30`, `events-only`).

use super::FallbackRule;
use super::estimate::TrackingState;
use super::redetect::RedetectConfig;
use crate::recon::IntensityFilterConfig;
use crate::refine::{DepthTerm, EventTerm, IntensityTerm};
use serde::{Deserialize, Serialize};

/// When the depth modality is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum DepthUse {
    /// `D_t` at every tick: the fresh frame at depth-exposure ticks, the carried `D_0` in between (ours).
    EveryTick,
    /// Only at depth-exposure ticks; no refinement in between (the `depth30` baseline holds the pose).
    DepthFramesOnly,
    /// Only the first depth frame (the `events-only` baseline).
    FirstFrameOnly,
    /// Never.
    Off,
}

/// Quality thresholds that set the tracking state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct QualityConfig {
    /// Below this quality the state is `degraded`.
    pub degraded_below: f32,
    /// Below this quality for `lost_after_ticks` consecutive ticks the state is `lost`.
    pub lost_below: f32,
    /// Consecutive low-quality ticks before `lost` is raised.
    pub lost_after_ticks: u32,
    /// `lost` is also raised while the mean quality over the last `lost_mean_ticks` ticks is below this: a track
    /// that stays mediocre (an estimate off the object that the data half supports) without ever dropping below
    /// `lost_below` for long.
    pub lost_mean_below: f32,
    /// Length of that window, ticks (0 disables the rule; 60 is 0.5 s at 120 Hz).
    pub lost_mean_ticks: u32,
    /// A better state is reported (pose CSV, zenoh, CAN, status) only after better states held for this many
    /// ticks in a row; a worse one at once. 0 or 1 reports every tick's state. The tracker's own decisions
    /// (prediction, re-detection) use each tick's state.
    pub recover_ticks: u32,
}

impl Default for QualityConfig {
    fn default() -> Self {
        Self {
            degraded_below: 0.5,
            lost_below: 0.2,
            lost_after_ticks: 12,
            lost_mean_below: 0.35,
            lost_mean_ticks: 60,
            recover_ticks: 6,
        }
    }
}

impl QualityConfig {
    /// The state of an estimate of `quality`, after `low_ticks` consecutive ticks below `lost_below` (this one
    /// included) and with `recent_mean` the mean quality over the last `lost_mean_ticks` ticks (`None` until
    /// that many ticks have passed).
    pub fn state(&self, quality: f32, low_ticks: u32, recent_mean: Option<f64>) -> TrackingState {
        let mediocre = recent_mean.is_some_and(|m| m < f64::from(self.lost_mean_below));
        if low_ticks >= self.lost_after_ticks || mediocre {
            TrackingState::Lost
        } else if quality < self.degraded_below {
            TrackingState::Degraded
        } else {
            TrackingState::Tracking
        }
    }
}

/// All tracker parameters. Every field has a default; a TOML `[tracker]` table may override any of them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct TrackerConfig {
    /// ROI output size, pixels (square).
    pub roi_size: u32,
    /// ROI side as a multiple of the object's projected diameter.
    pub roi_scale: f64,
    /// Gauss-Newton / Levenberg-Marquardt iterations per tick.
    pub iterations: u32,
    /// Levenberg-Marquardt damping relative to the diagonal.
    pub damping: f64,
    /// Depth modality schedule.
    pub depth: DepthUse,
    /// Whether the event modality is used.
    pub events: bool,
    /// Constant-velocity prediction on SE(3) (off: start from the previous pose), scaled by
    /// [`Self::prediction_gain`].
    pub prediction: bool,
    /// At a fresh depth frame, the depth-only refinement from the previous depth frame's pose replaces the
    /// event-driven estimate when its fraction of agreeing model points is higher by more than this; negative
    /// disables the check.
    pub depth_fallback_margin: f64,
    /// A depth-only candidate may replace the estimate only if the depth around the object confirms the motion
    /// it implies since the previous depth frame nearly as well as the best of the estimate and the candidates:
    /// its motion agreement (the fraction of the previous frame's moved surfaces the new frame confirms,
    /// [`crate::recon::MovingNeighbourhood`]) falls short of the best one's by at most this. Keeps the safety net from sliding the object onto the hand
    /// that holds it, which moves with it. Negative disables the check.
    pub depth_fallback_motion_margin: f64,
    /// The surroundings contradict the estimate when its motion agreement since the previous depth frame falls
    /// short of the best candidate's by more than this; the best eligible candidate then replaces it even if fewer
    /// model points agree with it (an estimate that jumped onto the hand in front of a mostly hidden object agrees
    /// with more of the depth than the object does). Negative disables.
    pub depth_fallback_estimate_motion_margin: f64,
    /// Weight of the events' verdict in the safety net: a candidate's score is its agreeing fraction plus this
    /// times how much more of its contour the recent event edges support than the estimate's
    /// ([`crate::track::DepthFallbackCheck::replacement`]). 0 leaves the choice to depth alone.
    pub depth_fallback_event_weight: f64,
    /// Whether the depth-only fallback also starts from the previous depth frame's pose carried on at the velocity
    /// measured between depth frames (and keeps the better of its two results).
    pub depth_fallback_extrapolate: bool,
    /// Whether the depth-only fallback also starts from the previous depth frame's pose carried on at the motion
    /// between the two depth frames before it: unlike the extrapolated start, the events since cannot have
    /// changed that motion, so one tick the events got wrong does not spoil it. On by default: it lifted dev
    /// ADD-S from 62.2 to 66.7 and holdout from 63.5 to 65.7, and ended `lost` on slow and moderate sequences
    /// (docs/history/tuning.md, eighteenth round).
    pub depth_fallback_anchored: bool,
    /// Whether the ROI at a depth exposure grows to also cover the extrapolated fallback start.
    pub roi_widen_at_depth: bool,
    /// Whether a degraded or lost object searches the event term's whole shift range every tick (to catch up
    /// with an object it fell behind) rather than the range its motion predicts.
    pub search_wide_when_degraded: bool,
    /// Whether silhouette samples that the depth `D_t` shows behind a nearer surface (by more than the depth
    /// term's `occlusion_gap`, at the predicted pose) are left out of the event and intensity terms: a hand
    /// gripping the object hides that part of its outline, and the events there are the hand's. Off by
    /// default: it lifts the hand-switch sequences but did not lower failures or slow / moderate `lost`
    /// (docs/history/tuning.md, fifteenth round).
    pub hide_occluded_outline: bool,
    /// With `hide_occluded_outline`, the largest share (0..=1) of the outline samples hidden on a tick; when
    /// more would be hidden, the whole outline is kept (a thin object mostly under a hand). 0.5 measured better
    /// than 1 on the hand-switch sequences (docs/history/tuning.md, fifteenth round).
    pub hide_occluded_max_share: f64,
    /// Fraction of the estimated velocity the prediction extrapolates with (1 = constant velocity).
    pub prediction_gain: f64,
    /// Whether the prediction also turns the object (off: it only moves it).
    pub predict_rotation: bool,
    /// Weight of the carried depth `D_t` between depth exposures relative to a fresh frame.
    pub carried_depth_weight: f64,
    /// Weight of the event term relative to the depth term.
    pub event_weight: f64,
    /// The short event window covers about this many pixels of predicted image motion.
    pub event_window_px: f64,
    /// Shortest event window, microseconds.
    pub min_event_window_us: i64,
    /// Longest event window, microseconds.
    pub max_event_window_us: i64,
    /// Largest rotation per refinement step, degrees (the paper: about 20).
    pub max_step_rotation_deg: f64,
    /// Largest translation per refinement step, object diameters (the paper: half).
    pub max_step_translation_diameters: f64,
    /// Most model surface samples per tick.
    pub max_surface_points: usize,
    /// Most silhouette samples per tick.
    pub max_contour_points: usize,
    /// Most event candidates per tick.
    pub max_event_points: usize,
    /// Velocity smoothing between depth frames: weight of the newest per-tick measurement in `[0, 1]`.
    pub velocity_smoothing: f64,
    /// Velocity smoothing at depth frames: weight of the motion measured since the previous depth frame.
    pub velocity_smoothing_depth: f64,
    /// Largest speed of the object centre the motion model accepts, m/s.
    pub max_speed: f64,
    /// Largest angular speed the motion model accepts, rad/s.
    pub max_angular_speed: f64,
    /// Standard deviation of the prior towards the predicted pose per tick: translation, metres.
    pub prior_translation_m: f64,
    /// Standard deviation of the prior towards the predicted pose per tick: rotation, degrees.
    pub prior_rotation_deg: f64,
    /// Intensity reconstruction.
    pub intensity: IntensityFilterConfig,
    /// Depth residual parameters.
    pub depth_term: DepthTerm,
    /// Event residual parameters.
    pub event_term: EventTerm,
    /// Intensity-edge residual parameters (edges of the reconstructed `I_t` against the model outline).
    pub intensity_term: IntensityTerm,
    /// Quality thresholds.
    pub quality: QualityConfig,
    /// Re-detection of objects that are not `tracking`, at depth frames.
    pub redetect: RedetectConfig,
    /// Threads that step the objects of a tick, and check its re-detection places, in parallel, the tracker's own
    /// included: 0 = one per available core, 1 = all on the tracker's thread. Never more than there are objects
    /// or places checked per tick; only renderers that can fork (the CPU renderer) run in parallel. Poses do not
    /// depend on it.
    pub object_threads: usize,
    /// At the end of a tick, start rendering each object's next ROI at the pose the next tick will predict (one
    /// tick period later, no depth frame): a GPU renderer rasterises between ticks, and a renderer that renders on
    /// the caller's thread (the CPU renderer) renders on a helper thread (`render-ahead`, a
    /// [`scene::render::RenderAhead`]). The next tick takes that image only for an identical request, so poses do
    /// not depend on it. `false` keeps the CPU renderer on the tracker's thread alone.
    pub prefetch_renders: bool,
    /// A mesh of more than this many triangles is rendered simplified ([`Self::render_mesh_tolerance_px`]): a
    /// render costs per triangle, and CAD exports are often tessellated far finer than the ROI resolves. Meshes
    /// up to it render as loaded (the library's have at most 4,736, and the suites' accuracy was measured with
    /// them as loaded). 0 simplifies every mesh.
    pub render_mesh_simplify_above: usize,
    /// How far a simplified render mesh may lie from the loaded one: until a vertex or triangle centre of the
    /// loaded mesh would lie farther than this from it, in ROI pixels at the object (one is `roi_scale`
    /// diameters over `roi_size`; [`scene::mesh::simplify_for_render`]). 0 renders every mesh as loaded.
    /// Accuracy is always scored, and the overlay drawn, with the mesh as loaded.
    pub render_mesh_tolerance_px: f64,
    /// Oldest depth frame the tracker still uses, ms between its exposure and the tick after it arrived. A live
    /// depth camera delivers a frame tens of milliseconds after its exposure: the tracker then registers it at
    /// the object's estimate at the exposure, carries the object's part by the motion estimated since, and
    /// refines against it at the current tick. Older frames are dropped and counted (`depth_frames_unused`);
    /// 0 uses only frames that arrive by their own tick. At most [`MAX_DEPTH_AGE_LIMIT_MS`].
    pub max_depth_age_ms: f64,
    /// When a depth frame arrives after its exposure's tick, go back to the tracker's state at that tick (saved
    /// then) and track the ticks since again with the frame in place, as if it had come in time; the poses
    /// already out stand. This is done when the frame arrives (between two ticks with a live camera), so it
    /// delays the next tick only by what it takes beyond the time left until that tick. `false` instead carries the frame from its exposure to the current tick (cheaper: no
    /// ticks tracked again, no states or events kept, but the motion since the exposure stays the events' alone).
    pub retrack_late_depth: bool,
    /// Most events kept for tracking again (24 bytes each): the events since the oldest exposure whose frame has
    /// not come. A late frame whose events no longer fit is carried instead (counted).
    pub retrack_max_events: usize,
}

/// Largest [`TrackerConfig::max_depth_age_ms`]: the span the per-object pose history covers at 120 Hz, less a
/// tick.
pub const MAX_DEPTH_AGE_LIMIT_MS: f64 = 500.0;

impl Default for TrackerConfig {
    fn default() -> Self {
        Self {
            roi_size: 160,
            roi_scale: 1.2,
            iterations: 5,
            damping: 1e-3,
            depth: DepthUse::EveryTick,
            events: true,
            prediction: true,
            depth_fallback_margin: 0.05,
            depth_fallback_motion_margin: 0.3,
            depth_fallback_estimate_motion_margin: 0.5,
            depth_fallback_event_weight: 0.0,
            depth_fallback_extrapolate: true,
            depth_fallback_anchored: true,
            roi_widen_at_depth: false,
            search_wide_when_degraded: false,
            hide_occluded_outline: false,
            hide_occluded_max_share: 0.5,
            prediction_gain: 0.5,
            predict_rotation: true,
            carried_depth_weight: 0.3,
            event_weight: 1.0,
            event_window_px: 3.0,
            min_event_window_us: 1_000,
            max_event_window_us: 8_333,
            max_step_rotation_deg: 20.0,
            max_step_translation_diameters: 0.5,
            max_surface_points: 600,
            max_contour_points: 200,
            max_event_points: 400,
            velocity_smoothing: 0.2,
            velocity_smoothing_depth: 0.7,
            max_speed: 6.0,
            max_angular_speed: 30.0,
            prior_translation_m: 0.01,
            prior_rotation_deg: 3.0,
            intensity: IntensityFilterConfig::default(),
            depth_term: DepthTerm::default(),
            event_term: EventTerm::default(),
            intensity_term: IntensityTerm::default(),
            quality: QualityConfig::default(),
            redetect: RedetectConfig::default(),
            object_threads: 0,
            prefetch_renders: true,
            render_mesh_simplify_above: 5_000,
            render_mesh_tolerance_px: 0.25,
            max_depth_age_ms: 200.0,
            retrack_late_depth: true,
            retrack_max_events: 4_000_000,
        }
    }
}

impl TrackerConfig {
    /// [`Self::prior_rotation_deg`] in radians.
    pub fn prior_rotation_rad(&self) -> f64 {
        self.prior_rotation_deg.to_radians()
    }

    /// The depth safety net's choice settings, from the `depth_fallback_*` fields.
    pub fn fallback_rule(&self) -> FallbackRule {
        FallbackRule {
            margin: self.depth_fallback_margin,
            motion_margin: self.depth_fallback_motion_margin,
            estimate_motion_margin: self.depth_fallback_estimate_motion_margin,
            event_weight: self.depth_fallback_event_weight,
        }
    }
}

/// A named tracking method: ours or one of the baselines, all on the same tracker code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum TrackingMethod {
    /// EventTrack6D: events + carried depth at every tick, fresh depth at exposures.
    #[serde(rename = "eventtrack6d")]
    EventTrack6d,
    /// Render-and-compare on depth only at depth frames (30 Hz), pose held in between.
    #[serde(rename = "depth30")]
    Depth30,
    /// Events only after the first depth frame.
    EventsOnly,
}

impl TrackingMethod {
    /// Every method, in report order.
    pub const ALL: [TrackingMethod; 3] = [Self::EventTrack6d, Self::Depth30, Self::EventsOnly];

    /// The method's name in configs, CLIs and reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::EventTrack6d => "eventtrack6d",
            Self::Depth30 => "depth30",
            Self::EventsOnly => "events-only",
        }
    }

    /// The method for a name, if any.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }

    /// `base` with this method's modality schedule applied.
    pub fn configure(self, base: &TrackerConfig) -> TrackerConfig {
        let mut c = base.clone();
        match self {
            Self::EventTrack6d => {}
            Self::Depth30 => {
                c.depth = DepthUse::DepthFramesOnly;
                c.events = false;
                c.prediction = false;
            }
            Self::EventsOnly => {
                c.depth = DepthUse::FirstFrameOnly;
                c.events = true;
                // No depth after the first frame: nothing to re-detect with.
                c.redetect.enabled = false;
            }
        }
        c
    }
}

impl std::fmt::Display for TrackingMethod {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn state_is_lost_after_a_run_of_low_ticks_or_a_mediocre_window() {
        let q = QualityConfig::default();
        assert_eq!(q.state(0.9, 0, Some(0.9)), TrackingState::Tracking);
        assert_eq!(q.state(0.3, 0, Some(0.9)), TrackingState::Degraded);
        assert_eq!(q.state(0.1, 11, None), TrackingState::Degraded);
        assert_eq!(q.state(0.1, 12, None), TrackingState::Lost);
        // Never 12 low ticks in a row, but mediocre for the whole window: lost even on a good tick.
        assert_eq!(q.state(0.9, 0, Some(0.3)), TrackingState::Lost);
        assert_eq!(q.state(0.3, 0, Some(0.4)), TrackingState::Degraded);
        assert_eq!(q.state(0.3, 0, None), TrackingState::Degraded);
    }
}

//! The tracker's parameters ([`TrackerConfig`]), grouped by concept, with their defaults. A file writes them as
//! one flat table ([`TrackerParameterKeys`]); the keys are the field names below.

use super::DepthUse;
use super::QualityConfig;
use crate::recon::IntensityFilterConfig;
use crate::refine::{DepthTerm, EventTerm, IntensityTerm};
use crate::track::FallbackRule;
use crate::track::redetect::RedetectConfig;

grouped_parameters! {
    /// All tracker parameters, grouped by concept. Every parameter has a default; a TOML `[tracker.parameters]`
    /// table or a `track --params` file may override any of them by its key (the field's name, without its group).
    pub struct TrackerConfig;
    /// The tracker's parameters as a file writes them (a `[tracker.parameters]` table, a `track --params` file):
    /// one flat table of keys, then the sub-tables. Every key has a default.
    pub struct TrackerParameterKeys;
    groups {
        /// The region of interest: the window around the object that is rendered and compared.
        roi: RoiConfig {
            /// ROI output size, pixels (square).
            roi_size: u32 = 160,
            /// ROI side as a multiple of the object's projected diameter.
            roi_scale: f64 = 1.2,
            /// Whether the ROI at a depth exposure grows to also cover the extrapolated fallback start.
            roi_widen_at_depth: bool = false,
        }
        /// Which modalities the tracker uses, and their weights.
        modalities: ModalityConfig {
            /// Depth modality schedule.
            depth: DepthUse = DepthUse::EveryTick,
            /// Whether the event modality is used.
            events: bool = true,
            /// Weight of the carried depth `D_t` between depth exposures relative to a fresh frame.
            carried_depth_weight: f64 = 0.3,
            /// Weight of the event term relative to the depth term.
            event_weight: f64 = 1.0,
        }
        /// The motion model: the prediction of the next pose and the velocity it extrapolates.
        motion: MotionConfig {
            /// Constant-velocity prediction on SE(3) (off: start from the previous pose), scaled by
            /// [`Self::prediction_gain`].
            prediction: bool = true,
            /// Fraction of the estimated velocity the prediction extrapolates with (1 = constant velocity).
            prediction_gain: f64 = 0.5,
            /// Whether the prediction also turns the object (off: it only moves it).
            predict_rotation: bool = true,
            /// Velocity smoothing between depth frames: weight of the newest per-tick measurement in `[0, 1]`.
            velocity_smoothing: f64 = 0.2,
            /// Velocity smoothing at depth frames: weight of the motion measured since the previous depth frame.
            velocity_smoothing_depth: f64 = 0.7,
            /// Whether the smoothing is corrected for the zero the velocity starts from (at the first pose and
            /// after a re-detection): each measurement then counts by its weight relative to all weight measured
            /// since, so the first sets the velocity outright, where the plain average reaches 0.2, 0.36, 0.49 of
            /// a steady motion over the first ticks (BENCHMARKS.md, "The fast suite").
            velocity_start_corrected: bool = true,
            /// Whether the prediction puts the object at the range (its centre's distance from the camera) that
            /// the latest depth frames' estimates extrapolate to, rather than where the velocity carries it along
            /// the line of sight: the events barely observe that motion, so between depth frames the velocity's
            /// part along it is mostly what earlier predictions put there.
            range_from_depth: bool = true,
            /// With [`Self::range_from_depth`], the share in `[0, 1]` of the change in the range's rate over the last
            /// three depth frames that the extrapolation adds (0: their latest rate alone).
            range_acceleration_share: f64 = 1.0,
            /// Largest speed of the object centre the motion model accepts, m/s.
            max_speed: f64 = 6.0,
            /// Largest angular speed the motion model accepts, rad/s.
            max_angular_speed: f64 = 30.0,
        }
        /// Steps between ticks: a fast object is refined again as its events arrive, at evenly spaced times between
        /// two ticks, so that each refinement starts from an estimate at most one step old. Only the ticks publish;
        /// a step between ticks moves the estimate and its history ([`crate::track::PoseTracker::pose_at`]), not
        /// its velocity, quality or state.
        inner_steps: InnerStepConfig {
            /// An object gets one step between ticks for every this many pixels its outline moves per tick at its
            /// estimated speed (beyond the first): at 25 px per tick and 6 px, three steps. 0 turns steps between
            /// ticks off (as `config/tracker/ticks-only.toml` does, at half the CPU on a fast object); on fast
            /// recordings no tuning saw, that cost 8.5 ADD-S points with the other options on (BENCHMARKS.md, "The
            /// fast suite").
            inner_step_px: f64 = 6.0,
            /// Most steps between two ticks (the CPU a tick may cost: each step costs about what a tick does).
            max_inner_steps: u32 = 3,
            /// Standard deviation of a step's motion along the line of sight to the object beyond its prediction,
            /// metres per tick period (spread over the steps like the optimiser's prior): events barely observe
            /// depth, so each step would drift there; the ticks refine it.
            line_of_sight_sigma_m: f64 = 0.001,
        }
        /// The correspond phase: the event window, how many samples are matched, and which outline samples count.
        correspond: CorrespondConfig {
            /// The short event window covers about this many pixels of predicted image motion.
            event_window_px: f64 = 3.0,
            /// Shortest event window, microseconds.
            min_event_window_us: i64 = 1_000,
            /// Longest event window, microseconds.
            max_event_window_us: i64 = 8_333,
            /// Whether a degraded or lost object searches the event term's whole shift range every tick (to catch up
            /// with an object it fell behind) rather than the range its motion predicts.
            search_wide_when_degraded: bool = false,
            /// Whether the tick at the first pose's own time uses the events when it has a depth frame. Their window
            /// is sized for an object at rest (nothing has measured its speed yet) and holds the motion into the
            /// first pose: on the `fast` suite they moved the exact first pose by 4.1 mm on average (up to 21 mm),
            /// against 1.3 mm on depth alone.
            events_at_first_pose: bool = false,
            /// Whether, at a fresh depth frame, the refinement starts moved along the line of sight onto the surface
            /// the frame measures, when most of the model's visible surface agrees on an offset beyond half the
            /// depth term's `occlusion_gap` (within a diameter): the events barely see motion along the line of
            /// sight, and by the first depth frame an object approaching fast is nearer than the estimate by more
            /// than the depth term reaches (it takes a surface that much nearer for an occluder).
            align_range_at_depth: bool = true,
            /// Most model surface samples per tick.
            max_surface_points: usize = 600,
            /// Most silhouette samples per tick.
            max_contour_points: usize = 200,
            /// Most event candidates per tick.
            max_event_points: usize = 400,
            /// Whether silhouette samples that the depth `D_t` shows behind a nearer surface (by more than the depth
            /// term's `occlusion_gap`, at the predicted pose) are left out of the event and intensity terms: a hand
            /// gripping the object hides that part of its outline, and the events there are the hand's. Off by
            /// default: it lifts the hand-switch sequences but did not lower failures or slow / moderate `lost`
            /// (docs/history/tuning.md, fifteenth round).
            hide_occluded_outline: bool = false,
            /// With `hide_occluded_outline`, the largest share (0..=1) of the outline samples hidden on a tick; when
            /// more would be hidden, the whole outline is kept (a thin object mostly under a hand). 0.5 measured better
            /// than 1 on the hand-switch sequences (docs/history/tuning.md, fifteenth round).
            hide_occluded_max_share: f64 = 0.5,
        }
        /// The optimise phase: the Gauss-Newton / Levenberg-Marquardt loop, its step limits and the prior towards the
    /// predicted pose.
        optimiser: OptimiserConfig {
            /// Gauss-Newton / Levenberg-Marquardt iterations per tick.
            iterations: u32 = 5,
            /// Levenberg-Marquardt damping relative to the diagonal.
            damping: f64 = 1e-3,
            /// Largest rotation per refinement step, degrees (the paper: about 20).
            max_step_rotation_deg: f64 = 20.0,
            /// Largest translation per refinement step, object diameters (the paper: half).
            max_step_translation_diameters: f64 = 0.5,
            /// Standard deviation of the prior towards the predicted pose per tick: translation, metres.
            prior_translation_m: f64 = 0.01,
            /// Standard deviation of the prior towards the predicted pose per tick: rotation, degrees.
            prior_rotation_deg: f64 = 3.0,
        }
        /// The depth safety net: when a depth-only refinement at a fresh depth frame replaces the estimate.
        safety_net: SafetyNetConfig {
            /// At a fresh depth frame, the depth-only refinement from the previous depth frame's pose replaces the
            /// event-driven estimate when its fraction of agreeing model points is higher by more than this; negative
            /// disables the check.
            depth_fallback_margin: f64 = 0.05,
            /// A depth-only candidate may replace the estimate only if the depth around the object confirms the motion
            /// it implies since the previous depth frame nearly as well as the best of the estimate and the candidates:
            /// its motion agreement (the fraction of the previous frame's moved surfaces the new frame confirms,
            /// [`crate::recon::MovingNeighbourhood`]) falls short of the best one's by at most this. Keeps the safety net from sliding the object onto the hand
            /// that holds it, which moves with it. Negative disables the check.
            depth_fallback_motion_margin: f64 = 0.3,
            /// The surroundings contradict the estimate when its motion agreement since the previous depth frame falls
            /// short of the best candidate's by more than this; the best eligible candidate then replaces it even if fewer
            /// model points agree with it (an estimate that jumped onto the hand in front of a mostly hidden object agrees
            /// with more of the depth than the object does). Negative disables.
            depth_fallback_estimate_motion_margin: f64 = 0.5,
            /// Weight of the events' verdict in the safety net: a candidate's score is its agreeing fraction plus this
            /// times how much more of its contour the recent event edges support than the estimate's
            /// ([`crate::track::DepthFallbackCheck::replacement`]). 0 leaves the choice to depth alone.
            depth_fallback_event_weight: f64 = 0.0,
            /// Whether the depth-only fallback also starts from the previous depth frame's pose carried on at the velocity
            /// measured between depth frames (and keeps the better of its two results).
            depth_fallback_extrapolate: bool = true,
            /// Whether the depth-only fallback also starts from the previous depth frame's pose carried on at the motion
            /// between the two depth frames before it: unlike the extrapolated start, the events since cannot have
            /// changed that motion, so one tick the events got wrong does not spoil it. On by default: it lifted dev
            /// ADD-S from 62.2 to 66.7 and holdout from 63.5 to 65.7, and ended `lost` on slow and moderate sequences
            /// (docs/history/tuning.md, eighteenth round).
            depth_fallback_anchored: bool = true,
        }
        /// Depth frames that arrive after their exposure's tick: how old a frame may be and how it is used.
        late_depth: LateDepthConfig {
            /// Oldest depth frame the tracker still uses, ms between its exposure and the tick after it arrived. A live
            /// depth camera delivers a frame tens of milliseconds after its exposure: the tracker then registers it at
            /// the object's estimate at the exposure, carries the object's part by the motion estimated since, and
            /// refines against it at the current tick. Older frames are dropped and counted (`depth_frames_unused`);
            /// 0 uses only frames that arrive by their own tick. At most [`MAX_DEPTH_AGE_LIMIT_MS`].
            max_depth_age_ms: f64 = 200.0,
            /// When a depth frame arrives after its exposure's tick, go back to the tracker's state at that tick (saved
            /// then) and track the ticks since again with the frame in place, as if it had come in time; the poses
            /// already out stand. This is done when the frame arrives (between two ticks with a live camera), so it
            /// delays the next tick only by what it takes beyond the time left until that tick. `false` instead carries the frame from its exposure to the current tick (cheaper: no
            /// ticks tracked again, no states or events kept, but the motion since the exposure stays the events' alone).
            retrack_late_depth: bool = true,
            /// Most events kept for tracking again (24 bytes each): the events since the oldest exposure whose frame has
            /// not come. A late frame whose events no longer fit is carried instead (counted).
            retrack_max_events: usize = 4_000_000,
        }
        /// How the work is carried out: threads, renders ahead of the tick, and the render mesh.
        execution: ExecutionConfig {
            /// Threads that step the objects of a tick, and check its re-detection places, in parallel, the tracker's own
            /// included: 0 = one per available core, 1 = all on the tracker's thread. Never more than there are objects
            /// or places checked per tick; only renderers that can fork (the CPU renderer) run in parallel. Poses do not
            /// depend on it.
            object_threads: usize = 0,
            /// At the end of a tick, start rendering each object's next ROI at the pose the next tick will predict (one
            /// tick period later, no depth frame): a GPU renderer rasterises between ticks, and a renderer that renders on
            /// the caller's thread (the CPU renderer) renders on a helper thread (`render-ahead`, a
            /// [`scene::render::RenderAhead`]). The next tick takes that image only for an identical request, so poses do
            /// not depend on it. `false` keeps the CPU renderer on the tracker's thread alone.
            prefetch_renders: bool = true,
            /// A mesh of more than this many triangles is rendered simplified ([`Self::render_mesh_tolerance_px`]): a
            /// render costs per triangle, and CAD exports are often tessellated far finer than the ROI resolves. Meshes
            /// up to it render as loaded (the library's have at most 4,736, and the suites' accuracy was measured with
            /// them as loaded). 0 simplifies every mesh.
            render_mesh_simplify_above: usize = 5_000,
            /// How far a simplified render mesh may lie from the loaded one: until a vertex or triangle centre of the
            /// loaded mesh would lie farther than this from it, in ROI pixels at the object (one is `roi_scale`
            /// diameters over `roi_size`; [`scene::mesh::simplify_for_render`]). 0 renders every mesh as loaded.
            /// Accuracy is always scored, and the overlay drawn, with the mesh as loaded.
            render_mesh_tolerance_px: f64 = 0.25,
        }
    }
    tables {
        /// Intensity reconstruction.
        intensity: IntensityFilterConfig,
        /// Depth residual parameters.
        depth_term: DepthTerm,
        /// Event residual parameters.
        event_term: EventTerm,
        /// Intensity-edge residual parameters (edges of the reconstructed `I_t` against the model outline).
        intensity_term: IntensityTerm,
        /// Quality thresholds.
        quality: QualityConfig,
        /// Re-detection of objects that are not `tracking`, at depth frames.
        redetect: RedetectConfig,
    }
}

impl OptimiserConfig {
    /// [`Self::prior_rotation_deg`] in radians.
    pub fn prior_rotation_rad(&self) -> f64 {
        self.prior_rotation_deg.to_radians()
    }
}

impl SafetyNetConfig {
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

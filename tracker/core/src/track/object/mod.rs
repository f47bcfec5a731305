//! One tracked object: its model, the state one tick hands to the next, the buffers a tick fills, and the phases
//! of its tick.
//!
//! The tracker predicts every object ([`ObjectState::predict`]) and re-detects lost ones; then each object's
//! tick runs [`ObjectTrack::prepare`] (depth registered, events binned: no render needed), the tracker renders
//! its ROI, and [`ObjectTrack::refine`] runs the phases in order:
//! 1. correspond ([`correspond`]): model view, a late frame's check, event matching, the start pose;
//! 2. optimise ([`optimise`]): the modalities and the bounded Gauss-Newton loop;
//! 3. assess: the depth safety net at a fresh frame ([`safety_net`]), then quality, state and the recorded
//!    estimate ([`assess`]).
//!
//! Re-detection probes a place with [`ObjectTrack::probe_depth`] ([`depth_check`]) and moves the object there
//! with [`ObjectTrack::relocate_on`] ([`placement`]); a depth frame that arrived late is handled in
//! [`late_depth`].

mod assess;
mod carried_depth;
mod correspond;
mod depth_check;
mod history;
mod inputs;
mod late_depth;
mod model;
mod motion;
mod optimise;
mod placement;
mod quality_window;
mod range_align;
mod range_track;
mod safety_net;
mod scratch;
mod start;
mod state;

pub(crate) use inputs::TickInputs;
pub(crate) use model::ObjectModel;
pub(crate) use start::TickDepth;
pub(crate) use state::ObjectState;

use super::config::TrackerConfig;
use crate::recon::DepthRig;
use depth_check::weaker_fit;
use drivers::recording::DepthFrame;
use nalgebra::{Isometry3, Vector3};
use scene::mesh::Symmetry;
use scratch::TickScratch;

/// A tracked object: its model, its state and the buffers its tick reuses.
#[derive(Debug)]
pub(crate) struct ObjectTrack {
    /// What the object is.
    pub model: ObjectModel,
    /// Where it is and how it is tracked (saved and restored as a whole).
    pub state: ObjectState,
    /// The buffers one tick fills.
    pub scratch: TickScratch,
}

impl ObjectTrack {
    /// The track of object `label` (box `aabb_min..aabb_max`, `symmetries`), first seen at `pose` at `t_us`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        label: u16,
        diameter: f64,
        aabb_min: Vector3<f64>,
        aabb_max: Vector3<f64>,
        pose: Isometry3<f64>,
        t_us: i64,
        symmetries: &[Symmetry],
        config: &TrackerConfig,
    ) -> Self {
        Self {
            model: ObjectModel::new(label, diameter, aabb_min, aabb_max, symmetries),
            state: ObjectState::new(pose, t_us, config.quality.lost_mean_ticks as usize),
            scratch: TickScratch::new(config),
        }
    }

    /// A scratch track for checking places where this object might be (re-detection): the same model with buffers
    /// of its own, so that a check leaves this track's buffers (its carried depth above all) as they were.
    pub fn probe(&self, config: &TrackerConfig) -> Self {
        Self {
            model: self.model.clone(),
            state: ObjectState::new(
                self.state.pose,
                self.state.t_us,
                config.quality.lost_mean_ticks as usize,
            ),
            scratch: TickScratch::new(config),
        }
    }

    /// Takes over the motion state of `track`, the object this scratch track probes for (buffers untouched).
    pub fn follow(&mut self, track: &Self) {
        self.state.follow(&track.state);
    }

    /// The part of this object's tick that needs no render, run before the tracker takes the ROI render so that a
    /// render still in flight overlaps it: registers this tick's depth frame as `D_0` and renders `D_t` at the
    /// prediction, and bins the events of the tick's window.
    pub fn prepare(&mut self, inputs: &TickInputs<'_>, config: &TrackerConfig) -> TickDepth {
        let Self {
            model,
            state,
            scratch,
        } = self;
        let depth = correspond::prepare_depth(model, state, scratch, inputs, config);
        correspond::prepare_events(model, state, scratch, inputs, config);
        depth
    }

    /// Refines the predicted pose at this tick from the render already in `scratch.target` (made at the predicted
    /// poses of all objects) and `depth` from [`Self::prepare`]: correspond, optimise, assess.
    pub fn refine(&mut self, inputs: &TickInputs<'_>, config: &TrackerConfig, depth: TickDepth) {
        let Self {
            model,
            state,
            scratch,
        } = self;
        state.fallback_check = None;
        // Events binned ahead of the render at this tick ([`Self::prepare`]), if any.
        let prebinned = scratch.edges.take_prebinned();
        let Some(roi) = state.roi else {
            if depth.fresh {
                // The render failed after the frame was registered: its points move with the pose reported (a
                // late frame's are split where the object was estimated at the exposure).
                let split_at = match state.late_frame.take() {
                    Some((_, then)) => then,
                    None => state.predicted,
                };
                state
                    .carried
                    .attach_to_object(&split_at, &model.aabb_min, &model.aabb_max, 0.01);
            }
            let predicted = state.predicted;
            assess::finish(model, state, false, inputs, predicted, None, None, config);
            return;
        };
        let in_view = |scratch: &TickScratch| scratch.view.visible_pixels > 0;

        // Correspond.
        let correspondence = correspond::correspond(
            model, state, scratch, inputs, config, depth, &roi, prebinned,
        );
        let Some(start) = correspondence else {
            let held = state.pose;
            assess::finish(
                model,
                state,
                in_view(scratch),
                inputs,
                held,
                None,
                None,
                config,
            );
            return;
        };

        // Optimise.
        let (pose, depth_stats) =
            optimise::optimise(model, state, scratch, inputs, config, &roi, &start);

        // Assess.
        assess_tick(
            model,
            state,
            scratch,
            inputs,
            config,
            &roi,
            &start,
            pose,
            depth_stats,
        );
    }

    /// Checks the hypothesis `state.predicted` against the fresh depth frame of `inputs` (re-detection), using the
    /// render the caller made at it: the agreeing fraction of the model points left in view and the pose refined
    /// on depth alone ([`depth_check::probe_depth`]).
    pub fn probe_depth(
        &mut self,
        inputs: &TickInputs<'_>,
        config: &TrackerConfig,
    ) -> Option<(f64, Isometry3<f64>)> {
        depth_check::probe_depth(
            &self.model,
            &mut self.state,
            &mut self.scratch,
            inputs,
            config,
        )
    }

    /// How well the silhouette rendered at `pose` matches the fresh depth at the object's depth
    /// ([`depth_check::silhouette_agreement`]).
    pub fn silhouette_agreement(&self, pose: &Isometry3<f64>, config: &TrackerConfig) -> f64 {
        depth_check::silhouette_agreement(&self.model, &self.scratch, pose, config)
    }

    /// Moves the object to where re-detection found it on `frame`, exposed at `found_us`
    /// ([`placement::relocate_on`]).
    pub fn relocate_on(
        &mut self,
        frame: &DepthFrame,
        rig: &DepthRig,
        found: Isometry3<f64>,
        found_us: i64,
        config: &TrackerConfig,
    ) {
        placement::relocate_on(
            &self.model,
            &mut self.state,
            frame,
            rig,
            found,
            found_us,
            config,
        );
    }
}

/// The assess phase after the optimisation: the depth safety net at a fresh depth frame (a late frame had its
/// check at its exposure), the depth the frame leaves carried, then quality, state and the recorded estimate of
/// `pose`; `depth_stats` are the depth term's counts at it.
#[allow(clippy::too_many_arguments)]
fn assess_tick(
    model: &ObjectModel,
    state: &mut ObjectState,
    scratch: &TickScratch,
    inputs: &TickInputs<'_>,
    config: &TrackerConfig,
    roi: &scene::geometry::Roi,
    start: &start::Start,
    mut pose: Isometry3<f64>,
    mut depth_stats: Option<crate::refine::DepthTermStats>,
) {
    let roi_camera = inputs.camera.crop(roi);
    let mut measured_support = None;
    if start.depth.fresh
        && !start.late
        && start.use_events
        && config.safety_net.depth_fallback_margin >= 0.0
        && let Some(anchor) = state.anchor
    {
        let kept = safety_net::check(
            model,
            state,
            scratch,
            inputs,
            config,
            &roi_camera,
            pose,
            anchor,
        );
        pose = kept.pose;
        depth_stats = Some(kept.depth_stats);
        measured_support = Some(kept.event_support);
    }
    if start.depth.fresh {
        state.depth_frames_used += 1;
        state
            .carried
            .attach_to_object(&pose, &model.aabb_min, &model.aabb_max, 0.01);
    }
    let support =
        if !inputs.inner && start.use_events && state.image_speed(model, inputs.camera) > 150.0 {
            measured_support.unwrap_or_else(|| {
                scratch
                    .edges
                    .contour_support(&scratch.view, &pose, inputs.camera)
            })
        } else {
            None
        };
    // A late frame's evidence is the weaker of its agreement at the exposure, with the pose checked there, and
    // at the tick, where its object part agrees with the events' motion by construction but its background and
    // hand stay where they were measured.
    let fit = if start.late {
        weaker_fit(start.late_fit, depth_stats)
    } else {
        depth_stats.filter(|_| start.depth.weight >= 1.0)
    };
    let in_view = scratch.view.visible_pixels > 0;
    assess::finish(model, state, in_view, inputs, pose, fit, support, config);
}

//! EventTrack6D: several objects tracked together from events and depth, each refined by render-and-compare in
//! its own ROI, with mutual occlusion through the other objects' rendered masks.
//!
//! - [`engine`]: the objects and what a tick of them runs on, and the tick as its phases (clock, depth, predict,
//!   detect, the objects' steps).
//! - [`build`]: the objects set up from their meshes and first poses; [`renderers`]: the renderers and threads.
//! - [`lost_search`], [`place_check`]: re-detection of objects the tracker fell off.
//! - [`retrack`]: tracking again from a late depth frame's exposure.
//! - [`inner`]: the steps between ticks; [`prefetch`]: renders started ahead of the step that takes them.
//! - This file: [`EventTrack6d`], the [`PoseTracker`] the runtime and the offline driver drive, which hands depth
//!   frames, late ones included, to the engine as [`DepthHandling`] says.

mod build;
mod counters;
mod engine;
mod inner;
mod lost_search;
mod next_tick;
mod place_check;
mod pose_places;
mod prefetch;
mod renderers;
mod retrack;
mod setup;
mod step;
mod threads;

pub use counters::TrackerCounters;
pub use setup::{TrackError, TrackedObject, TrackingRig};

use super::config::TrackerConfig;
use super::{DepthFallbackCheck, DepthHandling, PoseEstimate, PoseTracker};
use crate::recon::EventSurface;
use drivers::event::CdEvent;
use drivers::recording::DepthFrame;
use drivers::timeline::Tick;
use engine::TickEngine;
use inner::InnerPlan;
use nalgebra::{Isometry3, Vector3};
use retrack::{Deferred, Retrack};
use scene::mesh::Simplification;
use scene::render::Renderer;

/// The EventTrack6D tracker (and, through [`super::TrackingMethod`], its baselines).
pub struct EventTrack6d {
    engine: TickEngine,
    names: Vec<String>,
    render_meshes: Vec<Simplification>,
    /// States at recent depth-exposure ticks and the events since, to track again from a late frame's exposure
    /// ([`crate::track::LateDepthConfig::retrack_late_depth`]); `None` when off.
    retrack: Option<Box<Retrack>>,
    /// Whether the next tick's renders were started since the latest estimates changed ([`Self::prepare_next_tick`]).
    prepared: bool,
    /// A late frame handed over with [`DepthHandling::AfterNextTick`] or [`DepthHandling::CarryOnly`]: the next
    /// tick carries it, and this is its exposure from then until it is tracked again from there after that tick.
    deferred: Deferred,
    /// The steps between the latest tick and the next ([`crate::track::InnerStepConfig`]).
    inner: InnerPlan,
}

impl std::fmt::Debug for EventTrack6d {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EventTrack6d")
            .field("objects", &self.names)
            .field("counters", &self.engine.counters)
            .finish_non_exhaustive()
    }
}

impl EventTrack6d {
    /// A tracker of `objects` seen by `rig`, rendering with `renderer`.
    pub fn new(
        config: TrackerConfig,
        rig: TrackingRig,
        objects: Vec<TrackedObject>,
        renderer: Box<dyn Renderer + Send>,
    ) -> Result<Self, TrackError> {
        let retrack = (config.late_depth.retrack_late_depth
            && config.late_depth.max_depth_age_ms > 0.0)
            .then(|| Box::new(Retrack::new(config.late_depth.retrack_max_events)));
        let (engine, names, render_meshes) = TickEngine::new(config, rig, objects, renderer)?;
        Ok(Self {
            engine,
            names,
            render_meshes,
            retrack,
            prepared: false,
            deferred: Deferred::No,
            inner: InnerPlan::default(),
        })
    }

    /// How each object's render mesh was simplified from its CAD mesh, in object order
    /// ([`crate::track::ExecutionConfig::render_mesh_simplify_above`]).
    pub fn render_meshes(&self) -> &[Simplification] {
        &self.render_meshes
    }

    /// Counters since creation.
    pub fn counters(&self) -> TrackerCounters {
        self.engine.counters()
    }

    /// The configuration in use.
    pub fn config(&self) -> &TrackerConfig {
        &self.engine.config
    }

    /// The event state: time surface, and reconstructed intensity if `intensity.always` is set or the intensity
    /// term's weight is positive.
    pub fn event_surface(&self) -> &EventSurface {
        &self.engine.surface
    }

    /// The rig the tracker works with.
    pub fn rig(&self) -> &TrackingRig {
        &self.engine.rig
    }

    /// Object-frame axis-aligned box centre of object `k`, metres (the point refinement rotates about).
    pub fn object_center(&self, k: usize) -> Option<Vector3<f64>> {
        self.engine.objects.get(k).map(|o| o.model.center_obj)
    }

    /// Replaces object `k`'s latest estimate with `pose` at `t_us` (a re-initialisation from an external detector
    /// or operator, or a ground-truth probe): the next tick refines from it. The motion estimate is kept; the
    /// state returns to `tracking`. Returns `false` for an unknown object or a non-finite pose.
    pub fn reset_pose(&mut self, k: usize, t_us: i64, pose: Isometry3<f64>) -> bool {
        let reset = self.engine.reset_pose(k, t_us, pose);
        if reset {
            self.prepared = false;
        }
        reset
    }

    /// Hands `events` to the event state (logged while tracking again may need them).
    fn integrate(&mut self, events: &[CdEvent]) {
        let engine = &mut self.engine;
        if engine.config.modalities.events || engine.refines(false) {
            match self.retrack.as_mut() {
                Some(r) if r.is_logging() => engine.surface.integrate_logged(events, &mut r.log),
                _ => engine.surface.integrate(events),
            }
        }
    }

    /// The step between ticks at `t_us`, then the renders for the step after it.
    fn step_inner(&mut self, t_us: i64) {
        self.engine.step_inner(t_us);
        if self.prepared {
            prefetch::prefetch_renders(&mut self.engine, self.inner.next_time());
        }
    }

    /// Tracks again from a late frame waiting in the engine if it can; then starts the next tick's renders from
    /// the new estimates.
    fn retrack_on_arrival(&mut self) {
        let Some(retrack) = self.retrack.as_mut() else {
            return;
        };
        if retrack.on_arrival(&mut self.engine, &mut self.inner) {
            self.prepared = false;
            self.prepare_next_tick();
        }
    }

    /// After a tick carried the late frame exposed at `exposed_us` (handed over with
    /// [`DepthHandling::AfterNextTick`]): tracks the ticks from its exposure to that tick again with it, as
    /// [`Self::retrack_on_arrival`] would have before the tick. The frame was counted, and its safety-net check
    /// reported, by the tick that carried it.
    fn retrack_deferred(&mut self, exposed_us: i64) {
        let counted = self.engine.counters;
        self.engine.depth_t_us = Some(exposed_us);
        self.retrack_on_arrival();
        if self.engine.depth_t_us.take().is_some() {
            self.engine.counters.late_frames_not_retracked += 1;
            return;
        }
        self.engine.counters.depth_frames = counted.depth_frames;
        self.engine.counters.depth_frames_late = counted.depth_frames_late;
        if let Some(r) = self.retrack.as_mut() {
            r.forget_arrival_checks();
        }
    }
}

impl PoseTracker for EventTrack6d {
    fn objects(&self) -> &[String] {
        &self.names
    }

    fn render_device(&self) -> Option<scene::render::RenderDevice> {
        Some(self.engine.renderers.main.device())
    }

    fn push_events(&mut self, events: &[CdEvent]) {
        let mut rest = events;
        // A step between ticks runs once an event after its time shows that every event up to it is in.
        while let Some(t_us) = self.inner.next_time() {
            let split = rest.partition_point(|e| e.t_us <= t_us);
            if split == rest.len() {
                break;
            }
            self.integrate(&rest[..split]);
            rest = &rest[split..];
            self.inner.advance();
            self.step_inner(t_us);
        }
        self.integrate(rest);
    }

    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame, handling: DepthHandling) {
        if let Deferred::AfterTick(exposed_us) = self.deferred {
            // Tracking again needs the frame the tick carried, which this one replaces.
            self.deferred = Deferred::No;
            self.retrack_deferred(exposed_us);
        }
        self.engine.take_depth(t_us, frame);
        self.deferred = Deferred::No;
        match handling {
            DepthHandling::Now => self.retrack_on_arrival(),
            DepthHandling::AfterNextTick if self.retrack.is_some() => {
                self.deferred = Deferred::BeforeTick;
            }
            DepthHandling::CarryOnly if self.retrack.is_some() => {
                self.deferred = Deferred::CarryOnly;
            }
            DepthHandling::AfterNextTick | DepthHandling::CarryOnly => {}
        }
    }

    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        self.prepared = false;
        if let Some(retrack) = self.retrack.as_mut() {
            let defer = std::mem::replace(&mut self.deferred, Deferred::No);
            self.deferred = retrack.before_tick(&mut self.engine, &mut self.inner, tick, defer);
        }
        // Steps planned after the latest tick that no event after their time reached are not run.
        self.inner.clear();
        self.engine.step_tick(tick, out, true);
        self.inner.plan(&self.engine, tick.t_us);
    }

    fn take_revision(&mut self) -> Option<i64> {
        self.retrack.as_mut().and_then(|r| r.take_revision())
    }

    fn prepare_next_tick(&mut self) {
        if let Deferred::AfterTick(exposed_us) = self.deferred {
            self.deferred = Deferred::No;
            self.retrack_deferred(exposed_us);
        }
        if self.prepared {
            // Started already for these estimates (after tracking again when a frame arrived).
            return;
        }
        self.prepared = true;
        self.engine.catch_up_background();
        prefetch::prefetch_renders(&mut self.engine, self.inner.next_time());
    }

    fn event_surface(&self) -> Option<&EventSurface> {
        Some(&self.engine.surface)
    }

    fn tracker_counters(&self) -> Option<TrackerCounters> {
        Some(self.counters())
    }

    fn depth_fallback_checks(&self, out: &mut Vec<DepthFallbackCheck>) {
        // A check is the latest tick's only if the object refined at that tick (or tracked again before it).
        let latest = self.engine.last_tick_us;
        if let Some(r) = &self.retrack {
            out.extend_from_slice(r.checks());
        }
        out.extend(
            self.engine
                .objects
                .iter()
                .filter_map(|o| o.state.fallback_check)
                .filter(|c| Some(c.tick_us) == latest),
        );
    }

    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        self.engine.pose_at(object, t_us)
    }

    fn reseed(&mut self, object: usize, t_us: i64, pose: Isometry3<f64>) -> Result<(), String> {
        if !crate::track::hold::is_finite(&pose) {
            return Err("the pose is not finite".into());
        }
        if !self.engine.reseed(object, t_us, pose) {
            return Err(format!("no object {object}"));
        }
        if let Some(r) = self.retrack.as_mut() {
            r.forget_all();
        }
        self.deferred = Deferred::No;
        self.prepared = false;
        Ok(())
    }
}

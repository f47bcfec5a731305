//! What one tick of all objects runs on, and the tick itself as its phases: the clock advanced and the depth
//! frame chosen, every object predicted, lost objects re-detected, each object stepped (correspond, optimise,
//! assess: [`crate::track::object`]), and the estimates handed out.

use super::build::{BuiltObjects, build_objects};
use super::counters::TrackerCounters;
use super::lost_search::{Redetection, SearchFrame};
use super::next_tick::NextTick;
use super::place_check::ProbeSet;
use super::renderers::Renderers;
use super::setup::{TrackError, TrackedObject, TrackingRig};
use super::step::ObjectStep;
use crate::recon::EventSurface;
use crate::track::config::{DepthUse, TrackerConfig};
use crate::track::estimate::{PoseEstimate, TrackingState};
use crate::track::object::{ObjectTrack, TickInputs};
use drivers::recording::DepthFrame;
use drivers::timeline::Tick;
use nalgebra::Isometry3;
use scene::geometry::se3;
use scene::mesh::Simplification;
use scene::render::{RenderAhead, Renderer, Scene, SceneObject};

/// The tracked objects with everything a tick of them needs: the configuration and rig, the renderers and
/// threads, the event state, the latest depth frame, re-detection, and the counters. Saving the objects' states
/// and `last_tick_us` (see [`super::retrack`]) and restoring them puts the engine back at an earlier tick.
pub(super) struct TickEngine {
    pub config: TrackerConfig,
    pub rig: TrackingRig,
    pub renderers: Renderers,
    pub surface: EventSurface,
    pub objects: Vec<ObjectTrack>,
    /// Every object in the renderer's scene, at its latest prediction.
    pub scene: Vec<SceneObject>,
    /// The latest depth frame handed over, and its exposure while no tick has used it yet.
    pub depth: DepthFrame,
    pub depth_t_us: Option<i64>,
    pub last_tick_us: Option<i64>,
    /// Whether a step between ticks ran since the latest tick.
    pub inner_since_tick: bool,
    /// When the next tick is expected (for the renders prefetched for it).
    pub next_tick: NextTick,
    pub counters: TrackerCounters,
    pub redetection: Redetection,
}

impl TickEngine {
    /// The engine of `objects` seen by `rig`, rendering with `renderer`; also returns the objects' names and how
    /// their render meshes were simplified.
    pub fn new(
        config: TrackerConfig,
        rig: TrackingRig,
        objects: Vec<TrackedObject>,
        mut renderer: Box<dyn Renderer + Send>,
    ) -> Result<(Self, Vec<String>, Vec<Simplification>), TrackError> {
        if objects.is_empty() {
            return Err(TrackError::NoObjects);
        }
        if objects.len() > 65534 {
            return Err(TrackError::TooManyObjects(objects.len()));
        }
        if config.execution.prefetch_renders
            && config.modalities.depth != DepthUse::DepthFramesOnly
            && !renderer.renders_ahead()
        {
            renderer = Box::new(RenderAhead::new(renderer));
        }
        let BuiltObjects {
            names,
            render_meshes,
            tracks,
            scene,
            shapes,
        } = build_objects(&config, objects, renderer.as_mut())?;
        let renderers = Renderers::new(&config, tracks.len(), renderer);
        let probes = if config.redetect.enabled {
            (0..=renderers.workers.len())
                .map(|_| ProbeSet::new(&tracks, &scene, &config))
                .collect()
        } else {
            Vec::new()
        };
        let depth_cam = rig.depth.camera;
        let redetection = Redetection::new(&config, &scene, &depth_cam, probes, shapes);
        let cam = rig.event_camera;
        // `I_t` is reconstructed only where something reads it: the event term needs the latest times alone.
        let surface = if config.intensity.always || config.intensity_term.weight > 0.0 {
            EventSurface::new(cam.width, cam.height, config.intensity)
        } else {
            EventSurface::latest_times_only(cam.width, cam.height)
        };
        let mut engine = Self {
            surface,
            depth: DepthFrame {
                index: 0,
                width: depth_cam.width,
                height: depth_cam.height,
                depth_m: Vec::with_capacity(depth_cam.width as usize * depth_cam.height as usize),
            },
            config,
            rig,
            renderers,
            objects: tracks,
            scene,
            depth_t_us: None,
            last_tick_us: None,
            inner_since_tick: false,
            next_tick: NextTick::new(rig.clock),
            counters: TrackerCounters::default(),
            redetection,
        };
        engine.render_first_rois(&names)?;
        Ok((engine, names, render_meshes))
    }

    /// Renders each object's ROI at its first pose once, before any tick: a GPU compiles its pipelines and sizes
    /// its buffers now rather than in the first tick's latency, and a renderer that cannot render fails here.
    fn render_first_rois(&mut self, names: &[String]) -> Result<(), TrackError> {
        let scene = Scene::objects(&self.scene)
            .geometry_only()
            .normals_on_surface_grid(self.config.correspond.max_surface_points);
        let camera = &self.rig.event_camera;
        for (o, name) in self.objects.iter_mut().zip(names) {
            let first = o.state.pose;
            let Some(roi) =
                o.state
                    .roi_at(&o.model, &first, camera, &self.config, o.state.t_us, false)
            else {
                continue;
            };
            self.renderers
                .main
                .render_roi(&scene, camera, &roi, &mut o.scratch.target)
                .map_err(|source| TrackError::Render {
                    object: name.clone(),
                    source,
                })?;
        }
        Ok(())
    }

    /// Counters since creation.
    pub fn counters(&self) -> TrackerCounters {
        let prefetch = || self.renderers.all().map(|r| r.prefetch_counts());
        TrackerCounters {
            depth_fallbacks: self.objects.iter().map(|o| o.state.fallbacks).sum(),
            redetections: self.objects.iter().map(|o| o.state.redetections).sum(),
            late_depth_unplaced: self
                .objects
                .iter()
                .map(|o| o.state.late_depth_unplaced)
                .sum(),
            renders_prefetched: prefetch().map(|p| p.started).sum(),
            prefetched_renders_used: prefetch().map(|p| p.used).sum(),
            ..self.counters
        }
    }

    /// Takes `frame`, exposed at `t_us`, as the waiting depth frame (the previous one comes back in `frame`); a
    /// frame no tick used is counted as unused.
    pub fn take_depth(&mut self, t_us: i64, frame: &mut DepthFrame) {
        self.catch_up_background();
        if self.depth_t_us.is_some() {
            self.counters.depth_frames_unused += 1;
        }
        std::mem::swap(&mut self.depth, frame);
        self.depth_t_us = Some(t_us);
    }

    /// Folds the depth frame of the latest depth tick into the re-detection background, if it is not yet.
    pub fn catch_up_background(&mut self) {
        self.redetection.catch_up(&self.depth);
    }

    /// Whether any object refines at a tick (the `depth30` baseline refines only at depth exposures).
    pub fn refines(&self, depth_now: bool) -> bool {
        self.config.modalities.depth != DepthUse::DepthFramesOnly || depth_now
    }

    /// Replaces object `k`'s latest estimate with `pose` at `t_us`; `false` for an unknown object or a pose that
    /// is not finite.
    pub fn reset_pose(&mut self, k: usize, t_us: i64, pose: Isometry3<f64>) -> bool {
        let finite = pose.translation.vector.iter().all(|v| v.is_finite())
            && pose.rotation.coords.iter().all(|v| v.is_finite());
        match self.objects.get_mut(k) {
            Some(o) if finite => {
                o.state.reset(t_us, pose);
                true
            }
            _ => false,
        }
    }

    /// Re-seeds object `k` at `pose` as of `t_us` ([`crate::track::PoseTracker::reseed`]): its estimate is replaced
    /// and what was measured at the old one forgotten; `false` for an unknown object.
    pub fn reseed(&mut self, k: usize, t_us: i64, pose: Isometry3<f64>) -> bool {
        let Some(o) = self.objects.get_mut(k) else {
            return false;
        };
        o.state.reset(t_us, pose);
        // Nothing measured at the replaced estimate carries over: not its motion, not the depth anchors the next
        // frame's motion would be measured from, not the depth agreement and visibility its quality holds until
        // the next frame (the object starts as at its first pose).
        o.state.velocity = nalgebra::Vector6::zeros();
        o.state.velocity_weight = 0.0;
        o.state.previous = None;
        o.state.anchor = None;
        o.state.anchor_before = None;
        o.state.ranges.clear();
        o.state.depth_fit = 1.0;
        o.state.visibility = 1.0;
        self.renderers.forget_prefetched();
        true
    }

    /// One tick of every object, as its phases, and the estimates into `out`. `live` is false for a tick tracked
    /// again from a late frame's exposure (its time is not the clock's).
    pub fn step_tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>, live: bool) {
        let t_us = tick.t_us;
        let previous_tick_us = self.last_tick_us;
        let dt_s = self.advance_clock(t_us, live);
        let exposed_us = self.depth_for_tick(t_us);
        let depth_now = exposed_us.is_some();
        self.predict(t_us);
        let refines = self.refines(depth_now);
        if refines && self.config.redetect.enabled {
            self.detect(t_us, exposed_us, dt_s);
        }
        let velocity_since_us = previous_tick_us.filter(|_| self.inner_since_tick);
        self.step_objects(t_us, dt_s, exposed_us, refines, velocity_since_us, None);
        self.inner_since_tick = false;
        if depth_now {
            self.counters.depth_frames += 1;
            self.depth_t_us = None;
        }
        out.extend(self.objects.iter().enumerate().map(|(k, o)| PoseEstimate {
            object: k,
            t_us,
            pose: o.state.pose,
            quality: o.state.quality,
            state: o.state.reported.get(),
        }));
    }

    /// A step between ticks at `t_us` ([`crate::track::InnerStepConfig`]), on the events up to it: the objects that
    /// are not `lost` and move at least `inner_step_px` per tick at their smoothed velocity are predicted and stepped (correspond, optimise) without depth frame or re-detection, their
    /// quality and state left as the latest tick assessed them. Nothing is handed out; the next tick starts from
    /// these estimates. Nothing happens before the first tick, at or before the latest one, or when the tracker
    /// refines only at depth frames.
    pub fn step_inner(&mut self, t_us: i64) {
        if self.last_tick_us.is_none_or(|t| t_us <= t) || !self.refines(false) {
            return;
        }
        self.inner_since_tick = true;
        self.counters.inner_steps += 1;
        self.predict(t_us);
        let min_speed = self.config.inner_steps.inner_step_px / self.rig.clock.period_s();
        let dt_s = (t_us - self.last_tick_us.unwrap_or(t_us)) as f64 * 1e-6;
        self.step_objects(t_us, dt_s, None, true, None, Some(min_speed));
    }

    /// The clock phase: the seconds since the previous tick (one nominal period at the first), recorded for the
    /// next tick's guess when `live`.
    fn advance_clock(&mut self, t_us: i64, live: bool) -> f64 {
        let dt_s = self
            .last_tick_us
            .map(|t| (t_us - t) as f64 * 1e-6)
            .unwrap_or(self.rig.clock.period_s())
            .max(0.0);
        if live {
            self.next_tick.record(t_us);
        }
        self.last_tick_us = Some(t_us);
        self.counters.ticks += 1;
        dt_s
    }

    /// Which depth frame the tick at `t_us` uses: its exposure, if one waits. A frame belongs to this tick if it
    /// was exposed within half a tick period of it; one exposed earlier arrived late (a live depth camera's
    /// transport) and is used now unless it is older than `max_depth_age_ms`, when it is dropped and counted.
    fn depth_for_tick(&mut self, t_us: i64) -> Option<i64> {
        let half = self.rig.clock.half_period_us();
        let max_age_us = (self.config.late_depth.max_depth_age_ms * 1e3) as i64;
        match self.depth_t_us {
            Some(td) if (td - t_us).abs() <= half => Some(t_us),
            Some(td) if td < t_us - half && t_us - td <= max_age_us => {
                self.counters.depth_frames_late += 1;
                Some(td)
            }
            Some(td) if td < t_us - half => {
                self.depth_t_us = None;
                self.counters.depth_frames_unused += 1;
                None
            }
            _ => None,
        }
    }

    /// The predict phase: every object's pose at `t_us` by its motion model, and the scene at those poses.
    fn predict(&mut self, t_us: i64) {
        for o in &mut self.objects {
            let step = (t_us - o.state.t_us) as f64 * 1e-6;
            o.state.predict(&o.model, step.max(0.0), &self.config);
        }
        for (s, o) in self.scene.iter_mut().zip(&self.objects) {
            s.pose = o.state.predicted;
        }
    }

    /// The detect phase: at a depth frame, plans the search for objects that are not tracked; at every tick,
    /// checks some of the planned places and moves an object whose search found it.
    fn detect(&mut self, t_us: i64, exposed_us: Option<i64>, dt_s: f64) {
        if let Some(exposed_us) = exposed_us {
            // Off the tick's latency unless planning reads it (the frame is cold in cache in a live run).
            self.redetection.background_behind = true;
            self.redetection.plan(
                &self.config,
                &mut self.counters,
                &self.depth,
                &self.rig,
                &self.objects,
                t_us,
                exposed_us,
                dt_s,
            );
        }
        let frame = SearchFrame {
            config: &self.config,
            rig: &self.rig,
            depth: &self.depth,
            surface: &self.surface,
        };
        self.redetection.continue_search(
            &frame,
            &mut self.counters,
            &mut self.objects,
            &mut self.scene,
            &mut self.renderers,
            dt_s,
        );
    }

    /// The step of every object at `t_us` (correspond, optimise, assess; see [`crate::track::object`]), split over
    /// the renderers' threads, with the depth frame exposed at `exposed_us` if this tick uses one. At a tick after
    /// steps between ticks, `velocity_since_us` is the previous tick's time; at a step between ticks,
    /// `inner_min_speed` is the image speed (pixels per second) an object needs to be stepped. Renders that fail
    /// are counted.
    fn step_objects(
        &mut self,
        t_us: i64,
        dt_s: f64,
        exposed_us: Option<i64>,
        refines: bool,
        velocity_since_us: Option<i64>,
        inner_min_speed: Option<f64>,
    ) {
        let depth_now = exposed_us.is_some();
        let inputs = TickInputs {
            t_us,
            dt_s,
            inner: inner_min_speed.is_some(),
            span: 1.0,
            velocity_since_us,
            depth: depth_now.then_some(&self.depth),
            depth_exposed_us: exposed_us.unwrap_or(t_us),
            surface: &self.surface,
            camera: &self.rig.event_camera,
            depth_rig: &self.rig.depth,
        };
        // The tracker compares geometry only (no texturing), and reads normals only on the surface grid.
        let scene = Scene::objects(&self.scene)
            .geometry_only()
            .normals_on_surface_grid(self.config.correspond.max_surface_points);
        let step = ObjectStep {
            scene: &scene,
            camera: &self.rig.event_camera,
            config: &self.config,
            inputs,
            refines,
            depth_now,
            own_span: self.inner_since_tick.then(|| self.rig.clock.period_s()),
            inner_min_speed,
        };
        self.counters.render_errors += step.run_split(&mut self.objects, &mut self.renderers);
    }

    /// The pose of object `object` at any time `t_us`: from the recent estimates, interpolated between the ticks
    /// either side, else extrapolated at most one tick period past the latest; `None` before the first tick or
    /// for an unknown object. Reported `degraded` more than a tick period past the latest estimate.
    pub fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        let o = self.objects.get(object)?;
        self.last_tick_us?;
        let period_us = self.rig.clock.whole_period_us();
        let pose = match o.state.previous {
            _ if let Some(p) = o.state.history.at(t_us) => p,
            Some((t0, p0)) if o.state.t_us > t0 => {
                let s = (t_us - t0) as f64 / (o.state.t_us - t0) as f64;
                let limit = 1.0 + period_us as f64 / (o.state.t_us - t0) as f64;
                se3::interpolate(&p0, &o.state.pose, s.clamp(0.0, limit))
            }
            _ => o.state.pose,
        };
        let state = match o.state.reported.get() {
            TrackingState::Tracking if t_us > o.state.t_us + period_us => TrackingState::Degraded,
            reported => reported,
        };
        Some(PoseEstimate {
            object,
            t_us,
            pose,
            quality: o.state.quality,
            state,
        })
    }
}

//! EventTrack6D: several objects tracked together from events and depth, each refined by render-and-compare in
//! its own ROI, with mutual occlusion through the other objects' rendered masks.

mod counters;
mod lost_search;
mod next_tick;
mod place_check;
mod retrack;
mod setup;
mod step;
mod threads;

pub use counters::TrackerCounters;
pub use setup::{TrackError, TrackedObject, TrackingRig};

use super::config::{DepthUse, TrackerConfig};
use super::object::ObjectTrack;
use super::{DepthFallbackCheck, PoseEstimate, PoseTracker, TrackingState};
use lost_search::Redetection;
use next_tick::NextTick;
use place_check::ProbeSet;
use retrack::{Deferred, Retrack};
use threads::ObjectThreads;

use crate::recon::EventSurface;
use drivers::event::CdEvent;
use drivers::recording::DepthFrame;
use drivers::timeline::Tick;
use nalgebra::{Isometry3, Vector3};
use scene::geometry::se3;
use scene::mesh::{Simplification, simplify_for_render};
use scene::render::{RenderAhead, Renderer, Scene, SceneObject};
use std::sync::Arc;

/// The EventTrack6D tracker (and, through [`super::TrackingMethod`], its baselines).
pub struct EventTrack6d {
    config: TrackerConfig,
    names: Vec<String>,
    render_meshes: Vec<Simplification>,
    rig: TrackingRig,
    renderer: Box<dyn Renderer + Send>,
    /// Forks of `renderer` for the threads that step objects beside the tracker's own ([`TrackerConfig::object_threads`]).
    workers: Vec<Box<dyn Renderer + Send>>,
    /// The threads the workers step objects and check places on (started at the first tick that needs them).
    threads: ObjectThreads,
    surface: EventSurface,
    objects: Vec<ObjectTrack>,
    scene: Vec<SceneObject>,
    depth: DepthFrame,
    depth_t_us: Option<i64>,
    last_tick_us: Option<i64>,
    /// When the next tick is expected (for the renders prefetched for it).
    next_tick: NextTick,
    counters: TrackerCounters,
    redetection: Redetection,
    /// States at recent depth-exposure ticks and the events since, to track again from a late frame's exposure
    /// ([`TrackerConfig::retrack_late_depth`]); `None` when off.
    retrack: Option<Box<Retrack>>,
    /// Whether the next tick's renders were started since the latest estimates changed ([`Self::prepare_next_tick`]).
    prepared: bool,
    /// A late frame handed over with [`PoseTracker::push_depth_deferred`]: the next tick carries it, and this is
    /// its exposure from then until it is tracked again from there after that tick.
    deferred: Deferred,
}

impl std::fmt::Debug for EventTrack6d {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EventTrack6d")
            .field("objects", &self.names)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl EventTrack6d {
    /// A tracker of `objects` seen by `rig`, rendering with `renderer`.
    pub fn new(
        config: TrackerConfig,
        rig: TrackingRig,
        objects: Vec<TrackedObject>,
        mut renderer: Box<dyn Renderer + Send>,
    ) -> Result<Self, TrackError> {
        if objects.is_empty() {
            return Err(TrackError::NoObjects);
        }
        if objects.len() > 65534 {
            return Err(TrackError::TooManyObjects(objects.len()));
        }
        if config.prefetch_renders
            && config.depth != DepthUse::DepthFramesOnly
            && !renderer.renders_ahead()
        {
            renderer = Box::new(RenderAhead::new(renderer));
        }
        let mut tracks = Vec::with_capacity(objects.len());
        let mut scene = Vec::with_capacity(objects.len());
        let mut names = Vec::with_capacity(objects.len());
        let mut render_meshes = Vec::with_capacity(objects.len());
        for (k, o) in objects.into_iter().enumerate() {
            let p = &o.first_pose;
            if !(p.translation.vector.iter().all(|v| v.is_finite())
                && p.rotation.coords.iter().all(|v| v.is_finite()))
            {
                return Err(TrackError::BadFirstPose {
                    object: o.name,
                    reason: "not finite",
                });
            }
            if p.translation.z <= 0.0 {
                return Err(TrackError::BadFirstPose {
                    object: o.name,
                    reason: "behind the camera (z <= 0)",
                });
            }
            let aabb = o.mesh.aabb();
            let label = (k + 1) as u16;
            let diameter = if o.diameter.is_finite() && o.diameter > 0.0 {
                o.diameter
            } else {
                o.mesh.diameter()
            };
            let roi_pixel_m = config.roi_scale * diameter / f64::from(config.roi_size);
            let tolerance_m = if o.mesh.triangles().len() > config.render_mesh_simplify_above {
                config.render_mesh_tolerance_px * roi_pixel_m
            } else {
                0.0
            };
            let (render_mesh, simplification) = simplify_for_render(&o.mesh, tolerance_m);
            render_meshes.push(simplification);
            let mesh_id =
                renderer
                    .add_mesh(Arc::new(render_mesh))
                    .map_err(|source| TrackError::Render {
                        object: o.name.clone(),
                        source,
                    })?;
            tracks.push(ObjectTrack::new(
                label,
                diameter,
                aabb.min.coords,
                aabb.max.coords,
                o.first_pose,
                o.first_t_us,
                &o.symmetries,
                &config,
            ));
            scene.push(SceneObject {
                mesh: mesh_id,
                pose: o.first_pose,
                id: label,
            });
            names.push(o.name);
        }
        let objects_len = tracks.len();
        let threads = match config.object_threads {
            0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
            n => n,
        };
        // Threads step objects and check re-detection places; a single object's places are checked on several.
        let checks_at_once = match config.redetect {
            r if !r.enabled => 1,
            r if r.places_per_tick == 0 || config.depth == DepthUse::DepthFramesOnly => threads,
            r => r.places_per_tick,
        };
        let workers: Vec<_> = (1..threads.min(objects_len.max(checks_at_once)))
            .map_while(|_| renderer.fork())
            .collect();
        let probes = if config.redetect.enabled {
            (0..=workers.len())
                .map(|_| ProbeSet::new(&tracks, &scene, &config))
                .collect()
        } else {
            Vec::new()
        };
        let depth_cam = rig.depth.camera;
        let redetection = Redetection::new(&config, &scene, &depth_cam, probes);
        let cam = rig.event_camera;
        // `I_t` is reconstructed only where something reads it: the event term needs the latest times alone.
        let surface = if config.intensity.always || config.intensity_term.weight > 0.0 {
            EventSurface::new(cam.width, cam.height, config.intensity)
        } else {
            EventSurface::latest_times_only(cam.width, cam.height)
        };
        let config_retrack = config.retrack_late_depth && config.max_depth_age_ms > 0.0;
        let retrack_events = config.retrack_max_events;
        let mut tracker = Self {
            surface,
            depth: DepthFrame {
                index: 0,
                width: depth_cam.width,
                height: depth_cam.height,
                depth_m: Vec::with_capacity(depth_cam.width as usize * depth_cam.height as usize),
            },
            config,
            names,
            render_meshes,
            rig,
            renderer,
            workers,
            threads: ObjectThreads::default(),
            objects: tracks,
            scene,
            depth_t_us: None,
            last_tick_us: None,
            next_tick: NextTick::default(),
            counters: TrackerCounters::default(),
            redetection,
            retrack: config_retrack.then(|| Box::new(Retrack::new(retrack_events))),
            prepared: false,
            deferred: Deferred::No,
        };
        tracker.render_first_rois()?;
        Ok(tracker)
    }

    /// Renders each object's ROI at its first pose once, before any tick: a GPU compiles its pipelines and sizes
    /// its buffers now rather than in the first tick's latency, and a renderer that cannot render fails here.
    fn render_first_rois(&mut self) -> Result<(), TrackError> {
        let scene = Scene::objects(&self.scene)
            .geometry_only()
            .normals_on_surface_grid(self.config.max_surface_points);
        let camera = &self.rig.event_camera;
        for (o, name) in self.objects.iter_mut().zip(&self.names) {
            let first = o.state.pose;
            let Some(roi) =
                o.state
                    .roi_at(&o.model, &first, camera, &self.config, o.state.t_us, false)
            else {
                continue;
            };
            self.renderer
                .render_roi(&scene, camera, &roi, &mut o.scratch.target)
                .map_err(|source| TrackError::Render {
                    object: name.clone(),
                    source,
                })?;
        }
        Ok(())
    }

    /// How each object's render mesh was simplified from its CAD mesh, in object order
    /// ([`TrackerConfig::render_mesh_simplify_above`]).
    pub fn render_meshes(&self) -> &[Simplification] {
        &self.render_meshes
    }

    /// Counters since creation.
    pub fn counters(&self) -> TrackerCounters {
        let prefetch = std::iter::once(&self.renderer)
            .chain(&self.workers)
            .map(|r| r.prefetch_counts());
        TrackerCounters {
            depth_fallbacks: self.objects.iter().map(|o| o.state.fallbacks).sum(),
            redetections: self.objects.iter().map(|o| o.state.redetections).sum(),
            late_depth_unplaced: self
                .objects
                .iter()
                .map(|o| o.state.late_depth_unplaced)
                .sum(),
            renders_prefetched: prefetch.clone().map(|p| p.started).sum(),
            prefetched_renders_used: prefetch.map(|p| p.used).sum(),
            ..self.counters
        }
    }

    /// Starts each object's render for the tick expected at `next_t_us`, at the pose that tick will predict, in the
    /// ROI it will choose without a depth frame ([`TrackerConfig::prefetch_renders`]). A failed prefetch is not
    /// reported here: the next tick renders again and counts the error then.
    fn prefetch_next(&mut self, next_t_us: i64) {
        for (s, o) in self.scene.iter_mut().zip(&self.objects) {
            let step = (next_t_us - o.state.t_us) as f64 * 1e-6;
            s.pose = o.state.prediction(&o.model, step.max(0.0), &self.config);
        }
        let scene = Scene::objects(&self.scene)
            .geometry_only()
            .normals_on_surface_grid(self.config.max_surface_points);
        let camera = &self.rig.event_camera;
        // Each object's render is made ahead by the renderer that will step it ([`ObjectStep::run_split`]).
        let share = step::own_share(self.objects.len(), self.workers.len());
        let renderers = std::iter::once(&mut self.renderer).chain(&mut self.workers);
        for ((objects, poses), renderer) in self
            .objects
            .chunks(share.max(1))
            .zip(self.scene.chunks(share.max(1)))
            .zip(renderers)
        {
            for (o, s) in objects.iter().zip(poses) {
                if next_t_us < o.state.t_us {
                    continue;
                }
                if let Some(roi) =
                    o.state
                        .roi_at(&o.model, &s.pose, camera, &self.config, next_t_us, false)
                {
                    let _ = renderer.prefetch_roi(&scene, camera, &roi);
                }
            }
        }
    }

    /// The configuration in use.
    pub fn config(&self) -> &TrackerConfig {
        &self.config
    }

    /// The event state: time surface, and reconstructed intensity if `intensity.always` is set or the intensity
    /// term's weight is positive.
    pub fn event_surface(&self) -> &EventSurface {
        &self.surface
    }

    /// The rig the tracker works with.
    pub fn rig(&self) -> &TrackingRig {
        &self.rig
    }

    /// Object-frame axis-aligned box centre of object `k`, metres (the point refinement rotates about).
    pub fn object_center(&self, k: usize) -> Option<Vector3<f64>> {
        self.objects.get(k).map(|o| o.model.center_obj)
    }

    /// Replaces object `k`'s latest estimate with `pose` at `t_us` (a re-initialisation from an external detector
    /// or operator, or a ground-truth probe): the next tick refines from it. The motion estimate is kept; the
    /// state returns to `tracking`. Returns `false` for an unknown object or a non-finite pose.
    pub fn reset_pose(&mut self, k: usize, t_us: i64, pose: Isometry3<f64>) -> bool {
        let finite = pose.translation.vector.iter().all(|v| v.is_finite())
            && pose.rotation.coords.iter().all(|v| v.is_finite());
        match self.objects.get_mut(k) {
            Some(o) if finite => {
                o.state.reset(t_us, pose);
                self.prepared = false;
                true
            }
            _ => false,
        }
    }

    /// Takes `frame`, exposed at `t_us`, as the waiting depth frame (the previous one comes back in `frame`).
    fn take_depth(&mut self, t_us: i64, frame: &mut DepthFrame) {
        if let Deferred::AfterTick(exposed_us) = self.deferred {
            // Tracking again needs the frame the tick carried, which this one replaces.
            self.deferred = Deferred::No;
            self.retrack_deferred(exposed_us);
        }
        self.catch_up_background();
        if self.depth_t_us.is_some() {
            self.counters.depth_frames_unused += 1;
        }
        std::mem::swap(&mut self.depth, frame);
        self.depth_t_us = Some(t_us);
        self.deferred = Deferred::No;
    }

    /// Folds the depth frame of the latest depth tick into the re-detection background, if it is not yet.
    fn catch_up_background(&mut self) {
        self.redetection.catch_up(&self.depth);
    }

    /// Whether any object refines at this tick (the `depth30` baseline refines only at depth exposures).
    fn refines(&self, depth_now: bool) -> bool {
        self.config.depth != DepthUse::DepthFramesOnly || depth_now
    }
}

impl PoseTracker for EventTrack6d {
    fn objects(&self) -> &[String] {
        &self.names
    }

    fn render_device(&self) -> Option<scene::render::RenderDevice> {
        Some(self.renderer.device())
    }

    fn push_events(&mut self, events: &[CdEvent]) {
        if self.config.events || self.config.depth != DepthUse::DepthFramesOnly {
            match self.retrack.as_mut() {
                Some(r) if r.is_logging() => self.surface.integrate_logged(events, &mut r.log),
                _ => self.surface.integrate(events),
            }
        }
    }

    fn push_depth(&mut self, t_us: i64, frame: &mut DepthFrame) {
        self.take_depth(t_us, frame);
        self.retrack_on_arrival();
    }

    fn push_depth_deferred(&mut self, t_us: i64, frame: &mut DepthFrame) {
        self.take_depth(t_us, frame);
        if self.retrack.is_some() {
            self.deferred = Deferred::BeforeTick;
        }
    }

    fn push_depth_carried(&mut self, t_us: i64, frame: &mut DepthFrame) {
        self.take_depth(t_us, frame);
        if self.retrack.is_some() {
            self.deferred = Deferred::CarryOnly;
        }
    }

    fn tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>) {
        self.prepared = false;
        self.retrack_before(tick);
        self.step_tick(tick, out, true);
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
        self.catch_up_background();
        if self.config.prefetch_renders && self.refines(false) {
            // What the last tick did not take, the next one will not either.
            self.renderer.forget_prefetched();
            for w in &mut self.workers {
                w.forget_prefetched();
            }
            let (times, count) = self.next_tick.candidates();
            for &t in &times[..count] {
                self.prefetch_next(t);
            }
        }
    }

    fn event_surface(&self) -> Option<&EventSurface> {
        Some(&self.surface)
    }

    fn tracker_counters(&self) -> Option<TrackerCounters> {
        Some(self.counters())
    }

    fn depth_fallback_checks(&self, out: &mut Vec<DepthFallbackCheck>) {
        // A check is the latest tick's only if the object refined at that tick (or tracked again before it).
        let latest = self.last_tick_us;
        if let Some(r) = &self.retrack {
            out.extend_from_slice(&r.checks);
        }
        out.extend(
            self.objects
                .iter()
                .filter_map(|o| o.state.fallback_check)
                .filter(|c| Some(c.tick_us) == latest),
        );
    }

    fn pose_at(&self, object: usize, t_us: i64) -> Option<PoseEstimate> {
        let o = self.objects.get(object)?;
        self.last_tick_us?;
        let pose = match o.state.previous {
            // Within the recent estimates: interpolated between the two ticks either side.
            _ if let Some(p) = o.state.history.at(t_us) => p,
            Some((t0, p0)) if o.state.t_us > t0 => {
                let s = (t_us - t0) as f64 / (o.state.t_us - t0) as f64;
                // Interpolate, or extrapolate at most one tick period past the latest estimate.
                let limit = 1.0 + 8_333.0 / (o.state.t_us - t0) as f64;
                se3::interpolate(&p0, &o.state.pose, s.clamp(0.0, limit))
            }
            _ => o.state.pose,
        };
        let state = match o.state.reported.get() {
            TrackingState::Tracking if t_us > o.state.t_us + 8_333 => TrackingState::Degraded,
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

//! One tick of the tracker (predict, re-detect, then step the objects), and one tick's step of a set of objects
//! (render the ROI, refine or hold), which the tracker runs on its own thread or splits over several.

use crate::track::config::TrackerConfig;
use crate::track::object::{ObjectTrack, TickInputs};
use scene::geometry::PinholeCamera;
use scene::render::{Renderer, Scene};

use super::EventTrack6d;
use super::threads::{ObjectThreads, ShareRenderers, ShareSlice};
use crate::track::PoseEstimate;
use drivers::timeline::Tick;

/// What stepping one object at a tick needs besides the object and a renderer (shared, read-only).
pub(super) struct ObjectStep<'a> {
    pub(super) scene: &'a Scene<'a>,
    pub(super) camera: &'a PinholeCamera,
    pub(super) config: &'a TrackerConfig,
    pub(super) inputs: TickInputs<'a>,
    pub(super) refines: bool,
    pub(super) depth_now: bool,
}

impl ObjectStep<'_> {
    /// Prepares each object's depth, renders its ROI and refines it (or holds it when the tick does not refine);
    /// returns the number of failed renders.
    pub(super) fn run(&self, objects: &mut [ObjectTrack], renderer: &mut dyn Renderer) -> u64 {
        let mut errors = 0;
        let t_us = self.inputs.t_us;
        for o in objects {
            if t_us < o.state.t_us {
                continue;
            }
            let roi = if self.refines {
                o.state
                    .update_roi(&o.model, self.camera, self.config, t_us, self.depth_now)
            } else {
                None
            };
            if !self.refines {
                o.state.hold(t_us);
                continue;
            }
            // Before the render is taken, so that a render still in flight overlaps it.
            let depth = o.prepare(&self.inputs, self.config);
            if let Some(roi) = roi
                && renderer
                    .render_roi(self.scene, self.camera, &roi, &mut o.scratch.target)
                    .is_err()
            {
                errors += 1;
                o.state.roi = None;
            }
            o.refine(&self.inputs, self.config, depth);
        }
        errors
    }

    /// [`Self::run`] over all `objects`: split into one share per renderer, `renderer` stepping the first share on
    /// this thread and each of `workers` one of the others on one of `threads`. Each object's step reads only the
    /// shared inputs and writes only its own track, so the split changes nothing in the results.
    pub(super) fn run_split(
        &self,
        objects: &mut [ObjectTrack],
        renderer: &mut dyn Renderer,
        workers: &mut [Box<dyn Renderer + Send>],
        threads: &mut ObjectThreads,
    ) -> u64 {
        let per_thread = own_share(objects.len(), workers.len());
        if per_thread == objects.len() {
            return self.run(objects, renderer);
        }
        let len = objects.len();
        // At most `workers.len() + 1` shares (see `own_share`).
        let shares = len.div_ceil(per_thread);
        let objects = ShareSlice::new(objects);
        let renderers = ShareRenderers::new(renderer, workers);
        threads.run(shares - 1, &|i| {
            let start = i * per_thread;
            let end = (start + per_thread).min(len);
            // SAFETY: share `i` takes `objects[start..end]`, disjoint from the other shares' ranges, and renderer
            // `i` (`i <= workers.len()`), which no other share takes; `run` runs each share once.
            let (share, renderer) = unsafe { (objects.range(start..end), renderers.get(i)) };
            self.run(share, renderer)
        })
    }
}

// The shares hand object tracks to other threads through raw pointers: keep them `Send`.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<ObjectTrack>();
};

/// How many objects, from the first, [`ObjectStep::run_split`] steps on the tracker's own thread when `workers`
/// other renderers step the rest: all of them without workers, else an even share.
pub(super) fn own_share(objects: usize, workers: usize) -> usize {
    let per_thread = objects.div_ceil(workers + 1);
    if workers == 0 || objects <= per_thread {
        objects
    } else {
        per_thread
    }
}

impl EventTrack6d {
    /// One tick of every object: predict, re-detect, render, refine, and the estimates into `out`. `live` is
    /// false for a tick tracked again from a late frame's exposure (its time is not the clock's).
    pub(super) fn step_tick(&mut self, tick: &Tick, out: &mut Vec<PoseEstimate>, live: bool) {
        let t_us = tick.t_us;

        let dt_s = self
            .last_tick_us
            .map(|t| (t_us - t) as f64 * 1e-6)
            .unwrap_or(1.0 / 120.0)
            .max(0.0);
        if live {
            self.next_tick.record(t_us);
        }
        self.last_tick_us = Some(t_us);
        self.counters.ticks += 1;
        // A depth frame belongs to this tick if it was exposed within half a tick period of it; one exposed
        // earlier arrived late (a live depth camera's transport) and is used now unless it is too old.
        let max_age_us = (self.config.max_depth_age_ms * 1e3) as i64;
        let exposed_us = match self.depth_t_us {
            Some(td) if (td - t_us).abs() <= 4_200 => Some(t_us),
            Some(td) if td < t_us - 4_200 && t_us - td <= max_age_us => {
                self.counters.depth_frames_late += 1;
                Some(td)
            }
            Some(td) if td < t_us - 4_200 => {
                self.depth_t_us = None;
                self.counters.depth_frames_unused += 1;
                None
            }
            _ => None,
        };
        let depth_now = exposed_us.is_some();
        for o in &mut self.objects {
            let step = (t_us - o.state.t_us) as f64 * 1e-6;
            o.state.predict(&o.model, step.max(0.0), &self.config);
        }
        for (s, o) in self.scene.iter_mut().zip(&self.objects) {
            s.pose = o.state.predicted;
        }
        let refines = self.refines(depth_now);
        if refines && self.config.redetect.enabled {
            if depth_now {
                // Off the tick's latency unless planning reads it (the frame is cold in cache in a live run).
                self.redetection.background_behind = true;
                self.plan_redetection(t_us, exposed_us.unwrap_or(t_us));
            }
            self.continue_redetection(dt_s);
        }
        let inputs = TickInputs {
            t_us,
            dt_s,
            depth: depth_now.then_some(&self.depth),
            depth_exposed_us: exposed_us.unwrap_or(t_us),
            surface: &self.surface,
            camera: &self.rig.event_camera,
            depth_rig: &self.rig.depth,
        };
        // The tracker compares geometry only (no texturing), and reads normals only on the surface grid.
        let scene = Scene::objects(&self.scene)
            .geometry_only()
            .normals_on_surface_grid(self.config.max_surface_points);
        let step = ObjectStep {
            scene: &scene,
            camera: &self.rig.event_camera,
            config: &self.config,
            inputs,
            refines,
            depth_now,
        };
        let render_errors = step.run_split(
            &mut self.objects,
            self.renderer.as_mut(),
            &mut self.workers,
            &mut self.threads,
        );
        self.counters.render_errors += render_errors;
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
}

//! One tick's step of a set of objects (prepare, render the ROI, refine; or hold), which the tracker runs on its
//! own thread or splits over its object threads.

use crate::track::config::TrackerConfig;
use crate::track::estimate::TrackingState;
use crate::track::object::{ObjectTrack, TickInputs};
use scene::geometry::PinholeCamera;
use scene::render::{Renderer, Scene};

use super::renderers::Renderers;
use super::threads::{ShareRenderers, ShareSlice};

/// What stepping one object at a tick needs besides the object and a renderer (shared, read-only).
pub(super) struct ObjectStep<'a> {
    pub(super) scene: &'a Scene<'a>,
    pub(super) camera: &'a PinholeCamera,
    pub(super) config: &'a TrackerConfig,
    pub(super) inputs: TickInputs<'a>,
    pub(super) refines: bool,
    pub(super) depth_now: bool,
    /// With steps between ticks since the previous tick, the tick period, seconds: each object's step spans the
    /// time since its own latest estimate (an object a step between ticks left alone spans more).
    pub(super) own_span: Option<f64>,
    /// At a step between ticks: the image speed, pixels per second, below which an object is left alone (a lost
    /// one always is).
    pub(super) inner_min_speed: Option<f64>,
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
            if let Some(min_speed) = self.inner_min_speed
                && (o.state.tracking == TrackingState::Lost
                    || o.state.image_speed(&o.model, self.camera) < min_speed)
            {
                continue;
            }
            let own_inputs;
            let inputs = if let Some(period_s) = self.own_span
                && t_us > o.state.t_us
            {
                let dt_s = (t_us - o.state.t_us) as f64 * 1e-6;
                own_inputs = TickInputs {
                    dt_s,
                    span: (dt_s / period_s).min(1.0),
                    ..self.inputs
                };
                &own_inputs
            } else {
                &self.inputs
            };
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
            let depth = o.prepare(inputs, self.config);
            if let Some(roi) = roi
                && renderer
                    .render_roi(self.scene, self.camera, &roi, &mut o.scratch.target)
                    .is_err()
            {
                errors += 1;
                o.state.roi = None;
            }
            o.refine(inputs, self.config, depth);
        }
        errors
    }

    /// [`Self::run`] over all `objects`: split into one share per renderer, `renderer` stepping the first share on
    /// this thread and each of `workers` one of the others on one of `threads`. Each object's step reads only the
    /// shared inputs and writes only its own track, so the split changes nothing in the results.
    pub(super) fn run_split(&self, objects: &mut [ObjectTrack], renderers: &mut Renderers) -> u64 {
        let Renderers {
            main: renderer,
            workers,
            threads,
        } = renderers;
        let renderer = renderer.as_mut();
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

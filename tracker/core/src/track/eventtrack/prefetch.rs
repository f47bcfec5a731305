//! Renders started ahead of the step that takes them ([`crate::track::ExecutionConfig::prefetch_renders`]): each
//! object's ROI at the pose the next step (between ticks, or the next tick) will predict, on the renderer that will
//! step it.

use super::engine::TickEngine;
use super::step::own_share;
use scene::render::Scene;

impl TickEngine {
    /// Starts each object's render for the next step: the step between ticks planned at `inner_us`, else the next
    /// tick at the times it may come ([`super::next_tick::NextTick::candidates`]); not when the tracker refines
    /// only at depth frames ([`crate::track::ExecutionConfig::prefetch_renders`]).
    pub fn prefetch_renders(&mut self, inner_us: Option<i64>) {
        if !(self.config.execution.prefetch_renders && self.refines(false)) {
            return;
        }
        // What the last step did not take, the next one will not either.
        self.renderers.forget_prefetched();
        if let Some(t) = inner_us {
            self.prefetch_next(t);
            return;
        }
        let (times, count) = self.next_tick.candidates();
        for &t in &times[..count] {
            self.prefetch_next(t);
        }
    }

    /// Starts each object's render for the tick expected at `next_t_us`, at the pose that tick will predict, in the
    /// ROI it will choose without a depth frame. A failed prefetch is not reported here: the next tick renders
    /// again and counts the error then.
    fn prefetch_next(&mut self, next_t_us: i64) {
        for (s, o) in self.scene.iter_mut().zip(&self.objects) {
            let step = (next_t_us - o.state.t_us) as f64 * 1e-6;
            s.pose = o.state.prediction(&o.model, step.max(0.0), &self.config);
        }
        let scene = Scene::objects(&self.scene)
            .geometry_only()
            .normals_on_surface_grid(self.config.correspond.max_surface_points);
        let camera = &self.rig.event_camera;
        // Each object's render is made ahead by the renderer that will step it ([`ObjectStep::run_split`]).
        let share = own_share(self.objects.len(), self.renderers.workers.len());
        let renderers =
            std::iter::once(&mut self.renderers.main).chain(&mut self.renderers.workers);
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
}

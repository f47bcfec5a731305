//! Renders started ahead of the step that takes them ([`crate::track::ExecutionConfig::prefetch_renders`]): each
//! object's ROI at the pose the next step (between ticks, or the next tick) will predict, on the renderer that will
//! step it.

use super::engine::TickEngine;
use super::step::own_share;
use scene::render::Scene;

/// Starts each object's render for the next step: the step between ticks planned at `inner_us`, else the next
/// tick at the times it may come ([`super::next_tick::NextTick::candidates`]); not when the tracker refines
/// only at depth frames ([`crate::track::ExecutionConfig::prefetch_renders`]).
pub(super) fn prefetch_renders(engine: &mut TickEngine, inner_us: Option<i64>) {
    if !(engine.config.execution.prefetch_renders && engine.refines(false)) {
        return;
    }
    // What the last step did not take, the next one will not either.
    engine.renderers.forget_prefetched();
    if let Some(t) = inner_us {
        prefetch_next(engine, t);
        return;
    }
    let (times, count) = engine.next_tick.candidates();
    for &t in &times[..count] {
        prefetch_next(engine, t);
    }
}

/// Starts each object's render for the tick expected at `next_t_us`, at the pose that tick will predict, in the
/// ROI it will choose without a depth frame. A failed prefetch is not reported here: the next tick renders
/// again and counts the error then.
fn prefetch_next(engine: &mut TickEngine, next_t_us: i64) {
    for (s, o) in engine.scene.iter_mut().zip(&engine.objects) {
        let step = (next_t_us - o.state.t_us) as f64 * 1e-6;
        s.pose = o.state.prediction(&o.model, step.max(0.0), &engine.config);
    }
    let scene = Scene::objects(&engine.scene)
        .geometry_only()
        .normals_on_surface_grid(engine.config.correspond.max_surface_points);
    let camera = &engine.rig.event_camera;
    // Each object's render is made ahead by the renderer that will step it ([`ObjectStep::run_split`]).
    let share = own_share(engine.objects.len(), engine.renderers.workers.len());
    let renderers =
        std::iter::once(&mut engine.renderers.main).chain(&mut engine.renderers.workers);
    for ((objects, poses), renderer) in engine
        .objects
        .chunks(share.max(1))
        .zip(engine.scene.chunks(share.max(1)))
        .zip(renderers)
    {
        for (o, s) in objects.iter().zip(poses) {
            if next_t_us < o.state.t_us {
                continue;
            }
            if let Some(roi) =
                o.state
                    .roi_at(&o.model, &s.pose, camera, &engine.config, next_t_us, false)
            {
                let _ = renderer.prefetch_roi(&scene, camera, &roi);
            }
        }
    }
}

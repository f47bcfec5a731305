//! The rendering half of generation: chooses each step's length (no projected vertex moves more than the step
//! limit, and no step crosses a 120 Hz tick), renders the moving meshes over the region that can change, and
//! poses the scene for the depth frames exposed in the step. What the steps become is the sensor's half
//! ([`super::sensor`]), which also renders and measures the depth frames.

use super::GenerateError;
use super::sensor::{ChangingRegion, DepthExposure, Step};
use super::stage::Stage;
use nalgebra::Isometry3;
use scene::geometry::{PinholeCamera, Roi};
use scene::render::RenderError;

/// What the steps need that does not change during generation.
pub(super) struct StepPlan<'a> {
    /// The event camera.
    pub(super) camera: PinholeCamera,
    /// The pose of the event camera in the depth camera's frame.
    pub(super) depth_frame: Isometry3<f64>,
    /// Times of the rising 120 Hz edges, microseconds: steps end on them.
    pub(super) tick_times: &'a [f64],
    /// Depth exposures: frame index and time, microseconds, in order.
    pub(super) depth_times: &'a [(u64, i64)],
    /// End of the sequence, microseconds.
    pub(super) t_end_us: f64,
    /// Largest projected vertex motion in one step, pixels.
    pub(super) max_step_px: f64,
}

/// Totals of the rendering half.
#[derive(Debug, Default)]
pub(super) struct RenderTotals {
    /// Renders of the changing region.
    pub(super) renders: u64,
    /// Sum of the changing regions' areas, pixels.
    pub(super) region_px_sum: f64,
}

/// Renders every step of the sequence in order and hands each to `send` (which returns `false` once the sensor
/// takes no more: rendering stops there). `spare` gives a step whose buffers can be reused; `progress` gets the
/// simulated time rendered, seconds.
pub(super) fn render_steps(
    stage: &mut Stage,
    plan: &StepPlan<'_>,
    mut spare: impl FnMut() -> Step,
    mut send: impl FnMut(Step) -> bool,
    mut progress: impl FnMut(f64),
) -> Result<RenderTotals, GenerateError> {
    let cam = plan.camera;
    let identity = Isometry3::identity();
    let mut totals = RenderTotals::default();
    let (mut c0, mut c1, mut p0, mut p1) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // The step criterion uses a subsample of vertices; the changing region uses all of them.
    let n_points = stage.point_count();
    let stride = n_points.div_ceil(400).max(1);
    let mut full0 = !stage.project(0.0, &cam, 1, &mut p0);
    let mut next_tick = 0usize;
    let mut next_depth = 0usize;
    let mut t_us = 0.0f64;
    let mut dt_us = 200.0f64;
    let target_px = plan.max_step_px;
    while t_us < plan.t_end_us {
        // Adaptive step: no projected vertex moves more than max_step_px.
        let sub0 = !stage.project(t_us * 1e-6, &cam, stride, &mut c0);
        while next_tick < plan.tick_times.len() && plan.tick_times[next_tick] <= t_us {
            next_tick += 1;
        }
        // Never step over a tick: the sensor state is exact at every 120 Hz tick.
        let horizon = plan
            .tick_times
            .get(next_tick)
            .copied()
            .unwrap_or(f64::INFINITY)
            .min(plan.t_end_us);
        let mut t1 = (t_us + dt_us).min(horizon);
        for _ in 0..3 {
            let sub1 = !stage.project(t1 * 1e-6, &cam, stride, &mut c1);
            let moved = if sub0 || sub1 || c0.len() != c1.len() {
                f64::INFINITY
            } else {
                c0.iter()
                    .zip(&c1)
                    .map(|(a, b)| (a.0 - b.0).hypot(a.1 - b.1))
                    .fold(0.0, f64::max)
            };
            let step = t1 - t_us;
            if moved <= target_px * 1.05 || step <= 10.0 {
                break;
            }
            let shrink = if moved.is_finite() {
                (target_px / moved).clamp(0.1, 0.95)
            } else {
                0.5
            };
            t1 = t_us + (step * shrink).max(10.0);
        }
        let step_us = t1 - t_us;
        let full1 = !stage.project(t1 * 1e-6, &cam, 1, &mut p1);
        // The region that can change: the meshes' extent before and after, plus a margin for the blur.
        let (x0, y0, x1, y1) = if full0 || full1 {
            (0.0, 0.0, f64::from(cam.width), f64::from(cam.height))
        } else {
            let (mut lo_x, mut lo_y, mut hi_x, mut hi_y) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
            for &(u, v) in p0.iter().chain(&p1) {
                lo_x = lo_x.min(u);
                lo_y = lo_y.min(v);
                hi_x = hi_x.max(u);
                hi_y = hi_y.max(v);
            }
            let m = 3.0;
            (
                (lo_x - m).floor().max(0.0),
                (lo_y - m).floor().max(0.0),
                (hi_x + m).ceil().min(f64::from(cam.width)),
                (hi_y + m).ceil().min(f64::from(cam.height)),
            )
        };
        let mut step = spare();
        step.t0_us = t_us;
        step.t1_us = t1;
        step.region = None;
        step.depth.clear();
        if x1 > x0 && y1 > y0 {
            let (w, h) = ((x1 - x0) as u32, (y1 - y0) as u32);
            // Render one pixel more on each side (inside the image) for the optics blur.
            let (ex0, ey0) = ((x0 - 1.0).max(0.0), (y0 - 1.0).max(0.0));
            let (ex1, ey1) = (
                (x1 + 1.0).min(f64::from(cam.width)),
                (y1 + 1.0).min(f64::from(cam.height)),
            );
            let (ew, eh) = ((ex1 - ex0) as u32, (ey1 - ey0) as u32);
            let roi = Roi::new(ex0, ey0, f64::from(ew), f64::from(eh), ew, eh)
                .map_err(RenderError::from)?;
            stage.render(
                t1 * 1e-6,
                &identity,
                &cam,
                Some(&roi),
                &mut step.target,
                false,
            )?;
            step.region = Some(ChangingRegion {
                x0: x0 as u32,
                y0: y0 as u32,
                w,
                h,
                ex0: ex0 as u32,
                ey0: ey0 as u32,
                ew,
                eh,
            });
            totals.renders += 1;
            totals.region_px_sum += f64::from(w) * f64::from(h);
        }
        while next_depth < plan.depth_times.len() && (plan.depth_times[next_depth].1 as f64) < t1 {
            let (index, td) = plan.depth_times[next_depth];
            next_depth += 1;
            let (objects, background) = stage.instances(td as f64 * 1e-6, &plan.depth_frame, true);
            step.depth.push(DepthExposure {
                index,
                objects,
                background,
            });
        }
        if !send(step) {
            break;
        }
        progress(t1 * 1e-6);
        std::mem::swap(&mut p0, &mut p1);
        full0 = full1;
        // Next step starts from what worked, allowed to grow.
        dt_us = (step_us * 1.5).clamp(10.0, 4000.0);
        t_us = t1;
    }
    Ok(totals)
}

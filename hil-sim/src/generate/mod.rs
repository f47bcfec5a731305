//! Sequence generation: renders the scene at adaptively spaced times, turns intensity changes into events
//! (ESIM), renders depth at the 30 Hz exposures through the depth sensor model, and writes a recording
//! (`docs/recording-format.md`) with the trigger train, ground truth and the object model.

use crate::depth_sensor::DepthSensorModel;
use crate::esim::EventSimulator;
use crate::objects;
use crate::rig::SimRig;
use crate::rng::SeedRng;
use drivers::event::{CdEvent, TriggerEdge};
use drivers::recording::{RecordingMeta, RecordingWriter, TriggerSchedule};
use drivers::timeline::ideal_edges;
use nalgebra::Isometry3;
use std::path::Path;
use tracker::geometry::Roi;
use tracker::render::{
    BackgroundMesh, Lighting, MASK_EMPTY, RenderError, RenderTarget, Renderer, Scene,
};

mod config;
mod metadata;
mod optics;
mod stage;

use config::check;
pub use config::{Companion, GenerateConfig, GenerateError, GenerateReport, ObjectSource};
pub use optics::optics_log;
use stage::{Built, build, copy_user_obj};

/// The event sensor's log intensity over the whole image at `t_s`, exactly as the generator computes it
/// (render, optics blur, logarithm): for checking recordings against the model.
pub fn sensor_log_at(config: &GenerateConfig, t_s: f64) -> Result<Vec<f32>, GenerateError> {
    check(config)?;
    let cam = SimRig::default().event_camera;
    let mut built = build(config)?;
    let mut target = RenderTarget::new();
    built
        .stage
        .render(t_s, &Isometry3::identity(), &cam, None, &mut target, true)?;
    let mut log = Vec::new();
    optics_log(
        target.intensity(),
        cam.width,
        cam.height,
        (0, 0),
        (cam.width, cam.height),
        config.esim.log_eps,
        &mut log,
    );
    Ok(log)
}

/// Generates a recording into `out` (created; existing files are overwritten). `progress` gets the simulated
/// time done, seconds.
pub fn generate(
    config: &GenerateConfig,
    out: &Path,
    mut progress: impl FnMut(f64),
) -> Result<GenerateReport, GenerateError> {
    check(config)?;
    let rig = SimRig::default();
    let Built {
        mut stage,
        objects: scene_objects,
    } = build(config)?;
    let mut writer = RecordingWriter::create(
        out,
        rig.camera_rig(),
        &format!("hil-sim {}", env!("CARGO_PKG_VERSION")),
    )?;
    for o in &scene_objects {
        match (&o.source, &o.library_object) {
            (_, Some(lib)) => {
                objects::write_object(lib, &writer.models_dir())
                    .map_err(|e| GenerateError::Parameter(e.to_string()))?;
            }
            (ObjectSource::File(path), None) => {
                copy_user_obj(path, &writer.models_dir(), &o.name)?;
            }
            _ => {}
        }
    }

    let schedule = TriggerSchedule::default();
    let tl = schedule.timeline_config();
    let t_end_us = config.seconds * 1e6;
    let first_pulse_us = 500;
    let n_ticks = ((t_end_us - first_pulse_us as f64) / tl.period_us())
        .floor()
        .max(0.0) as u64
        + 1;
    let edges: Vec<TriggerEdge> = ideal_edges(&tl, first_pulse_us, n_ticks)
        .into_iter()
        .filter(|e| (e.t_us as f64) < t_end_us)
        .collect();
    let depth_times: Vec<(u64, i64)> = edges
        .iter()
        .filter(|e| e.rising)
        .enumerate()
        .filter(|(i, _)| (*i as u32).is_multiple_of(tl.ticks_per_depth))
        .enumerate()
        .map(|(n, (_, e))| (n as u64, e.t_us))
        .collect();

    let cam = rig.event_camera;
    let identity = Isometry3::identity();
    let depth_frame = rig.t_event_depth.inverse();
    let depth_model = DepthSensorModel {
        frame_drop_probability: config.depth_drop_probability,
        ..DepthSensorModel::d435i(rig.depth_camera.fx)
    };
    let mut depth_rng = SeedRng::new(config.seed ^ 0xDE97);

    // Initial state of the sensor.
    let mut target = RenderTarget::new();
    stage.render(0.0, &identity, &cam, None, &mut target, true)?;
    let eps = config.esim.log_eps;
    // The props never move and always lie behind the moving meshes: render them once.
    let mut background = RenderTarget::new();
    {
        let scene_props: Vec<BackgroundMesh> = stage
            .props
            .iter()
            .map(|(m, p)| BackgroundMesh { mesh: *m, pose: *p })
            .collect();
        let scene = Scene {
            lighting: Lighting::default(),
            ..Scene::objects(&[]).with_background(&scene_props)
        };
        stage.renderer.render(&scene, &cam, &mut background)?;
    }
    let background: Vec<f32> = background.intensity().to_vec();
    let mut composite: Vec<f32> = Vec::new();
    let mut log0 = Vec::new();
    optics_log(
        target.intensity(),
        cam.width,
        cam.height,
        (0, 0),
        (cam.width, cam.height),
        eps,
        &mut log0,
    );
    let mut sim = EventSimulator::new(cam.width, cam.height, config.esim, config.seed, &log0);

    let mut report = GenerateReport::default();
    let mut events: Vec<CdEvent> = Vec::new();
    let mut log: Vec<f32> = Vec::new();
    let mut depth_target = RenderTarget::new();
    let mut depth_mm: Vec<u16> = Vec::new();
    let (mut c0, mut c1, mut p0, mut p1) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // The step criterion uses a subsample of vertices; the changing region uses all of them.
    let n_points = stage.point_count();
    let stride = n_points.div_ceil(400).max(1);
    let mut full0 = !stage.project(0.0, &cam, 1, &mut p0);
    let tick_times: Vec<f64> = edges
        .iter()
        .filter(|e| e.rising)
        .map(|e| e.t_us as f64)
        .collect();
    let mut next_tick = 0usize;
    let mut next_edge = 0usize;
    let mut next_depth = 0usize;
    let mut t_us = 0.0f64;
    let mut dt_us = 200.0f64;
    let mut region_px_sum = 0.0f64;
    let target_px = config.max_step_px;
    while t_us < t_end_us {
        // Adaptive step: no projected vertex moves more than max_step_px.
        let sub0 = !stage.project(t_us * 1e-6, &cam, stride, &mut c0);
        while next_tick < tick_times.len() && tick_times[next_tick] <= t_us {
            next_tick += 1;
        }
        // Never step over a tick: the sensor state is exact at every 120 Hz tick.
        let horizon = tick_times
            .get(next_tick)
            .copied()
            .unwrap_or(f64::INFINITY)
            .min(t_end_us);
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
        let step = t1 - t_us;
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
        events.clear();
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
            stage.render(t1 * 1e-6, &identity, &cam, Some(&roi), &mut target, false)?;
            composite.clear();
            for (i, (&v, &m)) in target.intensity().iter().zip(target.mask()).enumerate() {
                let (x, y) = (
                    ex0 as usize + i % ew as usize,
                    ey0 as usize + i / ew as usize,
                );
                composite.push(if m == MASK_EMPTY {
                    background[y * cam.width as usize + x]
                } else {
                    v
                });
            }
            let inner = ((x0 - ex0) as u32, (y0 - ey0) as u32);
            optics_log(&composite, ew, eh, inner, (w, h), eps, &mut log);
            sim.update_region(t_us, t1, x0 as u32, y0 as u32, w, h, &log, &mut events);
            report.renders += 1;
            region_px_sum += f64::from(w) * f64::from(h);
        }
        sim.noise(t_us, t1, &mut events);
        events.sort_unstable_by_key(|e| (e.t_us, e.y, e.polarity, e.x));
        let edge_start = next_edge;
        while next_edge < edges.len() && (edges[next_edge].t_us as f64) < t1.floor() {
            next_edge += 1;
        }
        writer.write_events(&events, &edges[edge_start..next_edge])?;
        report.trigger_edges += (next_edge - edge_start) as u64;

        while next_depth < depth_times.len() && (depth_times[next_depth].1 as f64) < t1 {
            let (n, td) = depth_times[next_depth];
            next_depth += 1;
            if depth_model.drops_frame(&mut depth_rng) {
                report.depth_frames_dropped += 1;
                continue;
            }
            stage.render(
                td as f64 * 1e-6,
                &depth_frame,
                &rig.depth_camera,
                None,
                &mut depth_target,
                true,
            )?;
            depth_model.measure(
                depth_target.depth(),
                depth_target.width(),
                depth_target.height(),
                &mut depth_rng,
                &mut depth_mm,
            );
            writer.write_depth_mm(n, &depth_mm)?;
            report.depth_frames += 1;
        }
        progress(t1 * 1e-6);
        std::mem::swap(&mut p0, &mut p1);
        full0 = full1;
        // Next step starts from what worked, allowed to grow.
        dt_us = (step * 1.5).clamp(10.0, 4000.0);
        t_us = t1;
    }
    // Any trigger edge left (at the very end).
    if next_edge < edges.len() {
        writer.write_events(&[], &edges[next_edge..])?;
        report.trigger_edges += (edges.len() - next_edge) as u64;
    }
    report.esim = sim.stats();
    report.mean_region_px = if report.renders > 0 {
        region_px_sum / report.renders as f64
    } else {
        0.0
    };

    let gt = metadata::ground_truth(&stage.objects, &scene_objects, &edges, t_end_us);
    report.ground_truth_rows = gt.len() as u64;
    let parameters = metadata::parameters(config, &scene_objects, sim.contrast(), &report);
    let meta = RecordingMeta {
        generator: format!("hil-sim {}", env!("CARGO_PKG_VERSION")),
        trigger: schedule,
        parameters,
    };
    let infos: Vec<_> = scene_objects.into_iter().map(|o| o.info).collect();
    writer.finish(&meta, &infos, Some(&gt))?;
    Ok(report)
}

//! Sequence generation: renders the scene at adaptively spaced times, turns intensity changes into events
//! (ESIM), renders depth at the 30 Hz exposures through the depth sensor model, and writes a recording
//! (`docs/recording-format.md`) with the trigger train, ground truth and the object model.

use crate::depth_sensor::DepthSensorModel;
use crate::esim::EventSimulator;
use crate::objects;
use crate::rig::SimRig;
use crate::rng::SeedRng;
use drivers::event::TriggerEdge;
use drivers::recording::{RecordingMeta, RecordingWriter, TriggerSchedule};
use drivers::timeline::ideal_edges;
use nalgebra::Isometry3;
use scene::render::{BackgroundMesh, Lighting, RenderTarget, Renderer, Scene};
use std::path::Path;

mod config;
mod metadata;
mod optics;
mod sensor;
mod stage;
mod steps;

use config::check;
pub use config::{Companion, GenerateConfig, GenerateError, GenerateReport, ObjectSource};
pub use optics::optics_log;
use sensor::{DepthCamera, SensorSide, Step};
use stage::{Built, build, copy_user_obj};
use std::sync::mpsc;
use steps::{StepPlan, render_steps};

/// Steps queued between rendering and the sensor at most (each holds one rendered region); with the step each
/// half works on, rendering runs at most 6 steps ahead of the sensor.
const STEPS_IN_FLIGHT: usize = 4;

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
    let writer = RecordingWriter::create(
        out,
        rig.camera_rig(),
        &format!("hil-sim {}", env!("CARGO_PKG_VERSION")),
    )?;
    for o in &scene_objects {
        match (&o.source, &o.generated) {
            (_, Some(model)) => {
                objects::write_object(model.as_ref(), &writer.models_dir())
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
    let depth_model = DepthSensorModel {
        frame_drop_probability: config.depth_drop_probability,
        ..DepthSensorModel::d435i(rig.depth_camera.fx)
    };
    let depth_rng = SeedRng::new(config.seed ^ 0xDE97);

    // Initial state of the sensor.
    let mut target = RenderTarget::new();
    stage.render(0.0, &Isometry3::identity(), &cam, None, &mut target, true)?;
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
    let sim = EventSimulator::new(cam.width, cam.height, config.esim, config.seed, &log0);
    let depth_renderer = stage.renderer.fork().ok_or_else(|| {
        GenerateError::Thread("the renderer cannot make a second one for the depth camera".into())
    })?;
    let depth = DepthCamera::new(rig.depth_camera, depth_model, depth_rng, depth_renderer);
    let sensor = SensorSide::new(sim, writer, depth, &background, cam.width, eps, &edges);
    let tick_times: Vec<f64> = edges
        .iter()
        .filter(|e| e.rising)
        .map(|e| e.t_us as f64)
        .collect();
    let plan = StepPlan {
        camera: cam,
        depth_frame: rig.t_event_depth.inverse(),
        tick_times: &tick_times,
        depth_times: &depth_times,
        t_end_us,
        max_step_px: config.max_step_px,
    };

    // Rendering runs on this thread, the sensor (events, writing) on its own a few steps behind; steps go back
    // and forth so that their buffers are reused.
    let (step_tx, step_rx) = mpsc::sync_channel::<Step>(STEPS_IN_FLIGHT);
    let (spent_tx, spent_rx) = mpsc::channel::<Step>();
    let (rendered, sensor) = std::thread::scope(|scope| {
        let sensor = std::thread::Builder::new()
            .name("hil-sim-sensor".into())
            .spawn_scoped(scope, move || sensor.run(step_rx, spent_tx))
            .map_err(|e| GenerateError::Thread(format!("cannot start the sensor thread: {e}")))?;
        let rendered = render_steps(
            &mut stage,
            &plan,
            || spent_rx.try_recv().unwrap_or_default(),
            |step| step_tx.send(step).is_ok(),
            &mut progress,
        );
        drop(step_tx);
        let sensor = sensor
            .join()
            .map_err(|_| GenerateError::Thread("the sensor thread panicked".into()));
        Ok::<_, GenerateError>((rendered, sensor))
    })?;
    // A rendering error stops the sensor early: report it rather than what the sensor made of the stop.
    let rendered = rendered?;
    let written = sensor??.finish()?;
    let gt = metadata::ground_truth(&stage.objects, &scene_objects, &edges, t_end_us);
    let report = GenerateReport {
        renders: rendered.renders,
        mean_region_px: if rendered.renders > 0 {
            rendered.region_px_sum / rendered.renders as f64
        } else {
            0.0
        },
        esim: written.sim.stats(),
        trigger_edges: written.trigger_edges,
        depth_frames: written.depth_frames,
        depth_frames_dropped: written.depth_frames_dropped,
        ground_truth_rows: gt.len() as u64,
    };
    let parameters = metadata::parameters(config, &scene_objects, written.sim.contrast(), &report);
    let meta = RecordingMeta {
        generator: format!("hil-sim {}", env!("CARGO_PKG_VERSION")),
        trigger: schedule,
        parameters,
    };
    let infos: Vec<_> = scene_objects.into_iter().map(|o| o.info).collect();
    written.writer.finish(&meta, &infos, Some(&gt))?;
    Ok(report)
}

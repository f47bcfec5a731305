//! Sequence generation: renders the scene at adaptively spaced times, turns intensity changes into events
//! (ESIM), renders depth at the 30 Hz exposures through the depth sensor model, and writes a recording
//! (`docs/recording-format.md`) with the trigger train, ground truth and the object model.

use crate::depth_sensor::DepthSensorModel;
use crate::esim::{EsimConfig, EsimStats, EventSimulator};
use crate::motion::{MotionProfile, SpeedLevel};
use crate::objects::{self, ObjectKind};
use crate::rig::SimRig;
use crate::rng::SeedRng;
use drivers::event::{CdEvent, TriggerEdge};
use drivers::recording::{
    PoseSample, RecordingError, RecordingMeta, RecordingWriter, TriggerSchedule,
};
use drivers::timeline::ideal_edges;
use nalgebra::Isometry3;
use serde_json::json;
use std::path::{Path, PathBuf};
use tracker::geometry::Roi;
use tracker::render::{
    BackgroundMesh, Lighting, MASK_EMPTY, RenderError, RenderTarget, Renderer, Scene,
};

/// Which object to put in the scene.
#[derive(Debug, Clone, PartialEq)]
pub enum ObjectSource {
    /// A procedural library object.
    Library(ObjectKind),
    /// A user OBJ (metres), copied into the recording with its MTL and textures.
    File(PathBuf),
}

/// A further object in the scene, moving on its own trajectory (with its own hand) beside the first.
#[derive(Debug, Clone, PartialEq)]
pub struct Companion {
    /// The object.
    pub object: ObjectSource,
    /// Its motion profile.
    pub motion: MotionProfile,
    /// Its speed level.
    pub speed: SpeedLevel,
    /// Where its trajectory is centred relative to the first object's, metres, camera frame (negative z:
    /// nearer the camera, so it passes in front of the first object).
    pub offset_m: [f64; 3],
}

impl Companion {
    /// Parses a command-line companion `NAME[:MOTION[:SPEED[:X,Y,Z]]]` (library name or `.obj` path; offset in
    /// metres). Motion and speed default to `motion` and `speed`; the offset to [`Self::default_offset`]`(k)`.
    pub fn parse(
        spec: &str,
        k: usize,
        motion: MotionProfile,
        speed: SpeedLevel,
    ) -> Result<Self, String> {
        let mut parts = spec.split(':');
        let name = parts.next().unwrap_or_default().trim();
        let object = match ObjectKind::from_name(name) {
            Some(kind) => ObjectSource::Library(kind),
            None if name.ends_with(".obj") => ObjectSource::File(PathBuf::from(name)),
            None => {
                return Err(format!(
                    "`{spec}`: unknown object `{name}` (a library name or a path to an .obj file)"
                ));
            }
        };
        let motion = match parts.next() {
            Some(m) => m.parse().map_err(|e| format!("`{spec}`: {e}"))?,
            None => motion,
        };
        let speed = match parts.next() {
            Some(v) => v.parse().map_err(|e| format!("`{spec}`: {e}"))?,
            None => speed,
        };
        let offset_m = match parts.next() {
            Some(o) => {
                let v: Vec<f64> = o
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .map_err(|e| format!("`{spec}`: offset `{o}`: {e}"))?;
                <[f64; 3]>::try_from(v)
                    .map_err(|_| format!("`{spec}`: offset `{o}` must be X,Y,Z in metres"))?
            }
            None => Self::default_offset(k),
        };
        if let Some(extra) = parts.next() {
            return Err(format!(
                "`{spec}`: unexpected `:{extra}` (NAME[:MOTION[:SPEED[:X,Y,Z]]])"
            ));
        }
        Ok(Self {
            object,
            motion,
            speed,
            offset_m,
        })
    }

    /// The offset of the `k`-th companion (from 1) when none is given: 15 cm nearer the camera per companion,
    /// so that each passes in front of the objects behind it as they move.
    pub fn default_offset(k: usize) -> [f64; 3] {
        [0.0, 0.0, -0.15 * k as f64]
    }
}

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct GenerateConfig {
    /// The tracked object.
    pub object: ObjectSource,
    /// Further objects (each tracked too, and in the ground truth), empty by default.
    pub companions: Vec<Companion>,
    /// Motion profile.
    pub motion: MotionProfile,
    /// Speed level.
    pub speed: SpeedLevel,
    /// Length, seconds.
    pub seconds: f64,
    /// Seed of everything random (trajectory, textures, thresholds, noise).
    pub seed: u64,
    /// Event camera model.
    pub esim: EsimConfig,
    /// Probability that a depth frame is dropped.
    pub depth_drop_probability: f64,
    /// Whether hand-like occluders grip the object.
    pub hands: bool,
    /// Largest image motion of any object point between two renders, pixels (ESIM's adaptive sampling).
    pub max_step_px: f64,
}

impl GenerateConfig {
    /// A configuration with the simulator's defaults.
    pub fn new(
        object: ObjectSource,
        motion: MotionProfile,
        speed: SpeedLevel,
        seconds: f64,
        seed: u64,
    ) -> Self {
        Self {
            object,
            companions: Vec::new(),
            motion,
            speed,
            seconds,
            seed,
            esim: EsimConfig::default(),
            depth_drop_probability: 0.0,
            hands: true,
            max_step_px: 0.5,
        }
    }
}

/// What a generation produced.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GenerateReport {
    /// Renders of the event camera's changing region.
    pub renders: u64,
    /// Mean rendered region, pixels.
    pub mean_region_px: f64,
    /// Event counters.
    pub esim: EsimStats,
    /// Trigger edges written.
    pub trigger_edges: u64,
    /// Depth frames written.
    pub depth_frames: u64,
    /// Depth frames dropped on purpose (the sensor model's frame drops).
    pub depth_frames_dropped: u64,
    /// Ground-truth rows written.
    pub ground_truth_rows: u64,
}

/// Why generation failed.
#[derive(Debug, thiserror::Error)]
pub enum GenerateError {
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    Parameter(String),
    /// The object or a prop could not be built or loaded.
    #[error(transparent)]
    Mesh(#[from] tracker::mesh::MeshError),
    /// Writing the recording failed.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// The renderer refused the scene.
    #[error("rendering failed: {0}")]
    Render(#[from] RenderError),
    /// Copying a user mesh failed.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        error: std::io::Error,
    },
}

mod optics;
mod stage;

pub use optics::optics_log;
use stage::{Built, build, copy_user_obj};

fn check(config: &GenerateConfig) -> Result<(), GenerateError> {
    let bad = |s: &str| Err(GenerateError::Parameter(s.to_string()));
    if !(config.seconds.is_finite() && config.seconds > 0.0 && config.seconds <= 600.0) {
        return bad("seconds must be in (0, 600]");
    }
    if !(config.max_step_px.is_finite() && config.max_step_px > 0.01 && config.max_step_px <= 5.0) {
        return bad("max step must be in (0.01, 5] pixels");
    }
    if !(0.0..=1.0).contains(&config.depth_drop_probability) {
        return bad("depth frame drop probability must be in [0, 1]");
    }
    for (k, c) in config.companions.iter().enumerate() {
        let z = super::motion::WORKING_DISTANCE_M + c.offset_m[2];
        if !(c.offset_m.iter().all(|v| v.is_finite() && v.abs() <= 1.0) && z >= 0.25) {
            return Err(GenerateError::Parameter(format!(
                "companion {} offset {:?} m: each coordinate must be within 1 m and the object at least 0.25 m \
                 from the camera",
                k + 1,
                c.offset_m
            )));
        }
    }
    let e = &config.esim;
    if e.contrast
        .is_some_and(|c| !(c.is_finite() && c > 0.01 && c < 2.0))
        || !(e.contrast_spread.is_finite() && e.contrast_spread >= 0.0)
        || !(e.refractory_us.is_finite() && e.refractory_us >= 0.0)
        || !(e.noise_rate_hz.is_finite() && (0.0..=100.0).contains(&e.noise_rate_hz))
        || !(e.log_eps.is_finite() && e.log_eps > 0.0)
    {
        return bad(
            "event camera parameters out of range (contrast in (0.01, 2), spread >= 0, refractory >= 0, noise in [0, 100] Hz, log eps > 0)",
        );
    }
    Ok(())
}

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

    // Ground truth at 1 kHz plus every tick.
    let mut times: Vec<i64> = (0..)
        .map(|k| k * 1000)
        .take_while(|&t| (t as f64) < t_end_us)
        .collect();
    times.extend(edges.iter().filter(|e| e.rising).map(|e| e.t_us));
    times.sort_unstable();
    times.dedup();
    let gt: Vec<PoseSample> = times
        .iter()
        .flat_map(|&t| {
            stage.objects.iter().zip(&scene_objects).map(move |(o, b)| {
                let p = o.pose(t as f64 * 1e-6);
                let q = p.rotation.into_inner();
                PoseSample {
                    t_us: t,
                    object: b.name.clone(),
                    translation: [p.translation.x, p.translation.y, p.translation.z],
                    rotation_xyzw: [q.i, q.j, q.k, q.w],
                }
            })
        })
        .collect();
    report.ground_truth_rows = gt.len() as u64;
    let mut parameters = serde_json::Map::new();
    for (k, v) in [
        ("object", json!(scene_objects[0].name)),
        ("motion", json!(config.motion.name())),
        ("speed", json!(config.speed.name())),
        ("seconds", json!(config.seconds)),
        ("seed", json!(config.seed)),
        ("contrast_threshold", json!(sim.contrast())),
        ("contrast_spread", json!(config.esim.contrast_spread)),
        ("refractory_us", json!(config.esim.refractory_us)),
        ("noise_rate_hz", json!(config.esim.noise_rate_hz)),
        ("hands", json!(config.hands)),
        ("max_step_px", json!(config.max_step_px)),
        ("renders", json!(report.renders)),
        ("signal_events", json!(report.esim.signal_events)),
        ("noise_events", json!(report.esim.noise_events)),
        ("refractory_dropped", json!(report.esim.refractory_dropped)),
        ("depth_frames_dropped", json!(report.depth_frames_dropped)),
    ] {
        parameters.insert(k.to_string(), v);
    }
    // Only recordings with companions carry them (a single-object recording's metadata is unchanged).
    if !config.companions.is_empty() {
        let companions: Vec<_> = config
            .companions
            .iter()
            .zip(&scene_objects[1..])
            .map(|(c, b)| {
                json!({"object": b.name, "motion": c.motion.name(), "speed": c.speed.name(),
                       "offset_m": c.offset_m})
            })
            .collect();
        parameters.insert("companions".into(), json!(companions));
    }
    let meta = RecordingMeta {
        generator: format!("hil-sim {}", env!("CARGO_PKG_VERSION")),
        trigger: schedule,
        parameters,
    };
    let infos: Vec<_> = scene_objects.into_iter().map(|o| o.info).collect();
    writer.finish(&meta, &infos, Some(&gt))?;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn companion_specs_parse_with_defaults_and_name_what_is_wrong() {
        let (m, s) = (MotionProfile::Shake, SpeedLevel::Slow);
        let c = Companion::parse("can", 2, m, s).unwrap();
        assert_eq!(c.object, ObjectSource::Library(ObjectKind::Can));
        assert_eq!((c.motion, c.speed), (m, s));
        assert_eq!(c.offset_m, [0.0, 0.0, -0.3]);
        let c = Companion::parse("bowl:hand-switch:fast:0.05,-0.02,-0.1", 1, m, s).unwrap();
        assert_eq!(c.object, ObjectSource::Library(ObjectKind::Bowl));
        assert_eq!(
            (c.motion, c.speed),
            (MotionProfile::HandSwitch, SpeedLevel::Fast)
        );
        assert_eq!(c.offset_m, [0.05, -0.02, -0.1]);
        let c = Companion::parse("parts/gear.obj:rotation", 1, m, s).unwrap();
        assert_eq!(c.object, ObjectSource::File("parts/gear.obj".into()));
        assert_eq!(c.motion, MotionProfile::Rotation);
        for (spec, needle) in [
            ("teapot", "unknown object `teapot`"),
            ("can:wobble", "unknown motion profile `wobble`"),
            ("can:shake:warp", "unknown speed level `warp`"),
            ("can:shake:slow:1,2", "must be X,Y,Z"),
            ("can:shake:slow:1,x,2", "offset `1,x,2`"),
            ("can:shake:slow:0,0,0:more", "unexpected `:more`"),
        ] {
            let e = Companion::parse(spec, 1, m, s).unwrap_err();
            assert!(e.contains(needle) && e.contains(spec), "{spec}: {e}");
        }
    }
}

//! Building the pieces of a run from a configuration: the scene (cameras, objects, first poses), the tracker
//! ([`build_tracker`]), the source and the sinks.

use super::config::validate_live;
use super::config::{Config, ObjectConfig, SourceKind};
use super::error::RuntimeError;
use super::latency_log::LatencyLog;
use super::live::{Backoff, LiveEvk4Source};
use super::replay::ReplaySource;
use super::source::{Source, SourceError};
use crate::publish::PoseSink;
use crate::publish::csv::CsvPoseSink;
use drivers::event::{CdEvent, EventSink, TriggerEdge};
use drivers::recording::Recording;
use drivers::timeline::TimelineConfig;
use scene::mesh::{MeshLoadOptions, load_obj};
use scene::render::{RendererKind, create_renderer};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

pub use super::scene::{SceneObject, TrackerScene, pose_of};
use tracker::recording::{PoseTrack, ground_truth_objects, symmetries_of, tracking_rig};
use tracker::track::{
    EventTrack6d, HoldPoseTracker, PoseTracker, TrackedObject, TrackerConfig, TrackingMethod,
};

/// Tracker methods [`build_tracker`] knows.
pub const METHODS: &[&str] = &["eventtrack6d", "depth30", "events-only", "static"];

/// Builds the tracker named `method` for `scene`, triggered on `timeline`.
///
/// `eventtrack6d` is the tracker; `depth30` and `events-only` its baselines; `static` holds every object's first
/// pose (the plumbing test and benchmark floor).
pub fn build_tracker(
    method: &str,
    renderer: RendererKind,
    parameters: &TrackerConfig,
    scene: &TrackerScene,
    timeline: &TimelineConfig,
) -> Result<Box<dyn PoseTracker>, RuntimeError> {
    match method {
        "static" => Ok(Box::new(HoldPoseTracker::new(
            scene
                .objects
                .iter()
                .map(|o| (o.name.clone(), o.first_pose.1))
                .collect(),
        ))),
        name if TrackingMethod::from_name(name).is_some() => {
            let method = TrackingMethod::from_name(name).ok_or_else(|| {
                RuntimeError::Tracker(format!("tracker.method `{name}` is not known"))
            })?;
            Ok(Box::new(build_eventtrack6d(
                method, renderer, parameters, scene, timeline,
            )?))
        }
        other => Err(RuntimeError::Tracker(format!(
            "tracker.method `{other}` is not known (available: {})",
            METHODS.join(", ")
        ))),
    }
}

/// The EventTrack6D tracker (or one of its baselines) for `scene`, on `parameters` with the method's preset on
/// top, rendering with `renderer`, triggered on `timeline`.
fn build_eventtrack6d(
    method: TrackingMethod,
    renderer: RendererKind,
    parameters: &TrackerConfig,
    scene: &TrackerScene,
    timeline: &TimelineConfig,
) -> Result<EventTrack6d, RuntimeError> {
    let rig =
        tracking_rig(&scene.rig, timeline).map_err(|e| RuntimeError::Tracker(e.to_string()))?;
    let mut objects = Vec::with_capacity(scene.objects.len());
    for o in &scene.objects {
        let loaded = load_obj(&o.mesh, &MeshLoadOptions::default())
            .map_err(|e| RuntimeError::Tracker(format!("object {}: {e}", o.name)))?;
        let mesh = Arc::new(loaded.mesh);
        objects.push(TrackedObject {
            name: o.name.clone(),
            diameter: o.info.as_ref().map_or(mesh.diameter(), |i| i.diameter_m),
            mesh,
            first_t_us: o.first_pose.0,
            first_pose: o.first_pose.1,
            symmetries: match &o.info {
                Some(info) => {
                    symmetries_of(info).map_err(|e| RuntimeError::Tracker(e.to_string()))?
                }
                None => Vec::new(),
            },
        });
    }
    let config = method.configure(parameters);
    let renderer = create_renderer(renderer)
        .map_err(|e| RuntimeError::Tracker(format!("tracker.renderer: {e}")))?;
    EventTrack6d::new(config, rig, objects, renderer)
        .map_err(|e| RuntimeError::Tracker(e.to_string()))
}

/// Finds the first rising trigger edge on `channel` (the first tick) by decoding `events.raw` only that far.
fn first_tick_us(rec: &Recording, channel: u8) -> Result<Option<i64>, RuntimeError> {
    struct First {
        channel: u8,
        t: Option<i64>,
    }
    impl EventSink for First {
        fn cd(&mut self, _: CdEvent) {}
        fn cd_vector(&mut self, _: i64, _: u16, _: u16, _: u32, _: bool) {}
        fn trigger(&mut self, e: TriggerEdge) {
            if self.t.is_none() && e.rising && e.channel == self.channel {
                self.t = Some(e.t_us);
            }
        }
    }
    let mut reader = rec.events()?;
    let mut sink = First { channel, t: None };
    while sink.t.is_none() {
        let more = reader
            .read_chunk(&mut sink)
            .map_err(|e| RuntimeError::Source(SourceError::Input(e.to_string())))?;
        if !more {
            break;
        }
    }
    Ok(sink.t)
}

/// The scene of a recording: the configured objects (with their first poses), else every object with ground
/// truth, initialised from the ground truth at the first tick (the benchmark's protocol).
pub fn recording_scene(
    rec: &Recording,
    objects: &[ObjectConfig],
) -> Result<TrackerScene, RuntimeError> {
    let schedule = rec.meta.trigger;
    let t0 = first_tick_us(rec, schedule.channel)?.ok_or_else(|| {
        RuntimeError::Source(SourceError::Input(format!(
            "{}: events.raw has no trigger edge on channel {}: no tick to start from",
            rec.dir().display(),
            schedule.channel
        )))
    })?;
    let objs = if !objects.is_empty() {
        objects
            .iter()
            .map(|o| SceneObject {
                name: o.name.clone(),
                mesh: o.mesh.clone(),
                info: rec.model(&o.name).cloned(),
                first_pose: (t0, pose_of(o)),
            })
            .collect()
    } else {
        let names = ground_truth_objects(rec).map_err(|e| {
            RuntimeError::Tracker(format!(
                "{e}; give the objects and their first poses as [[objects]] in the configuration"
            ))
        })?;
        let gt = rec.ground_truth.as_deref().unwrap_or(&[]);
        let mut out = Vec::new();
        for name in names {
            let track = PoseTrack::from_samples(gt, &name);
            let pose = track
                .interpolated_at(t0)
                .or_else(|| track.first().map(|f| f.1))
                .ok_or_else(|| {
                    RuntimeError::Tracker(format!("object `{name}` has no ground-truth pose"))
                })?;
            out.push(SceneObject {
                mesh: rec.mesh_path(&name),
                info: rec.model(&name).cloned(),
                name,
                first_pose: (t0, pose),
            });
        }
        out
    };
    Ok(TrackerScene {
        rig: rec.rig.clone(),
        objects: objs,
        recording: Some(rec.clone()),
    })
}

/// The source of a configuration, the scene it shows and its trigger schedule.
pub fn build_source(
    config: &Config,
) -> Result<(Box<dyn Source>, TrackerScene, TimelineConfig), RuntimeError> {
    match config.source.kind {
        SourceKind::Demo => Err(RuntimeError::DemoNotResolved),
        SourceKind::Replay => {
            let Some(replay) = &config.replay else {
                return Err(RuntimeError::Tracker(
                    "source.kind = \"replay\" needs a [replay] table".into(),
                ));
            };
            let rec = Recording::open(&replay.recording)?;
            let scene = recording_scene(&rec, &config.objects)?;
            let timeline = rec.meta.trigger.timeline_config();
            let source = ReplaySource::new(
                rec,
                config.source.pace,
                config.queue.batch_events,
                config.queue.batch_us,
                Duration::from_millis(config.source.start_delay_ms),
            )
            .with_depth_latency((config.source.depth_latency_ms * 1e3).round() as i64)
            .with_depth_jitter((config.source.depth_latency_jitter_ms * 1e3).round() as i64)
            .with_max_seconds(config.source.max_seconds);
            Ok((Box::new(source), scene, timeline))
        }
        SourceKind::Live => build_live_source(config),
        SourceKind::Ros2 => super::ros2::connect(config),
    }
}

/// The live source of a configuration: the EVK4, with the depth of a recording until a live depth camera is
/// there.
fn build_live_source(
    config: &Config,
) -> Result<(Box<dyn Source>, TrackerScene, TimelineConfig), RuntimeError> {
    let Some(live) = &config.live else {
        return Err(RuntimeError::Tracker(
            "source.kind = \"live\" needs a [live] table".into(),
        ));
    };
    let depth_dir = validate_live::depth_recording(live, "run")
        .map_err(|m| RuntimeError::Source(SourceError::NotImplemented(m)))?;
    let rec = Recording::open(depth_dir)?;
    let scene = recording_scene(&rec, &config.objects)?;
    let mut schedule = rec.meta.trigger;
    schedule.channel = live.trigger_channel;
    let settings = validate_live::sensor_settings(live).map_err(RuntimeError::Tracker)?;
    let stream = validate_live::stream_config(live);
    let source = LiveEvk4Source::new(
        (!live.event_serial.is_empty()).then(|| live.event_serial.clone()),
        settings,
        stream,
        Backoff {
            first: Duration::from_millis(live.reconnect_ms),
            max: Duration::from_millis(live.reconnect_max_ms),
        },
        Some(rec),
        schedule,
        (config.queue.batch_events, config.queue.batch_us),
    )
    .with_max_seconds(config.source.max_seconds);
    Ok((Box::new(source), scene, schedule.timeline_config()))
}

/// Paths of the file outputs of a run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OutputPaths {
    /// The pose CSV, when on.
    pub csv: Option<PathBuf>,
    /// The candump log, when on.
    pub candump: Option<PathBuf>,
    /// The per-tick latency log, when on.
    pub latency_log: Option<PathBuf>,
}

/// The file sinks of a configuration (the network sinks are added by [`super::sinks`]).
pub fn build_file_sinks(
    config: &Config,
) -> Result<(Vec<Box<dyn PoseSink>>, OutputPaths), RuntimeError> {
    let mut sinks: Vec<Box<dyn PoseSink>> = Vec::new();
    let mut paths = OutputPaths::default();
    if config.sinks.csv
        || (config.can.enabled && config.can.candump_log.is_some())
        || config.output.latency_log.is_some()
    {
        std::fs::create_dir_all(&config.output.dir).map_err(|e| {
            RuntimeError::Output(format!(
                "output.dir {}: cannot create: {e}",
                config.output.dir.display()
            ))
        })?;
    }
    if config.sinks.csv {
        let path = config.output.dir.join("poses.csv");
        sinks.push(Box::new(CsvPoseSink::create(&path)?));
        paths.csv = Some(path);
    }
    Ok((sinks, paths))
}

/// The per-tick latency log of a configuration, when `[output] latency_log` is set (after
/// [`build_file_sinks`], which creates the output directory).
pub fn build_latency_log(config: &Config) -> Result<Option<LatencyLog>, RuntimeError> {
    config
        .output
        .latency_log
        .as_ref()
        .map(|p| LatencyLog::create(&config.output.dir.join(p)))
        .transpose()
}

//! The real-time process (DESIGN section 2, `runtime`): sources -> bounded queue -> tracker thread (trigger
//! timeline, tracker, sinks) with health reporting.
//!
//! - tokio runs the process: the source on a blocking task, the status timer, progress reports and Ctrl-C.
//! - The tracker runs on its own OS thread ([`worker`]), fed by the bounded [`queue`] (overload: drop the oldest
//!   event batch, count every dropped event, never block the tracker; trigger edges and depth frames are never
//!   dropped).
//! - Ticks come from trigger edges through `drivers::timeline::TriggerTimeline`; each tick remembers the instant
//!   its edge was decoded, and latency is measured from there to after each sink's publish (and after all sinks).
//!
//! Entry point: [`run`] (a [`Config`] and [`Hooks`] in, a [`Summary`] out).

mod assembly;
pub mod config;
pub mod control;
pub mod depth_arrival;
mod error;
pub mod health;
pub mod latency_log;
pub mod live;
mod live_clock;
mod priority;
pub mod queue;
pub mod recorder;
pub mod replay;
mod revision;
pub mod ros2;
pub mod scene;
pub mod setup;
pub mod sinks;
pub mod source;
pub mod summary;
pub mod worker;

pub use config::{Config, ConfigError, Pace, SourceKind};
pub use error::RuntimeError;
pub use health::{Health, LatencyHistogram, LatencySummary};
pub use latency_log::{LATENCY_LOG_HEADER, LatencyLog, TickTiming};
pub use setup::{OutputPaths, SceneObject, TrackerScene, build_tracker};
pub use sinks::StatusPut;
pub use source::{Source, SourceError, SourceOutput, SourceStats, StopFlag, UsbStats};
pub use summary::{SinkSummary, Summary};

use queue::{Ingest, IngestQueue};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use worker::Worker;

/// A progress callback: gets the current health.
pub type ProgressFn = Box<dyn FnMut(&Health) + Send>;

/// Caller hooks of a run.
pub struct Hooks {
    /// Called every `progress_period` with the current health (on a runtime task; keep it short).
    pub progress: Option<ProgressFn>,
    /// Period of `progress`.
    pub progress_period: Duration,
    /// Called once the sinks are up, before the source starts (e.g. to connect a subscriber).
    pub before_start: Option<Box<dyn FnOnce() + Send>>,
    /// Set to stop the run early (also set by Ctrl-C when `ctrl_c` is on).
    pub stop: StopFlag,
    /// Stop cleanly on Ctrl-C (SIGINT).
    pub ctrl_c: bool,
}

impl Default for Hooks {
    fn default() -> Self {
        Self {
            progress: None,
            progress_period: Duration::from_millis(200),
            before_start: None,
            stop: StopFlag::new(),
            ctrl_c: false,
        }
    }
}

/// Runs a configuration to the end of its source (or until stopped) and returns the summary. Builds its own
/// tokio runtime; call it from a plain thread (not from inside an async task).
pub fn run(config: &Config, hooks: Hooks) -> Result<Summary, RuntimeError> {
    let (source, scene, timeline) = setup::build_source(config)?;
    let tracker = build_tracker(
        &config.tracker.method,
        config.tracker.renderer,
        &config.tracker.parameters,
        &scene,
        &timeline,
    )?;
    let objects = tracker.objects().to_vec();
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .thread_name("eventtrack6d-rt")
        .enable_all()
        .build()
        .map_err(|e| RuntimeError::Thread(format!("cannot start the tokio runtime: {e}")))?;
    let (mut sinks, outputs) = setup::build_file_sinks(config)?;
    let latency_log = setup::build_latency_log(config)?;
    // zenoh first: it is what robots subscribe to, so it gets the earliest slot of every tick.
    let mut network = sinks::build_network_sinks(config, &scene, &outputs, rt.handle())?;
    let control = network.control.take();
    let outputs = OutputPaths {
        candump: network.candump.clone().or(outputs.candump),
        latency_log: config
            .output
            .latency_log
            .as_ref()
            .map(|p| config.output.dir.join(p)),
        ..outputs
    };
    let mut all: Vec<Box<dyn crate::publish::PoseSink>> = network.sinks;
    all.append(&mut sinks);
    let sinks = all;
    let sink_names: Vec<String> = sinks.iter().map(|s| s.name().to_string()).collect();
    let mut health = Health::new(&objects, &sink_names);
    if let Some(device) = tracker.render_device() {
        if let Some(warning) = device.warning() {
            eprintln!("warning: {warning}");
        }
        health.renderer = Some(device.to_string());
    }
    let health = Arc::new(Mutex::new(health));
    let queue = Arc::new(IngestQueue::new(
        config.queue.event_batches,
        config.queue.batch_events,
    ));
    let parts = Parts {
        source,
        tracker,
        sinks,
        status_put: network.status,
        timeline,
        health,
        queue,
        objects,
        outputs,
        control,
        status_period: Duration::from_millis(config.status.period_ms),
        // A live camera's overload buffer is the transfer ring at the USB side (dropping, counted): the
        // ingest queue waits for room behind it.
        wait_for_room: config.source.pace == Pace::Fast
            || matches!(config.source.kind, SourceKind::Live | SourceKind::Ros2),
        rt_priority: config.tracker.realtime_priority,
        latency_log,
        // Holding a frame compares the stream's clock with the wall clock: only where they run together.
        defer_depth: config.tracker.defer_late_depth
            && (matches!(config.source.kind, SourceKind::Live | SourceKind::Ros2)
                || config.source.pace == Pace::Realtime),
        // A frame within half a tick of its own tick is used whatever its age.
        depth_age_limit_ms: (config.tracker.method != "static").then(|| {
            config
                .tracker
                .parameters
                .late_depth
                .max_depth_age_ms
                .max(4.2)
        }),
    };
    let result = rt.block_on(run_parts(parts, hooks));
    rt.shutdown_timeout(Duration::from_secs(2));
    // The sinks (zenoh session, files) are closed here, outside the runtime's threads.
    let (summary, end_sinks, status) = result?;
    drop(status);
    drop(end_sinks);
    Ok(summary)
}

struct Parts {
    source: Box<dyn Source>,
    tracker: Box<dyn tracker::track::PoseTracker>,
    sinks: Vec<Box<dyn crate::publish::PoseSink>>,
    status_put: Option<StatusPut>,
    timeline: drivers::timeline::TimelineConfig,
    health: Arc<Mutex<Health>>,
    queue: Arc<IngestQueue>,
    objects: Vec<String>,
    outputs: OutputPaths,
    /// Control commands from the zenoh sink, carried out on the tracker thread.
    control: Option<control::ControlApplier>,
    status_period: Duration,
    wait_for_room: bool,
    rt_priority: u8,
    latency_log: Option<LatencyLog>,
    /// Hold a depth frame that would delay the next tick until its poses are out ([`worker::Worker::with_depth_deferral`]).
    defer_depth: bool,
    /// Warn when a depth frame arrives older than this, ms ([`worker::Worker::with_depth_age_limit`]).
    depth_age_limit_ms: Option<f64>,
}

fn snapshot(health: &Mutex<Health>) -> Health {
    health.lock().unwrap_or_else(|p| p.into_inner()).clone()
}

type RunEnd = (
    Summary,
    Vec<Box<dyn crate::publish::PoseSink>>,
    Arc<Mutex<Option<StatusPut>>>,
);

async fn run_parts(p: Parts, mut hooks: Hooks) -> Result<RunEnd, RuntimeError> {
    let Parts {
        mut source,
        tracker,
        sinks,
        status_put,
        timeline,
        health,
        queue,
        objects,
        outputs,
        control,
        status_period,
        wait_for_room,
        rt_priority,
        latency_log,
        defer_depth,
        depth_age_limit_ms,
    } = p;
    let stop = hooks.stop.clone();
    let describe = source.describe();

    // The tracker thread.
    let worker = Worker::new(tracker, sinks, timeline, queue.clone(), health.clone())
        .with_latency_log(latency_log)
        .with_control(control)
        .with_depth_deferral(defer_depth)
        .with_depth_age_limit(depth_age_limit_ms);
    let tracker_thread = std::thread::Builder::new()
        .name("tracker".into())
        .spawn(move || {
            let (end, refused) = worker.run_with_priority(rt_priority);
            if let Some(why) = refused {
                eprintln!("warning: {why}");
            }
            end
        })
        .map_err(|e| RuntimeError::Thread(format!("cannot start the tracker thread: {e}")))?;

    // Ctrl-C stops cleanly: the source ends, the tracker drains, sinks flush, the summary is printed.
    let ctrl_c = hooks.ctrl_c.then(|| {
        let stop = stop.clone();
        tokio::spawn(async move {
            if tokio::signal::ctrl_c().await.is_ok() {
                eprintln!("\nstopping (Ctrl-C): draining the tracker and flushing the sinks");
                stop.set();
            }
        })
    });

    // The status timer: the status document on the zenoh status key every period.
    let status_state = Arc::new(Mutex::new(status_put));
    let status_task = {
        let health = health.clone();
        let status_state = status_state.clone();
        tokio::spawn(async move {
            let mut interval = tokio::time::interval(status_period);
            interval.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
            loop {
                interval.tick().await;
                let doc = snapshot(&health).status_json("running");
                let state = status_state.clone();
                let _ = tokio::task::spawn_blocking(move || put_status(&state, &doc)).await;
            }
        })
    };

    // Progress reports.
    let progress_task = hooks.progress.take().map(|mut f| {
        let health = health.clone();
        let period = hooks.progress_period;
        tokio::spawn(async move {
            let mut interval = tokio::time::interval(period);
            loop {
                interval.tick().await;
                f(&snapshot(&health));
            }
        })
    });

    if let Some(f) = hooks.before_start.take() {
        tokio::task::spawn_blocking(f)
            .await
            .map_err(|e| RuntimeError::Thread(format!("before_start hook failed: {e}")))?;
    }

    // The source, on a blocking thread; its end (or failure) ends the run.
    let started = Instant::now();
    let out = SourceOutput::new(queue.clone(), wait_for_room).with_health(health.clone());
    let source_stop = stop.clone();
    let source_result = tokio::task::spawn_blocking(move || source.run(&out, &source_stop)).await;
    queue.push(Ingest::End);
    let end = tokio::task::spawn_blocking(move || tracker_thread.join())
        .await
        .map_err(|e| RuntimeError::Thread(format!("tracker thread: {e}")))?
        .map_err(|_| RuntimeError::Thread("the tracker thread panicked".into()))?;
    let wall_s = started.elapsed().as_secs_f64();
    status_task.abort();
    if let Some(t) = progress_task {
        t.abort();
    }
    if let Some(t) = ctrl_c {
        t.abort();
    }
    let source_stats =
        source_result.map_err(|e| RuntimeError::Thread(format!("source task: {e}")))??;

    let h = snapshot(&health);
    let stopped = stop.is_set() || source_stats.stopped;
    let status = h.status_json(if stopped { "stopped" } else { "finished" });
    {
        let state = status_state.clone();
        let doc = status.clone();
        let _ = tokio::task::spawn_blocking(move || put_status(&state, &doc)).await;
    }
    let summary = Summary {
        source: describe,
        renderer: h.renderer.clone(),
        objects,
        ticks: h.ticks,
        poses: h.poses,
        wall_s,
        tick_rate_hz: h.tick_rate_hz(),
        camera_tick_rate_hz: h.camera_tick_rate_hz(),
        latency: h.latency.summary(),
        depth_frame_age: h.depth_frame_age.summary(),
        depth_arrival: h.depth_arrival.summary(),
        depth_frames_deferred: h.depth_frames_deferred,
        depth_frames_too_old: h.depth_frames_too_old,
        event_hold_overflows: h.event_hold_overflows,
        depth_frames_shed: h.depth_frames_shed,
        poses_revised: h.poses_revised,
        sinks: h
            .sinks
            .iter()
            .map(|s| SinkSummary {
                name: s.name.clone(),
                counters: s.counters,
                errors: s.errors,
                latency: s.latency.summary(),
            })
            .collect(),
        queue: h.queue,
        timeline: h.timeline,
        source_stats,
        tracker: h.tracker,
        stopped,
        outputs,
        status,
        shutdown_errors: end.flush_errors,
    };
    Ok((summary, end.sinks, status_state))
}

fn put_status(state: &Mutex<Option<StatusPut>>, doc: &serde_json::Value) {
    let mut guard = state.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(put) = guard.as_mut()
        && let Ok(bytes) = serde_json::to_vec(doc)
    {
        // Failures are counted by the zenoh sink's status counters; the run goes on.
        let _ = put(&bytes);
    }
}

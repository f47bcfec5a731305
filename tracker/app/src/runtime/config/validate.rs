//! Range, cross-reference and file checks of a parsed [`Config`].

use super::*;
use std::path::Path;

/// Checks ranges and cross-references (no file access).
pub fn validate(config: &Config, origin: &str) -> Result<(), ConfigError> {
    let bad = |key: &str, message: String| ConfigError::Invalid {
        origin: origin.into(),
        key: key.into(),
        message,
    };
    for (key, latency) in [
        ("source.depth_latency_ms", config.source.depth_latency_ms),
        (
            "source.depth_latency_jitter_ms",
            config.source.depth_latency_jitter_ms,
        ),
    ] {
        if !(latency.is_finite() && (0.0..=1000.0).contains(&latency)) {
            return Err(bad(key, format!("{latency} is out of range: 0 to 1000 ms")));
        }
        if latency > 0.0 && matches!(config.source.kind, SourceKind::Live | SourceKind::Ros2) {
            return Err(bad(
                key,
                "simulates a depth camera's transport latency on replay; a live source has its own (set it \
                 to 0)"
                    .into(),
            ));
        }
    }
    match config.source.kind {
        SourceKind::Demo => {
            let d = &config.demo;
            if !DEMO_OBJECTS.contains(&d.object.as_str()) {
                return Err(bad(
                    "demo.object",
                    format!(
                        "`{}` is not a library object (one of {})",
                        d.object,
                        DEMO_OBJECTS.join(", ")
                    ),
                ));
            }
            if !DEMO_MOTIONS.contains(&d.motion.as_str()) {
                return Err(bad(
                    "demo.motion",
                    format!("`{}` is not one of {}", d.motion, DEMO_MOTIONS.join(", ")),
                ));
            }
            if !DEMO_SPEEDS.contains(&d.speed.as_str()) {
                return Err(bad(
                    "demo.speed",
                    format!("`{}` is not one of {}", d.speed, DEMO_SPEEDS.join(", ")),
                ));
            }
            if !(d.seconds.is_finite() && d.seconds >= 0.1 && d.seconds <= 60.0) {
                return Err(bad(
                    "demo.seconds",
                    format!(
                        "{} is out of range: must be in [0.1, 60] seconds",
                        d.seconds
                    ),
                ));
            }
        }
        SourceKind::Replay => {
            if config.replay.is_none() {
                return Err(bad(
                    "replay",
                    "source.kind = \"replay\" needs a [replay] table with `recording`".into(),
                ));
            }
        }
        SourceKind::Live => {
            let Some(live) = &config.live else {
                return Err(bad(
                    "live",
                    "source.kind = \"live\" needs a [live] table (see config/rig-evk4-d435i.toml)"
                        .into(),
                ));
            };
            if live.event_camera != "evk4" {
                return Err(bad(
                    "live.event_camera",
                    format!("`{}` is not supported (supported: evk4)", live.event_camera),
                ));
            }
            super::validate_live::check_live(live, origin)?;
            if live.trigger_channel > 15 {
                return Err(bad(
                    "live.trigger_channel",
                    format!(
                        "{} is out of range: EVT 3.0 carries channels 0..15",
                        live.trigger_channel
                    ),
                ));
            }
            if config.objects.is_empty() && live.depth_camera != "recording" {
                return Err(bad(
                    "objects",
                    "a live rig needs at least one [[objects]] entry (name, mesh, first pose)"
                        .into(),
                ));
            }
        }
        SourceKind::Ros2 => {
            let Some(r) = &config.ros2 else {
                return Err(bad(
                    "ros2",
                    "source.kind = \"ros2\" needs a [ros2] table with `calibration` (see docs/zenoh-ros2.md)"
                        .into(),
                ));
            };
            r.validate(origin)?;
            if config.objects.is_empty() {
                return Err(bad(
                    "objects",
                    "the ROS 2 source needs at least one [[objects]] entry (name, mesh, first pose)".into(),
                ));
            }
        }
    }
    let max_s = config.source.max_seconds;
    if !(max_s.is_finite() && (0.0..=1e6).contains(&max_s)) {
        return Err(bad(
            "source.max_seconds",
            format!("{max_s} is out of range: 0 (until the source ends) to 1000000 seconds"),
        ));
    }
    if config.source.start_delay_ms > 60_000 {
        return Err(bad(
            "source.start_delay_ms",
            format!(
                "{} is out of range: at most 60000 ms",
                config.source.start_delay_ms
            ),
        ));
    }
    if config.tracker.realtime_priority > 99 {
        return Err(bad(
            "tracker.realtime_priority",
            format!(
                "{} is out of range: 0 (off) or a SCHED_FIFO priority 1..=99",
                config.tracker.realtime_priority
            ),
        ));
    }
    if config.tracker.method.trim().is_empty() {
        return Err(bad("tracker.method", "must not be empty".into()));
    }
    if let Err(e) = tracker::track::validate(&config.tracker.parameters) {
        return Err(bad(
            &format!("tracker.parameters.{}", e.key),
            format!("{} is out of range: {}", e.value, e.expected),
        ));
    }
    for (i, o) in config.objects.iter().enumerate() {
        let key = |k: &str| format!("objects[{i}].{k}");
        if o.name.is_empty() || o.name.contains(['/', '\\', ',', ' ']) {
            return Err(bad(
                &key("name"),
                format!(
                    "`{}` must be non-empty without '/', '\\', ',' or spaces",
                    o.name
                ),
            ));
        }
        if config.objects[..i].iter().any(|p| p.name == o.name) {
            return Err(bad(&key("name"), format!("`{}` is listed twice", o.name)));
        }
        if o.position.iter().any(|v| !v.is_finite()) {
            return Err(bad(
                &key("position"),
                "must be three finite numbers (metres)".into(),
            ));
        }
        let n = o.orientation.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !n.is_finite() || (n - 1.0).abs() > 1e-3 {
            return Err(bad(
                &key("orientation"),
                format!("quaternion (x, y, z, w) must have unit length (norm is {n:.6})"),
            ));
        }
    }
    let q = &config.queue;
    if !(4..=65_536).contains(&q.event_batches) {
        return Err(bad(
            "queue.event_batches",
            format!("{} is out of range: must be in 4..=65536", q.event_batches),
        ));
    }
    if !(16..=1_048_576).contains(&q.batch_events) {
        return Err(bad(
            "queue.batch_events",
            format!(
                "{} is out of range: must be in 16..=1048576",
                q.batch_events
            ),
        ));
    }
    if !(50..=100_000).contains(&q.batch_us) {
        return Err(bad(
            "queue.batch_us",
            format!(
                "{} is out of range: must be in 50..=100000 microseconds",
                q.batch_us
            ),
        ));
    }
    if !(10..=60_000).contains(&config.status.period_ms) {
        return Err(bad(
            "status.period_ms",
            format!(
                "{} is out of range: must be in 10..=60000 ms",
                config.status.period_ms
            ),
        ));
    }
    let z = &config.zenoh;
    if config.sinks.zenoh {
        let n_listen = z.listen.len();
        for (i, e) in z.listen.iter().chain(z.connect.iter()).enumerate() {
            let key = if i < n_listen {
                format!("zenoh.listen[{i}]")
            } else {
                format!("zenoh.connect[{}]", i - n_listen)
            };
            if !e.contains('/') {
                return Err(bad(
                    &key,
                    format!("`{e}` is not a zenoh endpoint like tcp/127.0.0.1:7447"),
                ));
            }
        }
        if z.domain_id > 232 {
            return Err(bad(
                "zenoh.domain_id",
                format!(
                    "{} is out of range: ROS domain ids are 0..=232",
                    z.domain_id
                ),
            ));
        }
    }
    let n_objects = config.objects.len().max(1);
    config.can.validate(n_objects).map_err(|e| {
        let (key, message) = match e {
            crate::publish::can::CanError::Config { key, message } => {
                (format!("can.{key}"), message)
            }
            other => ("can".to_string(), other.to_string()),
        };
        bad(&key, message)
    })?;
    Ok(())
}

/// Checks that the input files named by the configuration exist (meshes, calibration, recording).
pub fn check_files(config: &Config, origin: &str) -> Result<(), ConfigError> {
    let missing = |key: String, what: &str, p: &Path| ConfigError::Invalid {
        origin: origin.into(),
        key,
        message: format!("{what} {} does not exist", p.display()),
    };
    for (i, o) in config.objects.iter().enumerate() {
        if !o.mesh.is_file() {
            return Err(missing(format!("objects[{i}].mesh"), "mesh file", &o.mesh));
        }
    }
    if config.source.kind == SourceKind::Replay
        && let Some(r) = &config.replay
        && !r.recording.is_dir()
    {
        return Err(missing(
            "replay.recording".into(),
            "recording directory",
            &r.recording,
        ));
    }
    if config.source.kind == SourceKind::Live
        && let Some(l) = &config.live
        && l.depth_camera == "d435i"
        && !l.calibration.is_file()
    {
        return Err(missing(
            "live.calibration".into(),
            "calibration file",
            &l.calibration,
        ));
    }
    if config.source.kind == SourceKind::Ros2
        && let Some(r) = &config.ros2
        && !r.calibration.is_file()
    {
        return Err(missing(
            "ros2.calibration".into(),
            "calibration file",
            &r.calibration,
        ));
    }
    for (i, o) in config.objects.iter().enumerate() {
        if let Some(m) = &o.models_info
            && !m.is_file()
        {
            return Err(missing(
                format!("objects[{i}].models_info"),
                "models_info.json",
                m,
            ));
        }
    }
    if config.source.kind == SourceKind::Live
        && let Some(r) = config
            .live
            .as_ref()
            .and_then(|l| l.depth_recording.as_ref())
        && !r.is_dir()
    {
        return Err(missing(
            "live.depth_recording".into(),
            "recording directory",
            r,
        ));
    }
    Ok(())
}

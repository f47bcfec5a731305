//! `eventtrack6d record`: what the live rig sees, written as a recording directory (docs/recording-format.md)
//! that `track`, `run` and `bench` replay later. `events.raw` holds the camera's EVT 3.0 bytes exactly as they
//! arrived, under a header naming the camera, its serial, firmware and biases; `meta.json` the trigger schedule
//! and the session's counters (bytes, dropped transfers, gaps, outages). Until a live depth camera is
//! configured, the depth source is a recording (`[live] depth_camera = "recording"`) whose cameras, objects,
//! depth frames and ground truth (if any) are copied along, so the result replays like the original (and, when
//! the camera is the emulator streaming that recording, scores like it).

use super::config::{Config, LiveConfig, SourceKind, validate_live};
use super::source::StopFlag;
use super::{RuntimeError, SourceError};
use drivers::event::{EventCounter, Geometry};
use drivers::evk4::camera::SensorSettings;
use drivers::evk4::session::StreamingCamera;
use drivers::evk4::stream::StreamConfig;
use drivers::formats::any::EventFormat;
use drivers::formats::evt3::Evt3Decoder;
use drivers::raw::RawHeader;
use drivers::recording::{Recording, RecordingMeta};
use drivers::transfer_ring::{Chunk, TransferRing};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How a recording session went, for the progress line and the summary.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct RecordStats {
    /// The camera ("EVK4 serial (firmware, sensor, speed)").
    pub camera: String,
    /// Stream time recorded, seconds (first to latest event).
    pub stream_s: f64,
    /// Bytes written to events.raw (after its header).
    pub bytes: u64,
    /// CD events in them.
    pub events: u64,
    /// Trigger edges in them.
    pub trigger_edges: u64,
    /// Transfers dropped because the ring was full (the file has a gap there).
    pub dropped_transfers: u64,
    /// Bytes of the dropped transfers.
    pub dropped_bytes: u64,
    /// Gaps in the file (runs of dropped or failed transfers).
    pub gaps: u64,
    /// Times the camera went away and was reopened.
    pub outages: u64,
    /// Wall-clock seconds from the camera's start to the end of the recording.
    pub wall_s: f64,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> RuntimeError + '_ {
    move |e| RuntimeError::Output(format!("{}: {e}", path.display()))
}

/// Copies `from` (a file or a directory tree) to `to`.
fn copy_tree(from: &Path, to: &Path) -> std::io::Result<()> {
    if from.is_dir() {
        std::fs::create_dir_all(to)?;
        for entry in std::fs::read_dir(from)? {
            let entry = entry?;
            copy_tree(&entry.path(), &to.join(entry.file_name()))?;
        }
        Ok(())
    } else {
        std::fs::copy(from, to).map(|_| ())
    }
}

/// The `[live]` table of a configuration and its depth recording, or why it cannot be recorded.
fn live_and_depth(config: &Config) -> Result<(&LiveConfig, Recording), RuntimeError> {
    let input = |m: String| RuntimeError::Source(SourceError::Input(m));
    let live = match (&config.source.kind, &config.live) {
        (SourceKind::Live, Some(live)) => live,
        _ => {
            return Err(input(
                "record needs a live configuration ([source] kind = \"live\" and a [live] table)"
                    .into(),
            ));
        }
    };
    let depth_dir = validate_live::depth_recording(live, "record")
        .map_err(|m| RuntimeError::Source(SourceError::NotImplemented(m)))?;
    Ok((live, Recording::open(depth_dir)?))
}

/// `events.raw`'s header: EVT 3.0 at the IMX636's geometry, naming the camera, its firmware and the biases.
fn header(session: &StreamingCamera, settings: &SensorSettings) -> RawHeader {
    let mut fields: Vec<(String, String)> = vec![
        ("camera_integrator_name".into(), "Prophesee".into()),
        ("plugin_name".into(), "hal_plugin_imx636_evk4".into()),
        ("serial_number".into(), session.camera.serial.clone()),
        (
            "firmware".into(),
            drivers::evk4::identity::release_string(session.camera.release),
        ),
        ("sensor".into(), session.camera.sensor.clone()),
        (
            "generator".into(),
            format!("eventtrack6d record {}", env!("CARGO_PKG_VERSION")),
        ),
    ];
    fields.extend(
        settings
            .biases
            .iter()
            .map(|(b, o)| (b.name.to_owned(), o.to_string())),
    );
    let extra: Vec<(&str, &str)> = fields
        .iter()
        .map(|(k, v)| (k.as_str(), v.as_str()))
        .collect();
    RawHeader::new(EventFormat::Evt3, Geometry::new(1280, 720), &extra)
}

/// Writes the camera's bytes to `events.raw` as they come, counting what they hold.
struct EventsFile {
    file: std::io::BufWriter<std::fs::File>,
    path: PathBuf,
    decoder: Evt3Decoder,
    counter: EventCounter,
    first_us: Option<i64>,
}

impl EventsFile {
    /// Creates `path` with `header`.
    fn create(path: PathBuf, header: &RawHeader) -> Result<Self, RuntimeError> {
        let mut file = std::io::BufWriter::new(std::fs::File::create(&path).map_err(io(&path))?);
        header.write(&mut file).map_err(io(&path))?;
        Ok(Self {
            file,
            path,
            decoder: Evt3Decoder::new(Some(Geometry::new(1280, 720))),
            counter: EventCounter::new(),
            first_us: None,
        })
    }

    /// Appends a chunk (after a gap, the decoder that counts resynchronises; the file keeps the bytes as they came).
    fn append(&mut self, chunk: &Chunk, stats: &mut RecordStats) -> Result<(), RuntimeError> {
        if chunk.after_gap {
            self.decoder.resynchronise();
            stats.gaps += 1;
        }
        self.file.write_all(&chunk.bytes).map_err(io(&self.path))?;
        stats.bytes += chunk.bytes.len() as u64;
        self.decoder.decode(&chunk.bytes, &mut self.counter);
        let now_us = self.decoder.current_time_us();
        stats.stream_s = (now_us - *self.first_us.get_or_insert(now_us)) as f64 * 1e-6;
        stats.events = self.counter.positive + self.counter.negative;
        Ok(())
    }

    /// Flushes the file; the trigger edges counted go into `stats`.
    fn finish(mut self, stats: &mut RecordStats) -> Result<(), RuntimeError> {
        stats.trigger_edges = self.counter.trigger_edges.iter().flatten().sum();
        self.file.flush().map_err(io(&self.path))
    }
}

/// Records the live rig of `config` into `out` (created; must not hold a recording already) until `seconds` of
/// stream time (if given) or `stop`; `progress` is called about once a second.
pub fn record(
    config: &Config,
    out: &Path,
    seconds: Option<f64>,
    stop: &StopFlag,
    mut progress: impl FnMut(&RecordStats),
) -> Result<RecordStats, RuntimeError> {
    let (live, depth) = live_and_depth(config)?;
    if out.join("events.raw").exists() {
        return Err(RuntimeError::Output(format!(
            "{} already holds a recording",
            out.display()
        )));
    }
    std::fs::create_dir_all(out).map_err(io(out))?;
    let input = |m: String| RuntimeError::Source(SourceError::Input(m));
    let settings = validate_live::sensor_settings(live).map_err(input)?;
    let stream = validate_live::stream_config(live);
    let ring = Arc::new(TransferRing::new(stream.ring_slots, stream.transfer_bytes));
    let serial = (!live.event_serial.is_empty()).then_some(live.event_serial.as_str());
    let mut session = StreamingCamera::start(serial, &settings, stream, &ring)
        .map_err(|e| input(e.to_string()))?;
    let mut stats = RecordStats {
        camera: session.describe(),
        ..RecordStats::default()
    };
    let mut file = EventsFile::create(out.join("events.raw"), &header(&session, &settings))?;
    let (started, mut last_report) = (Instant::now(), Instant::now());
    while !stop.is_set() && seconds.is_none_or(|s| stats.stream_s < s) {
        let Some(chunk) = ring.pop(Duration::from_millis(20)) else {
            if session.stream.is_disconnected() {
                stats.outages += 1;
                eprintln!("record: the camera was disconnected; reopening");
                drop(session);
                session = reopen(serial, &settings, stream, &ring, stop)?;
            }
            continue;
        };
        file.append(&chunk, &mut stats)?;
        ring.recycle(chunk);
        stats.wall_s = started.elapsed().as_secs_f64();
        if last_report.elapsed() >= Duration::from_secs(1) {
            last_report = Instant::now();
            progress(&stats);
        }
    }
    stats.wall_s = started.elapsed().as_secs_f64();
    let _ = session.camera.stop();
    drop(session);
    file.finish(&mut stats)?;
    let ring_counters = ring.counters();
    stats.dropped_transfers = ring_counters.dropped_chunks;
    stats.dropped_bytes = ring_counters.dropped_bytes;
    write_companions(&depth, live.trigger_channel, out, &stats)?;
    Ok(stats)
}

/// Reopens a camera that went away, until it is back or `stop` is set.
fn reopen(
    serial: Option<&str>,
    settings: &SensorSettings,
    stream: StreamConfig,
    ring: &Arc<TransferRing>,
    stop: &StopFlag,
) -> Result<StreamingCamera, RuntimeError> {
    loop {
        match StreamingCamera::start(serial, settings, stream, ring) {
            Ok(s) => return Ok(s),
            Err(e) if !e.is_transient() || stop.is_set() => {
                return Err(RuntimeError::Source(SourceError::Input(e.to_string())));
            }
            Err(_) => std::thread::sleep(Duration::from_millis(250)),
        }
    }
}

/// Writes meta.json and copies the depth recording's cameras, objects and depth frames into `out`.
fn write_companions(
    depth: &Recording,
    channel: u8,
    out: &Path,
    stats: &RecordStats,
) -> Result<(), RuntimeError> {
    for name in ["camera.json", "models", "depth", "groundtruth.csv"] {
        let from = depth.dir().join(name);
        if from.exists() {
            copy_tree(&from, &out.join(name)).map_err(io(&from))?;
        }
    }
    let mut trigger = depth.meta.trigger;
    trigger.channel = channel;
    let mut parameters = serde_json::Map::new();
    parameters.insert(
        "session".into(),
        serde_json::to_value(stats).unwrap_or_default(),
    );
    parameters.insert(
        "depth_from".into(),
        depth.dir().display().to_string().into(),
    );
    let meta = RecordingMeta {
        generator: format!("eventtrack6d record {}", env!("CARGO_PKG_VERSION")),
        trigger,
        parameters,
    };
    let path = out.join("meta.json");
    let text =
        serde_json::to_string_pretty(&meta).map_err(|e| RuntimeError::Output(e.to_string()))?;
    std::fs::write(&path, text).map_err(io(&path))
}

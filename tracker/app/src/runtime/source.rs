//! The sensor-source interface: recording replay implements it today, the live EVK4 + D435i drivers later.
//!
//! A source pushes, in stream order, decoded CD event batches, trigger edges (stamped with the instant they were
//! decoded) and depth frames (stamped with their exposure; the replay delivers each before the trigger edge that
//! completes its phase-coded pulse, or that much later in stream time with `depth_latency_ms`; a live depth camera
//! delivers it when it arrives, and the tracker tracks the ticks since its exposure again with it then) into a
//! [`SourceOutput`]. It runs on a blocking thread of the runtime and returns when its stream ends or when
//! [`StopFlag::is_set`] says so.

pub use super::health::Ros2Stats;

use super::health::{CameraHealth, Health};
use super::queue::{Ingest, IngestQueue};
use drivers::anomaly::DecodeAnomalies;
use drivers::event::{CdEvent, TriggerEdge};
use drivers::recording::DepthFrame;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// A shared stop request (Ctrl-C, the caller, or the end of the run).
#[derive(Debug, Clone, Default)]
pub struct StopFlag(Arc<AtomicBool>);

impl StopFlag {
    /// A flag not yet set.
    pub fn new() -> Self {
        Self::default()
    }
    /// Requests a stop.
    pub fn set(&self) {
        self.0.store(true, Ordering::SeqCst);
    }
    /// Whether a stop was requested.
    pub fn is_set(&self) -> bool {
        self.0.load(Ordering::SeqCst)
    }
}

/// Why a source failed.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// The input could not be read (names the file or device and the problem).
    #[error("{0}")]
    Input(String),
    /// The source exists in the configuration but has no driver yet.
    #[error("{0}")]
    NotImplemented(String),
}

/// What a source did, for the summary.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct SourceStats {
    /// CD events decoded.
    pub events: u64,
    /// Trigger edges decoded.
    pub trigger_edges: u64,
    /// Depth frames delivered.
    pub depth_frames: u64,
    /// Phase-coded pulses whose depth frame was missing (dropped by the camera, or unreadable).
    pub depth_missing: u64,
    /// Depth frames still in transit when the stream ended (replay with `depth_latency_ms`).
    pub depth_in_transit: u64,
    /// Skipped stream words by kind (malformed sensor data, counted and skipped).
    pub anomalies: Vec<(String, u64)>,
    /// Whether the source stopped early on request.
    pub stopped: bool,
    /// The USB side of a live camera (`None` for a replay).
    pub usb: Option<UsbStats>,
    /// What the ROS 2 source received (`None` for other sources).
    pub ros2: Option<Ros2Stats>,
}

/// What the USB side of a live camera did: the data path's counters and the camera's outages.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct UsbStats {
    /// Times the camera was opened and streamed.
    pub sessions: u64,
    /// Times the camera went away while streaming (each followed by reopening).
    pub outages: u64,
    /// Failed attempts to open the camera (absent, busy, or not yet back).
    pub open_attempts_failed: u64,
    /// Event bytes received into the ring.
    pub bytes: u64,
    /// Transfers dropped because the ring was full (the decoder resynchronised after each run of them).
    pub dropped_transfers: u64,
    /// Bytes of the dropped transfers.
    pub dropped_bytes: u64,
    /// Transfers that failed (I/O error, stall).
    pub transfer_errors: u64,
    /// Gaps in the stream the decoder resynchronised after.
    pub gaps: u64,
    /// Tick pulses made on the wall clock while the camera was away.
    pub pulses_made_while_away: u64,
    /// Memory of the ring between USB and the decoder, bytes.
    pub ring_bytes: u64,
    /// The most ring slots filled at once.
    pub max_ring_filled: u64,
    /// The latest problem with the camera, while it lasts.
    pub last_error: Option<String>,
}

impl SourceStats {
    /// Copies the decoder's anomaly counters.
    pub fn set_anomalies(&mut self, a: &DecodeAnomalies) {
        self.anomalies = a
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(k, n)| (k.to_string(), n))
            .collect();
    }
}

/// Where a source delivers its stream: the ingest queue, with the overload policy of the pacing mode.
#[derive(Debug, Clone)]
pub struct SourceOutput {
    queue: Arc<IngestQueue>,
    /// Wait for room instead of dropping (fast replay); real-time sources never wait.
    wait_for_room: bool,
    /// Where a live source reports its device's state (the status topic and the progress line read it).
    health: Option<Arc<Mutex<Health>>>,
}

impl SourceOutput {
    /// Output into `queue`; `wait_for_room` selects back-pressure (fast replay) over drop-oldest (real time).
    pub fn new(queue: Arc<IngestQueue>, wait_for_room: bool) -> Self {
        Self {
            queue,
            wait_for_room,
            health: None,
        }
    }

    /// The same output, reporting a live source's device state into `health`.
    pub fn with_health(mut self, health: Arc<Mutex<Health>>) -> Self {
        self.health = Some(health);
        self
    }

    /// Reports the live event camera's state (for the status topic).
    pub fn camera_health(&self, camera: CameraHealth) {
        if let Some(h) = &self.health {
            h.lock().unwrap_or_else(|p| p.into_inner()).event_camera = Some(camera);
        }
    }

    /// Reports what the ROS 2 source received so far (for the status topic).
    pub fn ros2_health(&self, stats: &Ros2Stats) {
        if let Some(h) = &self.health {
            h.lock().unwrap_or_else(|p| p.into_inner()).ros2_input = Some(stats.clone());
        }
    }

    /// An empty event buffer (recycled; no allocation in steady state).
    pub fn buffer(&self) -> Vec<CdEvent> {
        self.queue.buffer()
    }

    /// Delivers an event batch (time-ordered).
    pub fn events(&self, batch: Vec<CdEvent>) {
        if batch.is_empty() {
            self.queue.recycle(batch);
            return;
        }
        if self.wait_for_room {
            self.queue.push_wait(Ingest::Events(batch));
        } else {
            self.queue.push(Ingest::Events(batch));
        }
    }

    /// Delivers a trigger edge, stamped now as its decode instant.
    pub fn trigger(&self, edge: TriggerEdge) {
        self.queue.push(Ingest::Trigger {
            edge,
            decoded_at: Instant::now(),
        });
    }

    /// Delivers a depth frame exposed at `t_us`.
    pub fn depth(&self, t_us: i64, frame: Box<DepthFrame>) {
        self.queue.push(Ingest::Depth { t_us, frame });
    }
}

/// A sensor source (recording replay, live rig).
pub trait Source: Send {
    /// Human-readable description (for logs and the summary).
    fn describe(&self) -> String;
    /// Streams until the end of input or until `stop` is set. Malformed data is counted and skipped; only an
    /// unusable input (file or device) is an error.
    fn run(&mut self, out: &SourceOutput, stop: &StopFlag) -> Result<SourceStats, SourceError>;
}

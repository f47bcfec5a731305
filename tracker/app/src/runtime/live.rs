//! The live event camera as a source: an EVK4 over USB (`drivers::evk4`), its data endpoint decoded as it
//! arrives and assembled like a replay ([`super::assembly`]): event batches, trigger edges, and, until a live
//! depth camera is configured, a recording's depth frames on the trigger timeline (`[live] depth_camera =
//! "recording"`). The USB side never waits for the tracker: the transfer ring between them drops and counts when
//! full, and the decoder resynchronises after every gap. A camera that goes away is reported, and reopened
//! (with backoff) until the run stops; each outage is counted.

use super::assembly::StreamAssembler;
use super::source::{Source, SourceError, SourceOutput, SourceStats, StopFlag, UsbStats};
use drivers::event::EventBuffer;
use drivers::evk4::camera::{Evk4, SensorSettings};
use drivers::evk4::identity::DATA_IN;
use drivers::evk4::stream::{DataStream, StreamConfig};
use drivers::formats::evt3::Evt3Decoder;
use drivers::recording::{Recording, TriggerSchedule};
use drivers::transfer_ring::TransferRing;
use std::sync::Arc;
use std::time::{Duration, Instant};
use tracker::track::DepthTransport;

/// How long the reader waits for a chunk before it checks the stop flag and the device again.
const POLL: Duration = Duration::from_millis(20);

/// Reconnection timing after an unplug or a failed open.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Backoff {
    /// First wait before reopening.
    pub first: Duration,
    /// Longest wait (each failed attempt doubles the wait up to this).
    pub max: Duration,
}

/// The live EVK4 source.
pub struct LiveEvk4Source {
    serial: Option<String>,
    settings: SensorSettings,
    stream: StreamConfig,
    backoff: Backoff,
    depth: Option<Recording>,
    schedule: TriggerSchedule,
    batch: (usize, i64),
    max_seconds: f64,
}

impl LiveEvk4Source {
    /// The same source ending after `seconds` of the camera's clock from its first event (0: until stopped).
    pub fn with_max_seconds(mut self, seconds: f64) -> Self {
        self.max_seconds = seconds;
        self
    }

    /// A source reading the EVK4 with `serial` (or the first found), brought up with `settings`, whose depth
    /// frames come from `depth` (a recording, on `schedule`'s timeline) if given.
    pub fn new(
        serial: Option<String>,
        settings: SensorSettings,
        stream: StreamConfig,
        backoff: Backoff,
        depth: Option<Recording>,
        schedule: TriggerSchedule,
        batch: (usize, i64),
    ) -> Self {
        Self {
            serial,
            settings,
            stream,
            backoff,
            depth,
            schedule,
            batch,
            max_seconds: 0.0,
        }
    }
}

/// One open camera with its data stream running.
struct Session {
    camera: Evk4,
    stream: DataStream,
}

impl LiveEvk4Source {
    fn open(&self, context: &rusb::Context, ring: &Arc<TransferRing>) -> Result<Session, String> {
        let camera = Evk4::open(context, self.serial.as_deref()).map_err(|e| e.to_string())?;
        camera.bring_up(&self.settings).map_err(|e| e.to_string())?;
        camera
            .flush_data(Duration::from_millis(100))
            .map_err(|e| e.to_string())?;
        let stream = DataStream::start(camera.handle(), DATA_IN, self.stream, ring.clone())
            .map_err(|e| format!("EVK4 {}: data stream: {e}", camera.serial))?;
        camera.start().map_err(|e| e.to_string())?;
        eprintln!(
            "live: EVK4 {} (firmware {}, {}, {}) streaming",
            camera.serial,
            drivers::evk4::identity::release_string(camera.release),
            camera.sensor,
            camera.speed
        );
        Ok(Session { camera, stream })
    }

    /// Opens the camera, retrying with backoff until it opens or the run stops. A fault of the camera's
    /// configuration (a refused register, an unsupported device) ends the run at once.
    fn open_until_stopped(
        &self,
        context: &rusb::Context,
        ring: &Arc<TransferRing>,
        stop: &StopFlag,
        usb: &mut UsbStats,
    ) -> Result<Option<Session>, SourceError> {
        let mut wait = self.backoff.first;
        loop {
            match self.open(context, ring) {
                Ok(s) => return Ok(Some(s)),
                Err(e) if is_fatal(&e) => return Err(SourceError::Input(e)),
                Err(e) => {
                    if usb.last_error.as_deref() != Some(e.as_str()) {
                        eprintln!("live: {e}; retrying every {} ms", wait.as_millis());
                        usb.last_error = Some(e);
                    }
                    usb.open_attempts_failed += 1;
                }
            }
            let until = Instant::now() + wait;
            while Instant::now() < until {
                if stop.is_set() {
                    return Ok(None);
                }
                std::thread::sleep(POLL.min(until - Instant::now()));
            }
            wait = (wait * 2).min(self.backoff.max);
        }
    }
}

/// Whether an open error is the camera's or the configuration's fault (no use retrying).
fn is_fatal(message: &str) -> bool {
    message.contains("register")
        || message.contains("not supported")
        || message.contains("firmware")
        || message.contains("bias")
}

impl Source for LiveEvk4Source {
    fn describe(&self) -> String {
        format!(
            "live EVK4 {}{}",
            self.serial.as_deref().unwrap_or("(first found)"),
            self.depth.as_ref().map_or(String::new(), |r| format!(
                ", depth from {}",
                r.dir().display()
            ))
        )
    }

    fn run(&mut self, out: &SourceOutput, stop: &StopFlag) -> Result<SourceStats, SourceError> {
        let context = rusb::Context::new()
            .map_err(|e| SourceError::Input(format!("USB is not usable on this machine: {e}")))?;
        let ring = Arc::new(TransferRing::new(
            self.stream.ring_slots,
            self.stream.transfer_bytes,
        ));
        let mut assembler = StreamAssembler::new(
            out,
            self.depth.as_ref(),
            self.schedule,
            false,
            self.batch,
            DepthTransport::default(),
            stop,
        )
        .with_max_seconds(self.max_seconds);
        let mut decoder = Evt3Decoder::new(Some(drivers::event::Geometry::new(1280, 720)));
        let mut chunk = EventBuffer::new();
        let mut usb = UsbStats {
            ring_bytes: ring.memory_bytes() as u64,
            ..UsbStats::default()
        };
        let mut stopped = false;
        'sessions: while !stop.is_set() {
            let Some(session) = self.open_until_stopped(&context, &ring, stop, &mut usb)? else {
                break;
            };
            usb.sessions += 1;
            usb.last_error = None;
            loop {
                if stop.is_set() || assembler.reached_end() {
                    let _ = session.camera.stop();
                    stopped = stop.is_set();
                    break 'sessions;
                }
                let Some(c) = ring.pop(POLL) else {
                    if session.stream.is_disconnected() {
                        break;
                    }
                    continue;
                };
                if c.after_gap {
                    decoder.resynchronise();
                    usb.gaps += 1;
                }
                chunk.clear();
                decoder.decode(&c.bytes, &mut chunk);
                ring.recycle(c);
                assembler.feed(&chunk, stop);
            }
            // Unplugged: what is still in the ring goes out, then the camera is reopened.
            while let Some(c) = ring.pop(Duration::ZERO) {
                chunk.clear();
                decoder.decode(&c.bytes, &mut chunk);
                ring.recycle(c);
                assembler.feed(&chunk, stop);
            }
            let counters = session.stream.counters();
            usb.transfer_errors += counters.transfer_errors;
            drop(session);
            usb.outages += 1;
            usb.last_error = Some("the EVK4 was disconnected".into());
            eprintln!("live: the EVK4 was disconnected; reopening");
            decoder.resynchronise();
        }
        let mut stats = assembler.finish();
        stats.stopped = stopped;
        stats.set_anomalies(decoder.anomalies());
        let ring_counters = ring.counters();
        usb.bytes = ring_counters.bytes;
        usb.dropped_transfers = ring_counters.dropped_chunks;
        usb.dropped_bytes = ring_counters.dropped_bytes;
        usb.max_ring_filled = ring_counters.max_filled as u64;
        stats.usb = Some(usb);
        Ok(stats)
    }
}

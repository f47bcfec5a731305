//! The live event camera as a source: an EVK4 over USB (`drivers::evk4`), its data endpoint decoded as it
//! arrives and assembled like a replay ([`super::assembly`]): event batches, trigger edges, and, until a live
//! depth camera is configured, a recording's depth frames on the trigger timeline (`[live] depth_camera =
//! "recording"`). The USB side never waits for the tracker: the transfer ring between them drops and counts when
//! full, and the decoder resynchronises after every gap. A camera that goes away is reported, and reopened
//! (with backoff) until the run stops; each outage is counted, and meanwhile the tick pulses continue on the wall
//! clock so the objects keep being published with the states the tracker gives them ([`super::live_clock`]).

use super::assembly::StreamAssembler;
use super::health::CameraHealth;
use super::live_clock::LiveClock;
use super::source::{Source, SourceError, SourceOutput, SourceStats, StopFlag, UsbStats};
use drivers::event::EventBuffer;
use drivers::evk4::camera::SensorSettings;
use drivers::evk4::session::StreamingCamera;
use drivers::evk4::stream::StreamConfig;
use drivers::formats::evt3::Evt3Decoder;
use drivers::recording::{Recording, TriggerSchedule};
use drivers::transfer_ring::{Chunk, TransferRing};
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

impl LiveEvk4Source {
    /// Opens the camera, retrying with backoff until it opens or the run stops, while the reader keeps the tick
    /// pulses coming if the camera was lost ([`LiveClock`]). The bring-up runs on a helper thread for that. A
    /// fault of the camera's configuration (a refused register, an unsupported device) ends the run at once.
    fn open_until_stopped(
        &self,
        reader: &mut Reader<'_>,
        stop: &StopFlag,
    ) -> Result<Option<StreamingCamera>, SourceError> {
        let mut wait = self.backoff.first;
        loop {
            let attempt = {
                let (serial, settings, config) = (self.serial.clone(), self.settings, self.stream);
                let ring = reader.ring.clone();
                std::thread::Builder::new()
                    .name("evk4-open".into())
                    .spawn(move || {
                        StreamingCamera::start(serial.as_deref(), &settings, config, &ring)
                    })
                    .map_err(|e| {
                        SourceError::Input(format!("cannot start the camera thread: {e}"))
                    })?
            };
            while !attempt.is_finished() {
                if stop.is_set() {
                    // The bring-up ends on its own; its camera is dropped with it.
                    return Ok(None);
                }
                reader.while_away(stop);
                std::thread::sleep(POLL);
            }
            let result = attempt
                .join()
                .map_err(|_| SourceError::Input("the camera thread panicked".into()))?;
            match result {
                Ok(s) => {
                    eprintln!("live: {} streaming", s.describe());
                    reader.usb.last_error = None;
                    let back = reader.clock.camera_back();
                    if let Some(span) = reader.away_us.last_mut().filter(|s| s.1.is_none()) {
                        span.1 = Some(back);
                    }
                    report(
                        reader.out,
                        "streaming",
                        Some(s.describe()),
                        &reader.usb,
                        &reader.ring,
                        &reader.away_us,
                    );
                    return Ok(Some(s));
                }
                Err(e) if !e.is_transient() => return Err(SourceError::Input(e.to_string())),
                Err(e) => {
                    let e = e.to_string();
                    if reader.usb.last_error.as_deref() != Some(e.as_str()) {
                        eprintln!("live: {e}; retrying every {} ms", wait.as_millis());
                        reader.usb.last_error = Some(e);
                    }
                    reader.usb.open_attempts_failed += 1;
                    report(
                        reader.out,
                        "opening",
                        None,
                        &reader.usb,
                        &reader.ring,
                        &reader.away_us,
                    );
                }
            }
            let until = Instant::now() + wait;
            while Instant::now() < until {
                if stop.is_set() {
                    return Ok(None);
                }
                reader.while_away(stop);
                std::thread::sleep(POLL.min(until - Instant::now()));
            }
            wait = (wait * 2).min(self.backoff.max);
        }
    }
}

/// Reports the camera's state and the data path's drop counters to the status.
fn report(
    out: &SourceOutput,
    state: &'static str,
    camera: Option<String>,
    usb: &UsbStats,
    ring: &TransferRing,
    away_us: &[(i64, Option<i64>)],
) {
    let c = ring.counters();
    out.camera_health(CameraHealth {
        state,
        camera,
        error: usb.last_error.clone(),
        outages: usb.outages,
        dropped_transfers: c.dropped_chunks,
        dropped_bytes: c.dropped_bytes,
        away_us: away_us.to_vec(),
    });
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
        let ring = Arc::new(TransferRing::new(
            self.stream.ring_slots,
            self.stream.transfer_bytes,
        ));
        let assembler = StreamAssembler::new(
            out,
            self.depth.as_ref(),
            self.schedule,
            false,
            self.batch,
            DepthTransport::default(),
            stop,
        )
        .with_max_seconds(self.max_seconds);
        let mut reader = Reader {
            usb: UsbStats {
                ring_bytes: ring.memory_bytes() as u64,
                ..UsbStats::default()
            },
            ring,
            assembler,
            decoder: Evt3Decoder::new(Some(drivers::event::Geometry::new(1280, 720))),
            chunk: EventBuffer::new(),
            clock: LiveClock::new(self.schedule),
            away_us: Vec::new(),
            out,
        };
        let mut stopped = false;
        while !stop.is_set() {
            let Some(session) = self.open_until_stopped(&mut reader, stop)? else {
                break;
            };
            reader.usb.sessions += 1;
            match reader.stream(&session, stop) {
                SessionEnd::Ended { by_request } => {
                    let _ = session.camera.stop();
                    stopped = by_request;
                    break;
                }
                SessionEnd::Disconnected { last_data } => reader.outage(session, last_data),
            }
        }
        Ok(reader.finish(stopped))
    }
}

/// How a camera's session ended.
enum SessionEnd {
    /// The run ends: on request (`by_request`) or at the end of its stream time.
    Ended {
        /// Whether a stop was requested.
        by_request: bool,
    },
    /// The camera went away; its last data came at `last_data`.
    Disconnected {
        /// When the last chunk arrived.
        last_data: Instant,
    },
}

/// The reading side of a live run: the ring, the decoder and the assembler, with the USB counters.
struct Reader<'a> {
    ring: Arc<TransferRing>,
    assembler: StreamAssembler<'a>,
    decoder: Evt3Decoder,
    chunk: EventBuffer,
    clock: LiveClock,
    /// Spans of stream time the camera was away (see [`CameraHealth::away_us`]).
    away_us: Vec<(i64, Option<i64>)>,
    usb: UsbStats,
    out: &'a SourceOutput,
}

impl Reader<'_> {
    /// Decodes one chunk (resynchronising after a gap) and delivers it.
    fn deliver(&mut self, c: Chunk, stop: &StopFlag) {
        if c.after_gap {
            self.decoder.resynchronise();
            self.usb.gaps += 1;
        }
        self.chunk.clear();
        self.decoder.decode(&c.bytes, &mut self.chunk);
        self.ring.recycle(c);
        self.clock.map(&mut self.chunk);
        self.assembler.feed(&self.chunk, stop);
    }

    /// While the camera is away: a tick pulse of the stream's clock when one is due, so the tracker keeps ticking.
    fn while_away(&mut self, stop: &StopFlag) {
        let now = Instant::now();
        while let Some(edges) = self.clock.pulse_due(now) {
            self.chunk.clear();
            self.chunk.triggers.extend(edges);
            self.assembler.feed(&self.chunk, stop);
        }
    }

    /// Reads `session`'s data until the run ends or the camera goes away.
    fn stream(&mut self, session: &StreamingCamera, stop: &StopFlag) -> SessionEnd {
        let (mut last_data, mut last_report) = (Instant::now(), Instant::now());
        loop {
            if stop.is_set() || self.assembler.reached_end() {
                return SessionEnd::Ended {
                    by_request: stop.is_set(),
                };
            }
            let Some(c) = self.ring.pop(POLL) else {
                if session.stream.is_disconnected() {
                    return SessionEnd::Disconnected { last_data };
                }
                continue;
            };
            last_data = Instant::now();
            if last_data.duration_since(last_report) >= Duration::from_secs(1) {
                last_report = last_data;
                report(
                    self.out,
                    "streaming",
                    Some(session.describe()),
                    &self.usb,
                    &self.ring,
                    &self.away_us,
                );
            }
            self.deliver(c, stop);
        }
    }

    /// After an unplug: what is still in the ring goes out, the outage is counted and reported.
    fn outage(&mut self, session: StreamingCamera, last_data: Instant) {
        let never = StopFlag::new();
        while let Some(c) = self.ring.pop(Duration::ZERO) {
            self.deliver(c, &never);
        }
        self.usb.transfer_errors += session.stream.counters().transfer_errors;
        self.usb.outages += 1;
        let silent_ms = last_data.elapsed().as_secs_f64() * 1e3;
        let message = format!(
            "the EVK4 {} was disconnected (stream time {:.3} s, {silent_ms:.0} ms after its last data)",
            session.camera.serial,
            self.decoder.current_time_us() as f64 * 1e-6
        );
        drop(session);
        eprintln!("live: {message}; reopening");
        self.usb.last_error = Some(message);
        // A camera that comes back starts its own time base; the clock moves it to continue the stream.
        self.decoder.restart();
        let after = self.clock.camera_lost(Instant::now());
        self.away_us.push((after, None));
        report(
            self.out,
            "disconnected",
            None,
            &self.usb,
            &self.ring,
            &self.away_us,
        );
    }

    /// What the run delivered, with the ring's counters.
    fn finish(mut self, stopped: bool) -> SourceStats {
        let mut stats = self.assembler.finish();
        stats.stopped = stopped;
        stats.set_anomalies(self.decoder.anomalies());
        let ring = self.ring.counters();
        self.usb.bytes = ring.bytes;
        self.usb.dropped_transfers = ring.dropped_chunks;
        self.usb.dropped_bytes = ring.dropped_bytes;
        self.usb.max_ring_filled = ring.max_filled as u64;
        self.usb.pulses_made_while_away = self.clock.pulses_made;
        stats.usb = Some(self.usb);
        stats
    }
}

//! The sensors through ROS 2: events from an `event_camera_msgs/msg/EventPacket` topic (metavision_driver's raw
//! EVT3, decoded by one decoder whose state carries across packets), depth from a `sensor_msgs/msg/Image` topic
//! with its `CameraInfo` (realsense-ros), each on its rmw_zenoh key. Depth images are placed on the event camera's
//! clock through the stamps ([`clock`]) and matched to the phase-coded trigger pulses in the event stream
//! ([`super::assembly`], as the live source does). Every packet or image that cannot be used is counted by kind
//! and named once in a warning; a gap in the packets' sequence numbers resynchronises the decoder.

mod clock;
mod inputs;
mod playback;
mod startup;

pub use playback::{PlaybackEndpoints, playback_config};
pub use startup::connect;

use super::assembly::StreamAssembler;
use super::source::{Ros2Stats, Source, SourceError, SourceOutput, SourceStats, StopFlag};
use clock::ClockOffset;
use drivers::event::{EventBuffer, Geometry};
use drivers::formats::evt3::Evt3Decoder;
use drivers::recording::{CameraIntrinsics, DepthFrame, TriggerSchedule};
use inputs::{Ros2Input, Subscriptions, camera_info_mismatch};
use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};
use tracker::track::DepthTransport;

/// How long the source waits for a sample before it checks the stop flag and the idle time again.
const POLL: Duration = Duration::from_millis(50);

/// The ROS 2 source; built (and connected) by [`connect`].
pub struct Ros2Source {
    session: Option<zenoh::Session>,
    _subscriptions: Subscriptions,
    _node_token: zenoh::liveliness::LivelinessToken,
    rx: Receiver<Ros2Input>,
    /// What arrived while [`connect`] waited for the first trigger pulse, delivered first.
    prebuffer: VecDeque<Ros2Input>,
    schedule: TriggerSchedule,
    batch: (usize, i64),
    max_seconds: f64,
    end_after_idle: Option<Duration>,
    geometry: Geometry,
    depth_camera: CameraIntrinsics,
    describe: String,
}

/// The source thread's state while it runs.
struct Reading<'a> {
    assembler: StreamAssembler<'a>,
    decoder: Evt3Decoder,
    chunk: EventBuffer,
    clock: ClockOffset,
    /// Depth frames that came before the clock offset was known.
    waiting_depth: Vec<(i64, Box<DepthFrame>)>,
    last_seq: Option<u64>,
    stats: Ros2Stats,
    depth_camera: CameraIntrinsics,
}

impl Reading<'_> {
    fn warn_once(&mut self, kind: &str, message: &str) {
        let n = self.stats.unusable.entry(kind.to_owned()).or_insert(0);
        *n += 1;
        if *n == 1 {
            eprintln!("warning: ros2: {kind}: {message} (further ones are counted)");
        }
    }

    fn take(&mut self, item: Ros2Input, stop: &StopFlag) {
        match item {
            Ros2Input::Events {
                seq,
                stamp_ns,
                bytes,
            } => self.events(seq, stamp_ns, &bytes, stop),
            Ros2Input::Depth {
                stamp_ns,
                mut frame,
            } => {
                frame.index = self.stats.depth_images;
                self.stats.depth_images += 1;
                match self.clock.to_camera_us(stamp_ns) {
                    Some(t) => self.assembler.offer_depth(t, frame),
                    None => self.waiting_depth.push((stamp_ns, frame)),
                }
            }
            Ros2Input::Info(info) => {
                self.stats.camera_infos += 1;
                if let Some(why) = camera_info_mismatch(&info, &self.depth_camera) {
                    self.warn_once("camera_info: differs from the calibration", &why);
                }
            }
            Ros2Input::Unusable { kind, message } => self.warn_once(&kind, &message),
        }
    }

    fn events(&mut self, seq: u64, stamp_ns: i64, bytes: &[u8], stop: &StopFlag) {
        if let Some(last) = self.last_seq {
            if seq <= last {
                self.stats.packets_out_of_order += 1;
                let message = format!("packet seq {seq} after {last}: dropped");
                self.warn_once("events: out of order", &message);
                return;
            }
            if seq > last + 1 {
                let missing = seq - last - 1;
                self.stats.packets_missing += missing;
                self.decoder.resynchronise();
                let message = format!(
                    "{missing} packet(s) missing before seq {seq}: the decoder resynchronised"
                );
                self.warn_once("events: gap", &message);
            }
        }
        self.last_seq = Some(seq);
        self.stats.packets += 1;
        self.stats.bytes += bytes.len() as u64;
        self.chunk.clear();
        self.decoder.decode(bytes, &mut self.chunk);
        let first = [
            self.chunk.cd.first().map(|e| e.t_us),
            self.chunk.triggers.first().map(|e| e.t_us),
        ]
        .into_iter()
        .flatten()
        .min();
        if let Some(t) = first {
            self.clock.observe(stamp_ns, t);
            self.stats.clock_offset_ns = self.clock.offset_ns();
            for (stamp, frame) in std::mem::take(&mut self.waiting_depth) {
                if let Some(t) = self.clock.to_camera_us(stamp) {
                    self.assembler.offer_depth(t, frame);
                }
            }
        }
        self.assembler.feed(&self.chunk, stop);
    }
}

impl Source for Ros2Source {
    fn describe(&self) -> String {
        self.describe.clone()
    }

    fn run(&mut self, out: &SourceOutput, stop: &StopFlag) -> Result<SourceStats, SourceError> {
        let assembler = StreamAssembler::new(
            out,
            None,
            self.schedule,
            false,
            self.batch,
            DepthTransport::default(),
            stop,
        )
        .with_stamped_depth()
        .with_max_seconds(self.max_seconds);
        let mut r = Reading {
            assembler,
            decoder: Evt3Decoder::new(Some(self.geometry)),
            chunk: EventBuffer::new(),
            clock: ClockOffset::default(),
            waiting_depth: Vec::new(),
            last_seq: None,
            stats: Ros2Stats::default(),
            depth_camera: self.depth_camera.clone(),
        };
        let mut last_packet = Instant::now();
        let mut last_report = Instant::now();
        let mut stopped = false;
        loop {
            if last_report.elapsed() >= Duration::from_secs(1) {
                last_report = Instant::now();
                out.ros2_health(&r.stats);
            }
            if stop.is_set() {
                stopped = true;
                break;
            }
            if r.assembler.reached_end() {
                break;
            }
            let item = match self.prebuffer.pop_front() {
                Some(item) => item,
                None => match self.rx.recv_timeout(POLL) {
                    Ok(item) => item,
                    Err(RecvTimeoutError::Timeout) => {
                        if self
                            .end_after_idle
                            .is_some_and(|idle| last_packet.elapsed() >= idle)
                        {
                            break;
                        }
                        continue;
                    }
                    Err(RecvTimeoutError::Disconnected) => break,
                },
            };
            if matches!(item, Ros2Input::Events { .. }) {
                last_packet = Instant::now();
            }
            r.take(item, stop);
        }
        let mut stats = r.assembler.finish();
        stats.depth_in_transit += r.waiting_depth.len() as u64;
        stats.stopped = stopped;
        stats.set_anomalies(r.decoder.anomalies());
        out.ros2_health(&r.stats);
        stats.ros2 = Some(r.stats);
        if let Some(session) = self.session.take() {
            use zenoh::Wait;
            if let Err(e) = session.close().wait() {
                eprintln!("warning: ros2: closing the zenoh session: {e}");
            }
        }
        Ok(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runtime::queue::{Ingest, IngestQueue};
    use drivers::event::{CdEvent, TriggerEdge};
    use drivers::formats::evt3::Evt3Encoder;
    use std::sync::Arc;

    /// Two depth periods of tick pulses (every fourth one wide) with a CD event after each, as EVT3 bytes.
    fn stream(s: &TriggerSchedule) -> (Vec<u8>, Vec<i64>) {
        let period = (1e6 / s.tick_rate_hz).round() as i64;
        let (mut cd, mut edges, mut wide_rises) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..12i64 {
            let rise = 10_000 + k * period;
            let wide = k % i64::from(s.ticks_per_depth) == 0;
            let width = if wide {
                s.wide_width_us
            } else {
                s.narrow_width_us
            };
            if wide {
                wide_rises.push(rise);
            }
            edges.push(TriggerEdge {
                t_us: rise,
                channel: s.channel,
                rising: true,
            });
            edges.push(TriggerEdge {
                t_us: rise + width,
                channel: s.channel,
                rising: false,
            });
            cd.push(CdEvent {
                t_us: rise + width + 100,
                x: 5,
                y: 6,
                polarity: true,
            });
        }
        let mut bytes = Vec::new();
        Evt3Encoder::new().encode(&cd, &edges, &mut bytes).unwrap();
        (bytes, wide_rises)
    }

    #[test]
    fn gaps_reorderings_and_unusable_samples_are_counted_and_depth_lands_on_its_pulse() {
        let s = TriggerSchedule::default();
        let (bytes, wide_rises) = stream(&s);
        let queue = Arc::new(IngestQueue::new(1024, 64));
        let out = SourceOutput::new(queue.clone(), true);
        let stop = StopFlag::new();
        let assembler = StreamAssembler::new(
            &out,
            None,
            s,
            false,
            (64, 1000),
            DepthTransport::default(),
            &stop,
        )
        .with_stamped_depth();
        let depth_camera = CameraIntrinsics {
            width: 2,
            height: 1,
            fx: 1.0,
            fy: 1.0,
            cx: 0.5,
            cy: 0.5,
            distortion: Vec::new(),
        };
        let mut r = Reading {
            assembler,
            decoder: Evt3Decoder::new(None),
            chunk: EventBuffer::new(),
            clock: ClockOffset::default(),
            waiting_depth: Vec::new(),
            last_seq: None,
            stats: Ros2Stats::default(),
            depth_camera,
        };
        let offset_ns = 1_000_000_000_000i64;
        let frame = || {
            Box::new(DepthFrame {
                index: 0,
                width: 2,
                height: 1,
                depth_m: vec![1.0, 2.0],
            })
        };
        // A frame before any packet waits for the clock; it belongs to the second phase-coded pulse.
        r.take(
            Ros2Input::Depth {
                stamp_ns: offset_ns + 300_000 + wide_rises[1] * 1000 + 700_000,
                frame: frame(),
            },
            &stop,
        );
        let cut = (bytes.len() / 2) & !1;
        // The first packet arrives 0.3 ms after its first event (at 10 ms), the others much later.
        let events = |seq, part: &[u8], stamp_ns| Ros2Input::Events {
            seq,
            stamp_ns,
            bytes: part.to_vec(),
        };
        r.take(events(7, &bytes[..cut], offset_ns + 10_300_000), &stop);
        r.take(events(7, &bytes[..cut], offset_ns + 10_300_000), &stop);
        r.take(events(8, &bytes[cut..], offset_ns + 900_000_000), &stop);
        r.take(events(10, &[], offset_ns + 900_000_000), &stop);
        r.take(
            Ros2Input::Unusable {
                kind: "events: encoding".into(),
                message: "mono".into(),
            },
            &stop,
        );
        r.take(
            Ros2Input::Unusable {
                kind: "events: encoding".into(),
                message: "mono".into(),
            },
            &stop,
        );
        let stats = r.stats.clone();
        assert_eq!(
            (
                stats.packets,
                stats.packets_out_of_order,
                stats.packets_missing
            ),
            (3, 1, 1)
        );
        assert_eq!(stats.unusable.get("events: encoding"), Some(&2));
        assert_eq!(stats.unusable.get("events: out of order"), Some(&1));
        assert_eq!(stats.unusable.get("events: gap"), Some(&1));
        assert_eq!(stats.depth_images, 1);
        // The smallest delay between a packet's first event and its stamp.
        assert_eq!(stats.clock_offset_ns, Some(offset_ns + 300_000));
        let mut depth_at = Vec::new();
        let mut rising = 0;
        while let Some(item) = queue.pop(Duration::ZERO) {
            match item {
                Ingest::Depth { t_us, .. } => depth_at.push((t_us, rising)),
                Ingest::Trigger { edge, .. } if edge.rising => rising += 1,
                _ => {}
            }
        }
        // Exposed at the second phase-coded pulse's rising edge, handed over before the next pulse's.
        assert_eq!(depth_at, vec![(wide_rises[1], 5)]);
    }
}

//! The playback: the event packets in stream order, each depth frame's Image and CameraInfo put before the packet
//! whose stream time reaches the frame's exposure plus the depth latency, paced by the stream's clock or as fast as
//! zenoh takes them.

use super::exposure::{DepthSchedule, Exposure, TriggerScan};
use super::messages::{self, EventCamera, stamp};
use super::node::{Node, Topic, system_time_ns};
use super::slicer::{Packet, Slicer};
use super::{Pacer, Ros2PlayError, Ros2PlayOptions};
use drivers::formats::any::EventFormat;
use drivers::recording::{Recording, RecordingError, read_depth_png};
use ros2::Header;
use ros2::types::{CAMERA_INFO, EVENT_PACKET, IMAGE};
use std::collections::VecDeque;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::time::{Duration, Instant};

/// Bytes of `events.raw` read at a time.
const READ_BYTES: usize = 1 << 20;
/// How long the session stays open after the last message, so that the last samples leave.
const LINGER: Duration = Duration::from_millis(200);

/// What was published.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlaySummary {
    /// Event packets published.
    pub packets: u64,
    /// EVT 3.0 bytes published (all of `events.raw` after its header).
    pub bytes: u64,
    /// Depth frames published (an Image and a CameraInfo each).
    pub depth_frames: u64,
    /// Depth frames whose phase-coded pulse was missing, stamped by the schedule.
    pub depth_from_schedule: u64,
    /// Stream time covered, seconds.
    pub stream_seconds: f64,
    /// Wall time from the first message to the last, seconds.
    pub wall_seconds: f64,
    /// The stamp offset used, nanoseconds.
    pub stamp_offset_ns: i64,
}

/// A depth frame waiting for its time.
#[derive(Debug, Clone, Copy)]
struct DepthDue {
    index: u64,
    exposure: Exposure,
    due_us: i64,
}

/// Publishes the recording `options` names; see the module documentation.
pub fn play(options: &Ros2PlayOptions) -> Result<PlaySummary, Ros2PlayError> {
    let rec = Recording::open(&options.recording)?;
    let (depth, first_event_us) = depth_plan(&rec, options.depth_latency_us)?;

    let mut node = Node::open(&options.session, options.domain_id)?;
    let t = &options.topics;
    let events = node.publisher(1, &t.events, &EVENT_PACKET)?;
    let image = node.publisher(2, &t.depth_image, &IMAGE)?;
    let info = node.publisher(3, &t.camera_info, &CAMERA_INFO)?;
    if !options.wait_for_subscriber.is_zero() {
        node.wait_for_subscription(&t.events, options.wait_for_subscriber)?;
    }
    let first_ns = first_event_us.unwrap_or(0).saturating_mul(1000);
    let offset_ns = options
        .stamp_offset_ns
        .unwrap_or_else(|| system_time_ns().saturating_sub(first_ns));
    let mut player = Player {
        rec: &rec,
        options,
        camera: EventCamera {
            width: rec.rig.event_camera.width,
            height: rec.rig.event_camera.height,
        },
        offset_ns,
        topics: [events, image, info],
        depth,
        pacer: Pacer::new(options.pace),
        summary: PlaySummary {
            stamp_offset_ns: offset_ns,
            ..PlaySummary::default()
        },
        first_us: None,
        last_us: None,
        started: Instant::now(),
        next_progress: Instant::now() + Duration::from_secs(1),
    };
    stream_events(
        &rec.dir().join("events.raw"),
        rec.events_header.data_offset,
        options.slice_us,
        &mut player,
    )?;
    while let Some(d) = player.depth.pop_front() {
        player.depth_frame(d)?;
    }
    let mut summary = player.summary;
    summary.wall_seconds = player.started.elapsed().as_secs_f64();
    if let (Some(a), Some(b)) = (player.first_us, player.last_us) {
        summary.stream_seconds = (b - a) as f64 * 1e-6;
    }
    std::thread::sleep(LINGER);
    node.close()?;
    Ok(summary)
}

/// The recording's depth frames in the order they go out, each with its exposure and the stream time it is due
/// (exposure plus `latency_us`), from one pass over `events.raw`; and the stream's first event time.
fn depth_plan(
    rec: &Recording,
    latency_us: i64,
) -> Result<(VecDeque<DepthDue>, Option<i64>), Ros2PlayError> {
    let events_path = rec.dir().join("events.raw");
    if rec.events_header.format != EventFormat::Evt3 {
        return Err(RecordingError {
            path: events_path,
            problem: format!(
                "is {}; metavision_driver's packets carry EVT 3.0 (convert it with `eventtrack6d convert --format evt3`)",
                rec.events_header.format.format_name()
            ),
        }
        .into());
    }
    let mut scan = TriggerScan::new(rec.meta.trigger.channel);
    rec.events()?
        .read_all(&mut scan)
        .map_err(|e| RecordingError {
            path: events_path.clone(),
            problem: e.problem(),
        })?;
    let schedule = DepthSchedule::new(&scan, &rec.meta.trigger);
    if schedule.has_no_pulses() {
        eprintln!(
            "warning: {} has no phase-coded trigger pulse on channel {}: depth frames are stamped by the nominal \
             schedule from the first event",
            events_path.display(),
            rec.meta.trigger.channel
        );
    }
    if !messages::is_millimetres(rec.rig.depth_scale_m) {
        eprintln!(
            "warning: camera.json depth_scale_m is {} m, not millimetres: depth goes out rounded to the nearest \
             millimetre (16UC1), not bit for bit",
            rec.rig.depth_scale_m
        );
    }
    let mut depth: Vec<DepthDue> = rec
        .depth_frames
        .iter()
        .map(|&index| {
            let exposure = schedule.exposure(index);
            DepthDue {
                index,
                exposure,
                due_us: exposure.t_us.saturating_add(latency_us),
            }
        })
        .collect();
    depth.sort_by_key(|d| d.due_us);
    Ok((depth.into(), scan.first_event_us))
}

/// Reads `events.raw` from `data_offset` on, slices it and hands every packet to `player`.
fn stream_events(
    path: &Path,
    data_offset: u64,
    slice_us: i64,
    player: &mut Player<'_>,
) -> Result<(), Ros2PlayError> {
    let io = |e: std::io::Error| RecordingError {
        path: path.to_path_buf(),
        problem: e.to_string(),
    };
    let mut file = std::fs::File::open(path).map_err(io)?;
    file.seek(SeekFrom::Start(data_offset)).map_err(io)?;
    let mut slicer = Slicer::new(slice_us);
    let mut buf = vec![0u8; READ_BYTES];
    loop {
        let n = match file.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e).into()),
        };
        slicer.feed(&buf[..n], &mut |p| player.packet(p, false))?;
    }
    if let Some(p) = slicer.finish() {
        player.packet(p, true)?;
    }
    Ok(())
}

struct Player<'a> {
    rec: &'a Recording,
    options: &'a Ros2PlayOptions,
    camera: EventCamera,
    offset_ns: i64,
    /// Events, depth image, camera info.
    topics: [Topic; 3],
    depth: VecDeque<DepthDue>,
    pacer: Pacer,
    summary: PlaySummary,
    first_us: Option<i64>,
    last_us: Option<i64>,
    started: Instant,
    next_progress: Instant,
}

impl Player<'_> {
    /// Publishes the depth frames due before `p`'s end (up to and including it for the `last` packet), then `p`,
    /// stamped with its first event's time, at its end's time.
    fn packet(&mut self, p: Packet, last: bool) -> Result<(), Ros2PlayError> {
        if let Some(start) = p.start_us {
            self.pacer.until(start);
            self.first_us.get_or_insert(start);
        }
        if let Some(end) = p.end_us {
            while let Some(d) = self.depth.front().copied()
                && (d.due_us < end || (last && d.due_us == end))
            {
                self.depth.pop_front();
                self.depth_frame(d)?;
            }
            self.pacer.until(end);
            self.last_us = Some(self.last_us.map_or(end, |l| l.max(end)));
        }
        let header = Header::new(
            stamp(self.offset_ns, p.stamp_us())?,
            &self.options.topics.event_frame_id,
        );
        let msg = messages::event_packet(self.camera, header, self.summary.packets, &p.bytes);
        self.topics[0].put(msg)?;
        self.summary.packets += 1;
        self.summary.bytes += p.bytes.len() as u64;
        self.progress();
        Ok(())
    }

    /// Reads depth frame `d`, waits for its time and publishes its Image and CameraInfo.
    fn depth_frame(&mut self, d: DepthDue) -> Result<(), Ros2PlayError> {
        let path = self.rec.depth_path(d.index);
        let cam = &self.rec.rig.depth_camera;
        let (width, height, units) = read_depth_png(&path).map_err(|problem| RecordingError {
            path: path.clone(),
            problem,
        })?;
        if (width, height) != (cam.width, cam.height) {
            return Err(RecordingError {
                path,
                problem: format!(
                    "image is {width}x{height}, camera.json depth_camera is {}x{}",
                    cam.width, cam.height
                ),
            }
            .into());
        }
        let data = messages::depth_16uc1(&units, self.rec.rig.depth_scale_m);
        let header = Header::new(
            stamp(self.offset_ns, d.exposure.t_us)?,
            &self.options.topics.depth_frame_id,
        );
        self.pacer.until(d.due_us);
        self.topics[1].put(messages::depth_image(cam, header.clone(), &data))?;
        self.topics[2].put(messages::camera_info_bytes(cam, header))?;
        self.summary.depth_frames += 1;
        self.summary.depth_from_schedule += u64::from(!d.exposure.from_pulse);
        self.last_us = Some(self.last_us.map_or(d.due_us, |l| l.max(d.due_us)));
        Ok(())
    }

    fn progress(&mut self) {
        let now = Instant::now();
        if !self.options.progress || now < self.next_progress {
            return;
        }
        self.next_progress = now + Duration::from_secs(1);
        let stream = match (self.first_us, self.last_us) {
            (Some(a), Some(b)) => (b - a) as f64 * 1e-6,
            _ => 0.0,
        };
        eprintln!(
            "ros2-play: {stream:.2} s of stream, {} packets, {} depth frames",
            self.summary.packets, self.summary.depth_frames
        );
    }
}

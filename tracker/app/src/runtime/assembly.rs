//! The stream a source delivers, assembled from decoded CD events and trigger edges: events in batches, trigger
//! edges as they come, and a recording's depth frames on the trigger timeline. Each depth frame goes out when
//! the trigger edge that completes its phase-coded pulse arrives, or, when that pulse is missing from the stream,
//! at the next pulse (frames numbered by the schedule from the first phase-coded pulse, as the timeline numbers
//! depth ticks); with a depth latency, when the stream reaches its exposure plus that latency, as a live depth
//! camera's transport delivers it (if a tick pulse is open then, after the pulse's falling edge). Frames are read
//! ahead on a helper thread so PNG decoding never delays the stream. Used by the recording replay (paced by the
//! recording's clock or as fast as the tracker takes it) and by the live event camera with a recording's depth
//! (paced by the camera).

use super::source::{SourceOutput, SourceStats, StopFlag};
use drivers::event::{CdEvent, EventBuffer, TriggerEdge};
use drivers::recording::{DepthFrame, Recording, TriggerSchedule};
use std::collections::VecDeque;
use std::sync::mpsc::{Receiver, sync_channel};
use std::time::{Duration, Instant};
use tracker::track::DepthTransport;

pub(super) type DepthItem = (u64, Result<DepthFrame, String>);

/// Reads the recording's depth frames in order on a helper thread, a couple ahead of use.
pub(super) fn spawn_depth_reader(rec: &Recording, stop: StopFlag) -> Receiver<DepthItem> {
    let (tx, rx) = sync_channel::<DepthItem>(2);
    let rec = rec.clone();
    std::thread::Builder::new()
        .name("depth-reader".into())
        .spawn(move || {
            for &n in &rec.depth_frames {
                if stop.is_set() {
                    break;
                }
                let frame = rec.depth_frame(n).map_err(|e| e.to_string());
                if tx.send((n, frame)).is_err() {
                    break;
                }
            }
        })
        .map_or_else(
            |_| {
                // No thread: the stream goes on without depth (every frame counted missing).
                let (_tx, rx) = sync_channel(1);
                rx
            },
            |_| rx,
        )
}

/// Wall-clock pacing against the recording's clock.
pub(super) struct Pacer {
    realtime: bool,
    origin: Option<(i64, Instant)>,
}

impl Pacer {
    /// Waits until the wall clock reaches recording time `t_us` (real time only).
    fn until(&mut self, t_us: i64) {
        if !self.realtime {
            return;
        }
        let (t0, w0) = *self.origin.get_or_insert((t_us, Instant::now()));
        let target = w0 + Duration::from_micros(u64::try_from(t_us - t0).unwrap_or(0));
        let now = Instant::now();
        if target > now {
            std::thread::sleep(target - now);
        }
    }
}

pub(super) struct StreamAssembler<'a> {
    out: &'a SourceOutput,
    pacer: Pacer,
    batch: Vec<CdEvent>,
    batch_events: usize,
    batch_us: i64,
    channel: u8,
    wide_threshold_us: i64,
    pending_rise: Option<i64>,
    /// The latest phase-coded pulse's rising edge (camera clock, microseconds) and its depth frame: the frames
    /// after it follow every `depth_period_us`.
    depth_anchor: Option<(i64, u64)>,
    depth_period_us: f64,
    tick_period_us: f64,
    /// The next depth frame to deliver.
    next_frame: u64,
    depth: Receiver<DepthItem>,
    next_depth: Option<DepthItem>,
    depth_done: bool,
    transport: DepthTransport,
    /// Frames exposed but not yet delivered (exposure time, arrival time, frame), oldest first.
    in_transit: VecDeque<(i64, i64, Box<DepthFrame>)>,
    /// Depth from a stamped source ([`Self::offer_depth`]) instead of a recording.
    stamped_depth: bool,
    /// Stamped frames waiting for their phase-coded pulse: (time on the event camera's clock, frame).
    offered: VecDeque<(i64, Box<DepthFrame>)>,
    /// The rising edge of the latest phase-coded pulse closed (stamped depth).
    last_wide_rise: Option<i64>,
    stats: SourceStats,
    /// Stream time after which nothing more is delivered (first event plus the run's length), once known.
    end_us: Option<i64>,
    /// The run's length in stream time, microseconds (0: unlimited).
    limit_us: i64,
    /// Whether the stream reached `end_us`.
    reached_end: bool,
}

impl StreamAssembler<'_> {
    /// At the falling edge of the tick pulse that rose at `rise` (phase-coded or not): the depth frames exposed up
    /// to that pulse go out first, so the tracker has each before the tick the timeline makes of its exposure.
    /// A phase-coded pulse's frame number follows from the previous phase-coded pulse's and the number of depth
    /// periods between them (as the timeline re-locks its schedule), so the count stays right when a phase-coded
    /// pulse is missing, and the trigger clock's drift against the nominal rate never adds up. The frame of a
    /// missing phase-coded pulse goes out at the first pulse after its time, stamped by that schedule.
    fn expose_depth_until(&mut self, rise: i64, wide: bool) {
        if self.stamped_depth {
            self.match_offered(rise, wide);
            return;
        }
        let half_tick = (self.tick_period_us * 0.5) as i64;
        if wide {
            let n = match self.depth_anchor {
                None => 0,
                Some((at, n)) => {
                    let periods = ((rise - at) as f64 / self.depth_period_us).round().max(1.0);
                    n + periods as u64
                }
            };
            while self.next_frame < n {
                let k = self.next_frame;
                let exposed = self.scheduled_exposure(k).unwrap_or(rise);
                self.send_depth(k, exposed);
            }
            if self.next_frame == n {
                self.send_depth(n, rise);
            }
            self.depth_anchor = Some((rise, n));
        } else {
            while let Some(due) = self.scheduled_exposure(self.next_frame)
                && due <= rise + half_tick
            {
                self.send_depth(self.next_frame, due);
            }
        }
    }

    /// Stamped depth at the falling edge of the pulse that rose at `rise`: frames stamped more than half a depth
    /// period before it (their pulse is missing) go out at their own time; at a phase-coded pulse, the frame
    /// stamped within half a depth period of it goes out exposed at its rising edge.
    fn match_offered(&mut self, rise: i64, wide: bool) {
        let half = (self.depth_period_us * 0.5) as i64;
        while let Some((t, _)) = self.offered.front()
            && *t < rise - half
            && let Some((t, frame)) = self.offered.pop_front()
        {
            self.stats.depth_missing += 1;
            self.deliver_offered(t, frame);
        }
        if wide {
            if let Some((t, _)) = self.offered.front()
                && (*t - rise).abs() <= half
                && let Some((_, frame)) = self.offered.pop_front()
            {
                self.deliver_offered(rise, frame);
            }
            self.last_wide_rise = Some(rise);
        }
    }

    fn deliver_offered(&mut self, exposed: i64, frame: Box<DepthFrame>) {
        self.stats.depth_frames += 1;
        self.out.depth(exposed, frame);
    }

    /// A depth frame from a stamped source (ROS 2), exposed at `t_us` on the event camera's clock as far as its
    /// stamp tells: it goes out exposed at the rising edge of its phase-coded pulse, at that pulse's falling edge,
    /// or at once if that pulse has passed (a late frame, which the tracker tracks again from).
    pub(super) fn offer_depth(&mut self, t_us: i64, frame: Box<DepthFrame>) {
        let half = (self.depth_period_us * 0.5) as i64;
        match self.last_wide_rise {
            Some(r) if t_us <= r + half => {
                self.flush();
                let exposed = if (t_us - r).abs() <= half { r } else { t_us };
                self.deliver_offered(exposed, frame);
            }
            _ => {
                let at = self.offered.partition_point(|(t, _)| *t <= t_us);
                self.offered.insert(at, (t_us, frame));
            }
        }
    }

    /// When frame `k` is exposed by the schedule from the latest phase-coded pulse (`None` before the first).
    fn scheduled_exposure(&self, k: u64) -> Option<i64> {
        let (at, n) = self.depth_anchor?;
        Some(at + ((k as f64 - n as f64) * self.depth_period_us).round() as i64)
    }

    /// Sends depth frame `k`, exposed at `exposed` (or puts it in transit), and moves on to the next frame.
    fn send_depth(&mut self, k: u64, exposed: i64) {
        self.next_frame = k + 1;
        match self.depth_frame(k) {
            Some(frame) if !self.transport.is_immediate() => {
                let arrives = self.transport.due_us(exposed);
                self.in_transit
                    .push_back((exposed, arrives, Box::new(frame)));
            }
            Some(frame) => {
                self.stats.depth_frames += 1;
                self.out.depth(exposed, Box::new(frame));
            }
            None => self.stats.depth_missing += 1,
        }
    }

    /// Delivers the event batch being filled.
    pub(super) fn flush(&mut self) {
        if let Some(last) = self.batch.last() {
            self.pacer.until(last.t_us);
            let full = std::mem::replace(&mut self.batch, self.out.buffer());
            self.out.events(full);
        }
    }

    /// Delivers the frames in transit that are due by stream time `t_us`.
    fn deliver_due(&mut self, t_us: i64) {
        if self.in_transit.front().is_none_or(|f| t_us < f.1) {
            return;
        }
        self.flush();
        while self.in_transit.front().is_some_and(|f| t_us >= f.1)
            && let Some((exposed_us, due_us, frame)) = self.in_transit.pop_front()
        {
            self.pacer.until(due_us);
            self.stats.depth_frames += 1;
            self.out.depth(exposed_us, frame);
        }
    }

    fn cd(&mut self, e: CdEvent) {
        // A frame due inside an open tick pulse waits for its falling edge: the tick that pulse makes was
        // stamped before the frame was due, and the offline driver hands the frame over after it too.
        if self.pending_rise.is_none() {
            self.deliver_due(e.t_us);
        }
        if let Some(first) = self.batch.first()
            && (self.batch.len() >= self.batch_events || e.t_us - first.t_us >= self.batch_us)
        {
            self.flush();
        }
        self.batch.push(e);
        self.stats.events += 1;
    }

    /// The depth frame numbered `n`, if the recording has it (frames are read in order).
    fn depth_frame(&mut self, n: u64) -> Option<DepthFrame> {
        loop {
            if self.next_depth.is_none() && !self.depth_done {
                match self.depth.recv() {
                    Ok(item) => self.next_depth = Some(item),
                    Err(_) => self.depth_done = true,
                }
            }
            match self.next_depth.take() {
                None => return None,
                Some((k, _)) if k < n => continue,
                Some((k, frame)) if k == n => return frame.ok(),
                Some(later) => {
                    self.next_depth = Some(later);
                    return None;
                }
            }
        }
    }

    fn trigger(&mut self, edge: TriggerEdge) {
        self.flush();
        let tick_channel = edge.channel == self.channel;
        // A rising edge on the tick channel also ends a pulse whose falling edge was lost.
        if (tick_channel && edge.rising) || self.pending_rise.is_none() {
            self.deliver_due(edge.t_us);
        }
        self.pacer.until(edge.t_us);
        self.stats.trigger_edges += 1;
        let mut closed = false;
        if tick_channel {
            if edge.rising {
                self.pending_rise = Some(edge.t_us);
            } else if let Some(rise) = self.pending_rise.take() {
                closed = true;
                let wide = edge.t_us - rise >= self.wide_threshold_us;
                self.expose_depth_until(rise, wide);
            }
        }
        self.out.trigger(edge);
        if closed {
            // Frames that fell due while the pulse was open, after the tick it makes.
            self.deliver_due(edge.t_us);
        }
    }
}

impl<'a> StreamAssembler<'a> {
    /// An assembler delivering into `out`, with `recording`'s depth frames on `schedule`'s timeline; `realtime`
    /// paces the delivery by the stream's clock (a replay), otherwise it goes as fast as the input comes.
    pub(super) fn new(
        out: &'a SourceOutput,
        recording: Option<&Recording>,
        schedule: TriggerSchedule,
        realtime: bool,
        batch: (usize, i64),
        transport: DepthTransport,
        stop: &StopFlag,
    ) -> Self {
        let depth = match recording {
            Some(rec) => spawn_depth_reader(rec, stop.clone()),
            None => sync_channel(1).1,
        };
        Self {
            out,
            pacer: Pacer {
                realtime,
                origin: None,
            },
            batch: out.buffer(),
            batch_events: batch.0.max(1),
            batch_us: batch.1.max(1),
            channel: schedule.channel,
            wide_threshold_us: (schedule.narrow_width_us + schedule.wide_width_us) / 2,
            pending_rise: None,
            depth_anchor: None,
            depth_period_us: f64::from(schedule.ticks_per_depth) * 1e6 / schedule.tick_rate_hz,
            tick_period_us: 1e6 / schedule.tick_rate_hz,
            next_frame: 0,
            depth,
            next_depth: None,
            depth_done: false,
            transport,
            in_transit: VecDeque::with_capacity(16),
            stamped_depth: false,
            offered: VecDeque::new(),
            last_wide_rise: None,
            stats: SourceStats::default(),
            end_us: None,
            limit_us: 0,
            reached_end: false,
        }
    }

    /// The same assembler taking its depth frames from [`Self::offer_depth`] (a stamped source) rather than a
    /// recording.
    pub(super) fn with_stamped_depth(mut self) -> Self {
        self.stamped_depth = true;
        self
    }

    /// The same assembler delivering only the first `seconds` of stream time (0: all of it).
    pub(super) fn with_max_seconds(mut self, seconds: f64) -> Self {
        self.limit_us = (seconds * 1e6).round() as i64;
        self
    }

    /// Whether the stream passed the run's length: the source should end.
    pub(super) fn reached_end(&self) -> bool {
        self.reached_end
    }

    /// Whether a record at `t_us` lies past the run's length (and, if so, notes that the end is reached).
    fn past_end(&mut self, t_us: i64) -> bool {
        if self.limit_us <= 0 {
            return false;
        }
        let end = *self.end_us.get_or_insert(t_us + self.limit_us);
        if t_us > end {
            self.reached_end = true;
        }
        self.reached_end
    }

    /// Delivers a decoded chunk: its CD events and trigger edges merged by time (edges first at equal times).
    /// Returns early, with the rest of the chunk undelivered, when `stop` is set.
    pub(super) fn feed(&mut self, chunk: &EventBuffer, stop: &StopFlag) {
        let (mut i, mut j) = (0, 0);
        while i < chunk.cd.len() || j < chunk.triggers.len() {
            let take_edge = match (chunk.cd.get(i), chunk.triggers.get(j)) {
                (Some(c), Some(t)) => t.t_us <= c.t_us,
                (None, Some(_)) => true,
                _ => false,
            };
            let t_us = if take_edge {
                chunk.triggers[j].t_us
            } else {
                chunk.cd[i].t_us
            };
            if self.past_end(t_us) {
                return;
            }
            if take_edge {
                self.trigger(chunk.triggers[j]);
                j += 1;
                if stop.is_set() {
                    return;
                }
            } else {
                self.cd(chunk.cd[i]);
                i += 1;
            }
        }
    }

    /// Ends the stream: the last batch goes out; returns what was delivered (frames still in transit counted).
    pub(super) fn finish(mut self) -> SourceStats {
        self.flush();
        self.stats.depth_in_transit = (self.in_transit.len() + self.offered.len()) as u64;
        self.stats
    }
}

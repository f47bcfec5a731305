//! One pass over an event file: counts, time span, trigger edges, anomalies and the trigger timeline.

use crate::anomaly::DecodeAnomalies;
use crate::event::{CdEvent, EventCounter, EventSink, TriggerEdge};
use crate::formats::any::EventFormat;
use crate::raw::{RawFileError, RawReader};
use crate::timeline::{TimelineConfig, TimelineCounters, TriggerTimeline};
use std::collections::BTreeMap;
use std::path::Path;

/// What `eventtrack6d inspect` reports about a `.raw` stream.
#[derive(Debug, Clone)]
pub struct StreamSummary {
    /// Stream encoding.
    pub format: EventFormat,
    /// Sensor width, if the header gives or implies it.
    pub width: Option<u16>,
    /// Sensor height, if the header gives or implies it.
    pub height: Option<u16>,
    /// Header `% key value` fields in file order.
    pub header: Vec<(String, String)>,
    /// Bytes of event data (header excluded).
    pub data_bytes: u64,
    /// CD event and trigger counts and time span.
    pub counts: EventCounter,
    /// Skipped words by kind.
    pub anomalies: DecodeAnomalies,
    /// Trigger timeline on the configured channel, if that channel has edges.
    pub timeline: Option<TimelineSummary>,
}

/// The trigger timeline's view of a stream.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimelineSummary {
    /// Ticks produced (including bridged ones).
    pub ticks: u64,
    /// Ticks that are depth exposures.
    pub depth_exposures: u64,
    /// Estimated tick period at the end of the stream, microseconds.
    pub period_us: f64,
    /// Irregularities found.
    pub counters: TimelineCounters,
}

struct SummarySink {
    counter: EventCounter,
    timeline: TriggerTimeline,
    ticks: u64,
    depth_exposures: u64,
}

impl SummarySink {
    fn drain(&mut self) {
        while let Some(t) = self.timeline.pop_tick() {
            self.ticks += 1;
            self.depth_exposures += u64::from(t.depth_frame.is_some());
        }
    }
}

impl EventSink for SummarySink {
    #[inline]
    fn cd(&mut self, event: CdEvent) {
        self.counter.cd(event);
    }

    #[inline]
    fn cd_vector(&mut self, t_us: i64, y: u16, x_base: u16, mask: u32, polarity: bool) {
        self.counter.cd_vector(t_us, y, x_base, mask, polarity);
    }

    fn trigger(&mut self, edge: TriggerEdge) {
        self.counter.trigger(edge);
        self.timeline.push(edge);
        self.drain();
    }
}

/// Reads a `.raw` file once, in constant memory. `progress` is called after each chunk with
/// `(bytes done, total bytes)`.
pub fn summarize_raw(
    path: &Path,
    timeline: TimelineConfig,
    mut progress: impl FnMut(u64, u64),
) -> Result<StreamSummary, RawFileError> {
    let total = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    let mut reader = RawReader::open(path)?;
    let mut sink = SummarySink {
        counter: EventCounter::new(),
        timeline: TriggerTimeline::new(timeline),
        ticks: 0,
        depth_exposures: 0,
    };
    while reader.read_chunk(&mut sink)? {
        progress(reader.bytes_read() + reader.header().data_offset, total);
    }
    sink.timeline.finish();
    sink.drain();
    let h = reader.header();
    let has_edges = sink.counter.trigger_edges[usize::from(timeline.channel & 31)] != [0, 0];
    Ok(StreamSummary {
        format: h.format,
        width: h.geometry.map(|g| g.width),
        height: h.geometry.map(|g| g.height),
        header: h.fields.clone(),
        data_bytes: reader.bytes_read(),
        anomalies: *reader.anomalies(),
        timeline: has_edges.then(|| TimelineSummary {
            ticks: sink.ticks,
            depth_exposures: sink.depth_exposures,
            period_us: sink.timeline.period_us(),
            counters: *sink.timeline.counters(),
        }),
        counts: sink.counter,
    })
}

impl StreamSummary {
    /// Trigger edges per channel that saw any: `channel -> (rising, falling)`.
    pub fn trigger_edges(&self) -> BTreeMap<u8, (u64, u64)> {
        self.counts
            .trigger_edges
            .iter()
            .enumerate()
            .filter(|(_, c)| c[0] + c[1] > 0)
            .map(|(ch, c)| (ch as u8, (c[0], c[1])))
            .collect()
    }
}

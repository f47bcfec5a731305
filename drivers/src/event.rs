//! Decoded event-camera records: contrast-detection events and trigger edges.

/// One contrast-detection (CD) event on the event camera's pixel grid.
///
/// `t_us` is on the event camera's clock in microseconds (the master timeline). `polarity` is `true`
/// for an ON event (log intensity increased by one contrast threshold), `false` for OFF.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CdEvent {
    /// Timestamp in microseconds on the event camera's clock.
    pub t_us: i64,
    /// Column, 0 at the left edge.
    pub x: u16,
    /// Row, 0 at the top edge.
    pub y: u16,
    /// `true` for ON (brighter), `false` for OFF (darker).
    pub polarity: bool,
}

/// An edge seen on an external trigger input (EVT `EXT_TRIGGER` word).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct TriggerEdge {
    /// Timestamp in microseconds on the event camera's clock.
    pub t_us: i64,
    /// Trigger input channel (EVT3 carries 4 bits, EVT2 5 bits).
    pub channel: u8,
    /// `true` for a rising edge, `false` for a falling edge.
    pub rising: bool,
}

/// Receiver of decoded records. Decoders call it in stream order.
pub trait EventSink {
    /// One CD event.
    fn cd(&mut self, event: CdEvent);

    /// A group of CD events sharing a row, time and polarity: bit `i` of `mask` set means an event at
    /// column `x_base + i`. Decoders only pass columns that passed the geometry check. Sinks that only
    /// count may override this to avoid expanding the mask.
    #[inline]
    fn cd_vector(&mut self, t_us: i64, y: u16, x_base: u16, mask: u32, polarity: bool) {
        let mut m = mask;
        while m != 0 {
            let i = m.trailing_zeros() as u16;
            m &= m - 1;
            self.cd(CdEvent {
                t_us,
                x: x_base + i,
                y,
                polarity,
            });
        }
    }

    /// One trigger edge.
    fn trigger(&mut self, edge: TriggerEdge);
}

/// A sink that keeps everything it receives, in order.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct EventBuffer {
    /// CD events in stream order.
    pub cd: Vec<CdEvent>,
    /// Trigger edges in stream order.
    pub triggers: Vec<TriggerEdge>,
}

impl EventBuffer {
    /// Empty buffer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Removes all records, keeping the allocations.
    pub fn clear(&mut self) {
        self.cd.clear();
        self.triggers.clear();
    }
}

impl EventSink for EventBuffer {
    #[inline]
    fn cd(&mut self, event: CdEvent) {
        self.cd.push(event);
    }

    #[inline]
    fn trigger(&mut self, edge: TriggerEdge) {
        self.triggers.push(edge);
    }
}

/// A sink that only counts and tracks the time span; memory does not grow with stream length.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EventCounter {
    /// Number of ON events.
    pub positive: u64,
    /// Number of OFF events.
    pub negative: u64,
    /// Trigger edges per channel: `[rising, falling]` counts, index = channel (0..32).
    pub trigger_edges: [[u64; 2]; 32],
    /// Earliest timestamp seen, `i64::MAX` before any record.
    t_min: i64,
    /// Latest timestamp seen, `i64::MIN` before any record.
    t_max: i64,
}

impl Default for EventCounter {
    fn default() -> Self {
        Self {
            positive: 0,
            negative: 0,
            trigger_edges: [[0; 2]; 32],
            t_min: i64::MAX,
            t_max: i64::MIN,
        }
    }
}

impl EventCounter {
    /// Empty counter.
    pub fn new() -> Self {
        Self::default()
    }

    /// Total CD events.
    pub fn cd_events(&self) -> u64 {
        self.positive + self.negative
    }

    /// Earliest timestamp seen (CD or trigger), microseconds.
    pub fn t_first_us(&self) -> Option<i64> {
        (self.t_min <= self.t_max).then_some(self.t_min)
    }

    /// Latest timestamp seen (CD or trigger), microseconds.
    pub fn t_last_us(&self) -> Option<i64> {
        (self.t_min <= self.t_max).then_some(self.t_max)
    }

    #[inline]
    fn see(&mut self, t: i64) {
        self.t_min = self.t_min.min(t);
        self.t_max = self.t_max.max(t);
    }
}

impl EventSink for EventCounter {
    #[inline]
    fn cd(&mut self, event: CdEvent) {
        if event.polarity {
            self.positive += 1;
        } else {
            self.negative += 1;
        }
        self.see(event.t_us);
    }

    #[inline]
    fn cd_vector(&mut self, t_us: i64, _y: u16, _x_base: u16, mask: u32, polarity: bool) {
        if mask == 0 {
            return;
        }
        let n = u64::from(mask.count_ones());
        if polarity {
            self.positive += n;
        } else {
            self.negative += n;
        }
        self.see(t_us);
    }

    #[inline]
    fn trigger(&mut self, edge: TriggerEdge) {
        let ch = usize::from(edge.channel & 31);
        self.trigger_edges[ch][usize::from(!edge.rising)] += 1;
        self.see(edge.t_us);
    }
}

/// Sensor pixel-array size. Events outside it are counted as anomalies and skipped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Geometry {
    /// Columns.
    pub width: u16,
    /// Rows.
    pub height: u16,
}

impl Geometry {
    /// A `width` x `height` sensor.
    pub const fn new(width: u16, height: u16) -> Self {
        Self { width, height }
    }
}

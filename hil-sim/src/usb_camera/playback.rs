//! What the emulated camera streams on its data endpoint: a recording's EVT 3.0 bytes, in chunks stamped with
//! the stream time they reach, released at the recording's pace (real time) or as fast as the host reads, with
//! the trigger words taken out while the sensor's trigger input is off, and the stream faults injected.

use drivers::event::EventCounter;
use drivers::formats::any::EventFormat;
use drivers::formats::evt3::Evt3Decoder;
use drivers::raw::RawHeader;
use std::io::BufReader;
use std::path::Path;
use std::time::{Duration, Instant};

/// Bytes per chunk of the stream (a multiple of the 2-byte EVT 3.0 word).
const CHUNK_BYTES: usize = 16 * 1024;
/// EVT 3.0 word type of an external trigger edge.
const EXT_TRIGGER: u16 = 0xA;

/// A recording's event stream, cut into chunks.
#[derive(Debug)]
pub struct EventStream {
    bytes: Vec<u8>,
    /// Chunk `k` is `bytes[k * CHUNK_BYTES ..]` up to the next; its stream time at its end, microseconds.
    chunk_end_us: Vec<i64>,
}

/// Why a recording cannot be streamed.
#[derive(Debug, thiserror::Error)]
pub enum PlaybackError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The error.
        source: std::io::Error,
    },
    /// The header is unreadable.
    #[error("{path}: {problem}")]
    Header {
        /// The file.
        path: String,
        /// What is wrong.
        problem: String,
    },
    /// The camera streams EVT 3.0 only.
    #[error(
        "{path} is {format}; an EVK4 streams EVT 3.0 (convert it with `eventtrack6d convert --format evt3`)"
    )]
    Format {
        /// The file.
        path: String,
        /// Its format.
        format: &'static str,
    },
}

impl EventStream {
    /// The stream of `events.raw` at `path`.
    pub fn open(path: &Path) -> Result<Self, PlaybackError> {
        let name = path.display().to_string();
        let io = |source| PlaybackError::Io {
            path: name.clone(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let header =
            RawHeader::read(&mut BufReader::new(file)).map_err(|e| PlaybackError::Header {
                path: name.clone(),
                problem: e.to_string(),
            })?;
        if header.format != EventFormat::Evt3 {
            return Err(PlaybackError::Format {
                path: name,
                format: header.format.format_name(),
            });
        }
        let all = std::fs::read(path).map_err(io)?;
        let start = usize::try_from(header.data_offset)
            .unwrap_or(all.len())
            .min(all.len());
        Ok(Self::from_bytes(all[start..].to_vec()))
    }

    /// A stream of raw EVT 3.0 bytes.
    pub fn from_bytes(mut bytes: Vec<u8>) -> Self {
        bytes.truncate(bytes.len() & !1);
        let mut decoder = Evt3Decoder::new(None);
        let mut sink = EventCounter::new();
        let chunk_end_us = bytes
            .chunks(CHUNK_BYTES)
            .map(|c| {
                decoder.decode(c, &mut sink);
                decoder.current_time_us()
            })
            .collect();
        Self {
            bytes,
            chunk_end_us,
        }
    }

    /// Total bytes.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether the stream has no bytes.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Stream time at the end, microseconds.
    pub fn end_us(&self) -> i64 {
        self.chunk_end_us.last().copied().unwrap_or(0)
    }

    /// How many bytes from `from` are released once the stream has played for `elapsed` (stream time since its
    /// first chunk's end), up to `max` bytes.
    fn released(&self, from: usize, elapsed_us: i64, max: usize) -> usize {
        let t0 = self.chunk_end_us.first().copied().unwrap_or(0);
        let chunks = self.chunk_end_us.partition_point(|&t| t - t0 <= elapsed_us);
        let limit = (chunks * CHUNK_BYTES).min(self.bytes.len());
        limit.saturating_sub(from).min(max)
    }
}

/// The stream's pace.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pace {
    /// At the recording's own pace from the sensor's start.
    Realtime,
    /// As fast as the host reads.
    Fast,
}

/// Stream faults injected on the data endpoint.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StreamFaults {
    /// Once, after this long of streaming, hold the data back for `stall_ms` (the host's requests wait).
    pub stall_after: Option<Duration>,
    /// Length of the stall.
    pub stall: Duration,
    /// Once, after this long of streaming, release this many bytes at once regardless of pace (more than the link
    /// carries in that time: the host's ring overflows if it is smaller).
    pub burst_after: Option<Duration>,
    /// Bytes of the burst.
    pub burst_bytes: usize,
    /// Replace every this-many-th word with a word of a reserved type (0 = never).
    pub malformed_every: usize,
}

/// The data endpoint's state across one sensor start.
#[derive(Debug)]
pub struct Playback {
    /// Next byte to send.
    position: usize,
    pace: Pace,
    started: Option<Instant>,
    faults: StreamFaults,
    burst_done: bool,
    /// The stream is released up to this byte regardless of pace (a burst).
    burst_until: usize,
    words_sent: u64,
    /// Bytes sent to the host so far.
    pub bytes_sent: u64,
    /// Trigger words taken out because the trigger input was off.
    pub triggers_removed: u64,
    /// Words replaced by malformed ones.
    pub malformed_sent: u64,
}

impl Playback {
    /// A playback from the start of the stream.
    pub fn new(pace: Pace, faults: StreamFaults) -> Self {
        Self {
            position: 0,
            pace,
            started: None,
            faults,
            burst_done: false,
            burst_until: 0,
            words_sent: 0,
            bytes_sent: 0,
            triggers_removed: 0,
            malformed_sent: 0,
        }
    }

    /// Whether every byte was sent.
    pub fn finished(&self, stream: &EventStream) -> bool {
        self.position >= stream.len()
    }

    /// Marks the sensor's start (the pace counts from here); a restart continues where the stream was.
    pub fn start(&mut self, now: Instant) {
        self.started.get_or_insert(now);
    }

    /// The next bytes for a bulk-IN request of `max` bytes, or `None` when none are due yet.
    pub fn next(
        &mut self,
        stream: &EventStream,
        max: usize,
        trigger_input: bool,
        now: Instant,
    ) -> Option<Vec<u8>> {
        let started = self.started?;
        let playing = now.saturating_duration_since(started);
        if let Some(at) = self.faults.stall_after
            && playing >= at
            && playing < at + self.faults.stall
        {
            return None;
        }
        let max = max & !1;
        let mut n = match self.pace {
            Pace::Fast => stream.len().saturating_sub(self.position).min(max),
            Pace::Realtime => {
                let elapsed = i64::try_from(playing.as_micros()).unwrap_or(i64::MAX);
                stream.released(self.position, elapsed, max)
            }
        };
        if let Some(at) = self.faults.burst_after
            && !self.burst_done
            && playing >= at
        {
            self.burst_done = true;
            self.burst_until = (self.position + self.faults.burst_bytes).min(stream.len()) & !1;
        }
        if self.burst_until > self.position {
            n = n.max((self.burst_until - self.position).min(max));
        }
        if n == 0 {
            return None;
        }
        let mut out = Vec::with_capacity(n);
        for w in stream.bytes[self.position..self.position + n].chunks_exact(2) {
            let word = u16::from_le_bytes([w[0], w[1]]);
            self.words_sent += 1;
            if !trigger_input && word >> 12 == EXT_TRIGGER {
                self.triggers_removed += 1;
                continue;
            }
            if self.faults.malformed_every > 0
                && self
                    .words_sent
                    .is_multiple_of(self.faults.malformed_every as u64)
            {
                // Type 0x1 is reserved in EVT 3.0: a decoder skips and counts it.
                out.extend_from_slice(&0x1000u16.to_le_bytes());
                self.malformed_sent += 1;
                continue;
            }
            out.extend_from_slice(w);
        }
        self.position += n;
        self.bytes_sent += out.len() as u64;
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use drivers::event::{CdEvent, EventBuffer, TriggerEdge};
    use drivers::formats::evt3::Evt3Encoder;

    fn stream() -> EventStream {
        let cd: Vec<CdEvent> = (0..20_000)
            .map(|i| CdEvent {
                t_us: i64::from(i) * 50,
                x: (i % 1000) as u16,
                y: 7,
                polarity: i % 2 == 0,
            })
            .collect();
        let triggers: Vec<TriggerEdge> = (0..100)
            .map(|i| TriggerEdge {
                t_us: i * 8_333,
                channel: 0,
                rising: i % 2 == 0,
            })
            .collect();
        let mut bytes = Vec::new();
        Evt3Encoder::new()
            .encode(&cd, &triggers, &mut bytes)
            .unwrap();
        EventStream::from_bytes(bytes)
    }

    fn decode(bytes: &[u8]) -> EventBuffer {
        let mut d = Evt3Decoder::new(None);
        let mut b = EventBuffer::new();
        d.decode(bytes, &mut b);
        b
    }

    #[test]
    fn fast_playback_sends_the_recording_and_real_time_holds_it_back() {
        let s = stream();
        let t0 = Instant::now();
        let mut fast = Playback::new(Pace::Fast, StreamFaults::default());
        assert!(
            fast.next(&s, 1 << 20, true, t0).is_none(),
            "nothing before the sensor starts"
        );
        fast.start(t0);
        let mut all = Vec::new();
        while let Some(b) = fast.next(&s, 4096, true, t0) {
            all.extend(b);
        }
        assert_eq!(all, s.bytes);
        let mut rt = Playback::new(Pace::Realtime, StreamFaults::default());
        rt.start(t0);
        let first = rt.next(&s, 1 << 20, true, t0).map_or(0, |b| b.len());
        assert!(
            first < s.len() / 2,
            "{first} of {} bytes released at once",
            s.len()
        );
        let later = rt
            .next(&s, 1 << 20, true, t0 + Duration::from_secs(2))
            .unwrap();
        assert_eq!(first + later.len(), s.len());
    }

    #[test]
    fn triggers_are_only_sent_with_the_trigger_input_on_and_malformed_words_are_counted() {
        let s = stream();
        let t0 = Instant::now();
        let mut off = Playback::new(Pace::Fast, StreamFaults::default());
        off.start(t0);
        let b = off.next(&s, 1 << 22, false, t0).unwrap();
        assert_eq!(decode(&b).triggers.len(), 0);
        assert_eq!(off.triggers_removed, 100);
        assert_eq!(decode(&s.bytes).triggers.len(), 100);
        let faults = StreamFaults {
            malformed_every: 100,
            ..Default::default()
        };
        let mut bad = Playback::new(Pace::Fast, faults);
        bad.start(t0);
        let b = bad.next(&s, 1 << 22, true, t0).unwrap();
        let mut d = Evt3Decoder::new(None);
        d.decode(&b, &mut EventBuffer::new());
        assert_eq!(
            d.anomalies()
                .get(drivers::anomaly::AnomalyKind::UnknownType),
            bad.malformed_sent
        );
        assert!(bad.malformed_sent > 0);
    }
}

//! Event-camera stream formats: streaming decoders that accept bytes in arbitrary chunks, and encoders.
//!
//! Every decoder follows the same contract: [`decode`](evt3::Evt3Decoder::decode) may be called with any
//! split of the stream (a chunk boundary may fall inside a word or a word group); records are delivered to an
//! [`EventSink`](crate::event::EventSink) in stream order; nothing panics on any input; every skipped word is
//! counted in [`DecodeAnomalies`](crate::anomaly::DecodeAnomalies). Call `finish` at the end of the stream so
//! a trailing partial word is counted.

pub mod any;
pub mod csv;
pub mod evt2;
pub mod evt21;
pub mod evt3;

use thiserror::Error;

/// Why an encoder refused its input.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum EncodeError {
    /// The format cannot carry this coordinate.
    #[error("event at ({x}, {y}) does not fit the format's {bits}-bit coordinates")]
    CoordinateTooLarge {
        /// Column.
        x: u16,
        /// Row.
        y: u16,
        /// Coordinate width of the format.
        bits: u32,
    },
    /// Timestamps must be non-negative.
    #[error("timestamp {t_us} us is negative")]
    NegativeTime {
        /// The offending timestamp.
        t_us: i64,
    },
    /// The stream's time base can only move forwards.
    #[error("timestamp went back from {from_us} us to {to_us} us across a time-high boundary")]
    TimeWentBack {
        /// Previous timestamp.
        from_us: i64,
        /// Offending timestamp.
        to_us: i64,
    },
    /// The format cannot carry this trigger channel.
    #[error("trigger channel {channel} does not fit the format (max {max})")]
    ChannelTooLarge {
        /// The offending channel.
        channel: u8,
        /// Largest channel the format carries.
        max: u8,
    },
}

/// Merges two time-ordered record streams, yielding triggers before CD events at equal time, keeping each
/// stream's own order.
pub(crate) fn merge_by_time<'a>(
    cd: &'a [crate::event::CdEvent],
    triggers: &'a [crate::event::TriggerEdge],
) -> impl Iterator<Item = Record<'a>> + 'a {
    let mut i = 0;
    let mut j = 0;
    std::iter::from_fn(move || {
        let take_trigger = match (cd.get(i), triggers.get(j)) {
            (None, None) => return None,
            (Some(_), None) => false,
            (None, Some(_)) => true,
            (Some(c), Some(t)) => t.t_us <= c.t_us,
        };
        if take_trigger {
            j += 1;
            Some(Record::Trigger(&triggers[j - 1]))
        } else {
            // Hand out the run of CD events that follows, up to the next trigger's time.
            let limit = triggers.get(j).map_or(i64::MAX, |t| t.t_us);
            let start = i;
            while i < cd.len() && (i == start || cd[i].t_us < limit) {
                i += 1;
            }
            Some(Record::Cd(&cd[start..i]))
        }
    })
}

/// A merged record for encoders.
pub(crate) enum Record<'a> {
    Cd(&'a [crate::event::CdEvent]),
    Trigger(&'a crate::event::TriggerEdge),
}

/// Reassembles fixed-size words from byte chunks split anywhere (USB transfers cut words and word groups).
#[derive(Debug, Clone)]
pub(crate) struct WordAssembler<const N: usize> {
    partial: [u8; N],
    len: usize,
}

impl<const N: usize> Default for WordAssembler<N> {
    fn default() -> Self {
        Self {
            partial: [0; N],
            len: 0,
        }
    }
}

impl<const N: usize> WordAssembler<N> {
    /// Calls `word` with every complete word of `bytes` (after any bytes held back from the previous chunk), in
    /// stream order, and holds back a trailing partial word.
    #[inline(always)]
    pub(crate) fn feed(&mut self, bytes: &[u8], mut word: impl FnMut([u8; N])) {
        let mut bytes = bytes;
        if self.len > 0 {
            let take = (N - self.len).min(bytes.len());
            self.partial[self.len..self.len + take].copy_from_slice(&bytes[..take]);
            self.len += take;
            bytes = &bytes[take..];
            if self.len < N {
                return;
            }
            self.len = 0;
            word(self.partial);
        }
        let mut words = bytes.chunks_exact(N);
        for w in &mut words {
            let mut a = [0u8; N];
            a.copy_from_slice(w);
            word(a);
        }
        let rest = words.remainder();
        self.partial[..rest.len()].copy_from_slice(rest);
        self.len = rest.len();
    }

    /// Ends the stream: `true` if a partial word was left over (and is dropped).
    pub(crate) fn finish(&mut self) -> bool {
        std::mem::take(&mut self.len) > 0
    }
}

/// The time-high counter an encoder has emitted, and the TIME_HIGH words needed to reach a new time so that the
/// decoder's wrap rule (a drop of at least half the counter's range is a wrap) recovers absolute time.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TimeHighSteps {
    /// Time bits below the counter (12 for EVT3, 6 for EVT2 / EVT2.1).
    shift: u32,
    /// Counter range (2^12 for EVT3, 2^28 for EVT2 / EVT2.1).
    range: i64,
    /// Absolute counter value (`t >> shift`) last emitted.
    high: Option<i64>,
    last_t: i64,
}

impl TimeHighSteps {
    pub(crate) const fn new(shift: u32, range: i64) -> Self {
        Self {
            shift,
            range,
            high: None,
            last_t: 0,
        }
    }

    /// Moves to time `t`, calling `emit` with each counter value (already masked to the range) to write as a
    /// TIME_HIGH word. Returns whether the counter changed. Time may not go back across a counter step.
    pub(crate) fn advance(
        &mut self,
        t: i64,
        mut emit: impl FnMut(i64),
    ) -> Result<bool, EncodeError> {
        if t < 0 {
            return Err(EncodeError::NegativeTime { t_us: t });
        }
        let target = t >> self.shift;
        let changed = match self.high {
            Some(h) if target < h => {
                return Err(EncodeError::TimeWentBack {
                    from_us: self.last_t,
                    to_us: t,
                });
            }
            Some(h) if target == h => false,
            _ => {
                let mut cur = match self.high {
                    Some(h) => h,
                    None => {
                        // The decoder starts its wrap count at zero on the first TIME_HIGH.
                        let first = target.min(self.range - 1);
                        emit(first);
                        first
                    }
                };
                // Steps shorter than half the range keep every wrap detectable.
                while cur < target {
                    cur = (cur + self.range / 2 - 1).min(target);
                    emit(cur & (self.range - 1));
                }
                self.high = Some(target);
                true
            }
        };
        self.last_t = t;
        Ok(changed)
    }
}

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

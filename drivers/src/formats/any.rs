//! Runtime choice between the supported event formats.

use super::EncodeError;
use super::evt2::{Evt2Decoder, Evt2Encoder};
use super::evt3::{Evt3Decoder, Evt3Encoder};
use super::evt21::{Evt21Decoder, Evt21Encoder, WordOrder};
use crate::anomaly::DecodeAnomalies;
use crate::event::{CdEvent, EventSink, Geometry, TriggerEdge};
use std::fmt;

/// An event-camera stream encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EventFormat {
    /// EVT 3.0 (16-bit words).
    Evt3,
    /// EVT 2.0 (32-bit words).
    Evt2,
    /// EVT 2.1 (64-bit words) in the given byte order.
    Evt21(WordOrder),
}

impl EventFormat {
    /// The `evt` header value (`3.0`, `2.0`, `2.1`).
    pub fn evt_version(self) -> &'static str {
        match self {
            EventFormat::Evt3 => "3.0",
            EventFormat::Evt2 => "2.0",
            EventFormat::Evt21(_) => "2.1",
        }
    }

    /// The name used in the `format` header line (`EVT3`, `EVT2`, `EVT21`).
    pub fn format_name(self) -> &'static str {
        match self {
            EventFormat::Evt3 => "EVT3",
            EventFormat::Evt2 => "EVT2",
            EventFormat::Evt21(_) => "EVT21",
        }
    }

    /// Bytes per word.
    pub fn word_bytes(self) -> usize {
        match self {
            EventFormat::Evt3 => 2,
            EventFormat::Evt2 => 4,
            EventFormat::Evt21(_) => 8,
        }
    }
}

impl fmt::Display for EventFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EventFormat::Evt21(WordOrder::Legacy) => f.write_str("EVT21 (legacy word order)"),
            other => f.write_str(other.format_name()),
        }
    }
}

/// A decoder for any [`EventFormat`].
#[derive(Debug, Clone)]
pub enum AnyDecoder {
    /// EVT 3.0.
    Evt3(Evt3Decoder),
    /// EVT 2.0.
    Evt2(Evt2Decoder),
    /// EVT 2.1.
    Evt21(Evt21Decoder),
}

impl AnyDecoder {
    /// A decoder for `format`, bounds-checking against `geometry` when given.
    pub fn new(format: EventFormat, geometry: Option<Geometry>) -> Self {
        match format {
            EventFormat::Evt3 => AnyDecoder::Evt3(Evt3Decoder::new(geometry)),
            EventFormat::Evt2 => AnyDecoder::Evt2(Evt2Decoder::new(geometry)),
            EventFormat::Evt21(order) => AnyDecoder::Evt21(Evt21Decoder::new(order, geometry)),
        }
    }

    /// Decodes the next chunk.
    pub fn decode<S: EventSink>(&mut self, bytes: &[u8], sink: &mut S) {
        match self {
            AnyDecoder::Evt3(d) => d.decode(bytes, sink),
            AnyDecoder::Evt2(d) => d.decode(bytes, sink),
            AnyDecoder::Evt21(d) => d.decode(bytes, sink),
        }
    }

    /// Ends the stream (counts a trailing partial word).
    pub fn finish(&mut self) {
        match self {
            AnyDecoder::Evt3(d) => d.finish(),
            AnyDecoder::Evt2(d) => d.finish(),
            AnyDecoder::Evt21(d) => d.finish(),
        }
    }

    /// Counters of skipped words so far.
    pub fn anomalies(&self) -> &DecodeAnomalies {
        match self {
            AnyDecoder::Evt3(d) => d.anomalies(),
            AnyDecoder::Evt2(d) => d.anomalies(),
            AnyDecoder::Evt21(d) => d.anomalies(),
        }
    }
}

/// An encoder for any [`EventFormat`].
#[derive(Debug, Clone)]
pub enum AnyEncoder {
    /// EVT 3.0.
    Evt3(Evt3Encoder),
    /// EVT 2.0.
    Evt2(Evt2Encoder),
    /// EVT 2.1.
    Evt21(Evt21Encoder),
}

impl AnyEncoder {
    /// A fresh encoder for `format`.
    pub fn new(format: EventFormat) -> Self {
        match format {
            EventFormat::Evt3 => AnyEncoder::Evt3(Evt3Encoder::new()),
            EventFormat::Evt2 => AnyEncoder::Evt2(Evt2Encoder::new()),
            EventFormat::Evt21(order) => AnyEncoder::Evt21(Evt21Encoder::new(order)),
        }
    }

    /// Encodes time-ordered records, appending to `out`.
    pub fn encode(
        &mut self,
        cd: &[CdEvent],
        triggers: &[TriggerEdge],
        out: &mut Vec<u8>,
    ) -> Result<(), EncodeError> {
        match self {
            AnyEncoder::Evt3(e) => e.encode(cd, triggers, out),
            AnyEncoder::Evt2(e) => e.encode(cd, triggers, out),
            AnyEncoder::Evt21(e) => e.encode(cd, triggers, out),
        }
    }
}

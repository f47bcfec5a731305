//! `.raw` writer: header, then encoded records appended batch by batch.

use super::header::RawHeader;
use crate::event::{CdEvent, TriggerEdge};
use crate::formats::EncodeError;
use crate::formats::any::AnyEncoder;
use std::io::{self, Write};

/// Writes a `.raw` stream; records must be given in time order across calls.
pub struct RawWriter<W: Write> {
    out: W,
    encoder: AnyEncoder,
    buf: Vec<u8>,
}

/// Why a write failed.
#[derive(Debug, thiserror::Error)]
pub enum RawWriteError {
    /// The output failed.
    #[error(transparent)]
    Io(#[from] io::Error),
    /// The records cannot be encoded.
    #[error(transparent)]
    Encode(#[from] EncodeError),
}

impl<W: Write> RawWriter<W> {
    /// Writes `header` to `out` and prepares the matching encoder.
    pub fn new(mut out: W, header: &RawHeader) -> io::Result<Self> {
        header.write(&mut out)?;
        Ok(Self {
            out,
            encoder: AnyEncoder::new(header.format),
            buf: Vec::with_capacity(1 << 16),
        })
    }

    /// Encodes and writes one batch of time-ordered records.
    pub fn write(&mut self, cd: &[CdEvent], triggers: &[TriggerEdge]) -> Result<(), RawWriteError> {
        self.buf.clear();
        self.encoder.encode(cd, triggers, &mut self.buf)?;
        self.out.write_all(&self.buf)?;
        Ok(())
    }

    /// Flushes and returns the output.
    pub fn finish(mut self) -> io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

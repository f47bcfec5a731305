//! Streaming `.raw` reader: memory stays constant whatever the file length.

use super::header::{HeaderError, RawHeader};
use crate::anomaly::DecodeAnomalies;
use crate::event::EventSink;
use crate::formats::any::AnyDecoder;
use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Bytes handed to the decoder per read: the size of one EVK4 bulk transfer.
pub const CHUNK_BYTES: usize = 128 * 1024;

/// A `.raw` file that cannot be opened or read, naming the file.
#[derive(Debug, Error)]
pub enum RawFileError {
    /// Opening or reading failed.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        error: io::Error,
    },
    /// The header is malformed.
    #[error("{path}: {error}")]
    Header {
        /// The file.
        path: PathBuf,
        /// What is wrong with the header.
        error: HeaderError,
    },
}

impl RawFileError {
    /// What is wrong, without the file's name (for a message that names the file already).
    pub fn problem(&self) -> String {
        match self {
            Self::Io { error, .. } => error.to_string(),
            Self::Header { error, .. } => error.to_string(),
        }
    }
}

/// Reads a `.raw` file chunk by chunk through the decoder its header names.
pub struct RawReader<R: Read> {
    path: PathBuf,
    header: RawHeader,
    input: BufReader<R>,
    decoder: AnyDecoder,
    buf: Vec<u8>,
    bytes_read: u64,
    done: bool,
}

impl RawReader<File> {
    /// Opens `path` and parses its header.
    pub fn open(path: &Path) -> Result<Self, RawFileError> {
        let file = File::open(path).map_err(|error| RawFileError::Io {
            path: path.into(),
            error,
        })?;
        Self::new(file, path)
    }
}

impl<R: Read> RawReader<R> {
    /// Reads the header from `input`; `path` is only used in error messages.
    pub fn new(input: R, path: &Path) -> Result<Self, RawFileError> {
        let mut input = BufReader::with_capacity(64 * 1024, input);
        let header = RawHeader::read(&mut input).map_err(|error| RawFileError::Header {
            path: path.into(),
            error,
        })?;
        let decoder = AnyDecoder::new(header.format, header.geometry);
        Ok(Self {
            path: path.into(),
            header,
            input,
            decoder,
            buf: vec![0; CHUNK_BYTES],
            bytes_read: 0,
            done: false,
        })
    }

    /// The parsed header.
    pub fn header(&self) -> &RawHeader {
        &self.header
    }

    /// Counters of skipped words so far (final after [`read_all`](Self::read_all) or the last chunk).
    pub fn anomalies(&self) -> &DecodeAnomalies {
        self.decoder.anomalies()
    }

    /// Event-stream bytes consumed so far (header excluded).
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read
    }

    /// Decodes up to one chunk into `sink`. Returns `false` once the stream has ended.
    pub fn read_chunk<S: EventSink>(&mut self, sink: &mut S) -> Result<bool, RawFileError> {
        if self.done {
            return Ok(false);
        }
        let n = loop {
            match self.input.read(&mut self.buf) {
                Ok(n) => break n,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(error) => {
                    return Err(RawFileError::Io {
                        path: self.path.clone(),
                        error,
                    });
                }
            }
        };
        if n == 0 {
            self.decoder.finish();
            self.done = true;
            return Ok(false);
        }
        self.bytes_read += n as u64;
        self.decoder.decode(&self.buf[..n], sink);
        Ok(true)
    }

    /// Decodes the rest of the file into `sink`.
    pub fn read_all<S: EventSink>(&mut self, sink: &mut S) -> Result<(), RawFileError> {
        while self.read_chunk(sink)? {}
        Ok(())
    }
}

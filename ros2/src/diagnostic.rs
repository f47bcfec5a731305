//! `diagnostic_msgs/msg/DiagnosticArray`: the tracking state as ROS 2 nodes read it, one status per object.

use crate::CdrError;
use crate::header::Header;
use crate::wire::{CdrReader, CdrWriter};

/// `DiagnosticStatus.level` values.
pub mod level {
    /// Working as it should.
    pub const OK: u8 = 0;
    /// Working, but worse.
    pub const WARN: u8 = 1;
    /// Not working.
    pub const ERROR: u8 = 2;
    /// No recent information.
    pub const STALE: u8 = 3;
}

/// A `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagnosticStatus {
    /// `level` ([`level`]).
    pub level: u8,
    /// `name`: what is described.
    pub name: String,
    /// `message`: its state in words.
    pub message: String,
    /// `hardware_id`.
    pub hardware_id: String,
    /// `values`: key/value pairs.
    pub values: Vec<(String, String)>,
}

/// A `diagnostic_msgs/msg/DiagnosticArray`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagnosticArray {
    /// `header`.
    pub header: Header,
    /// `status`.
    pub status: Vec<DiagnosticStatus>,
}

/// Encodes a `diagnostic_msgs/msg/DiagnosticArray` into `out` (cleared first).
pub fn encode_diagnostic_array(out: &mut Vec<u8>, msg: &DiagnosticArray) {
    let mut w = CdrWriter::new(out);
    msg.header.write(&mut w);
    w.count(msg.status.len());
    for s in &msg.status {
        w.u8(s.level);
        w.string(&s.name);
        w.string(&s.message);
        w.string(&s.hardware_id);
        w.count(s.values.len());
        for (k, v) in &s.values {
            w.string(k);
            w.string(v);
        }
    }
}

/// Decodes a `diagnostic_msgs/msg/DiagnosticArray`. Never panics.
pub fn decode_diagnostic_array(bytes: &[u8]) -> Result<DiagnosticArray, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let header = Header::read(&mut r)?;
    // Smallest status: level 1, three strings 3 x 5 (aligned), values count 4.
    let n = r.count("status", 1 + 15 + 4)?;
    let mut status = Vec::with_capacity(n);
    for _ in 0..n {
        let level = r.u8("status.level")?;
        let name = r.string("status.name")?;
        let message = r.string("status.message")?;
        let hardware_id = r.string("status.hardware_id")?;
        let k = r.count("status.values", 10)?;
        let mut values = Vec::with_capacity(k);
        for _ in 0..k {
            values.push((r.string("values.key")?, r.string("values.value")?));
        }
        status.push(DiagnosticStatus {
            level,
            name,
            message,
            hardware_id,
            values,
        });
    }
    Ok(DiagnosticArray { header, status })
}

//! `std_srvs/srv/Trigger`: a request with no fields and a response with `success` and `message`.

use crate::CdrError;
use crate::wire::{CdrReader, CdrWriter};

/// A `std_srvs/srv/Trigger_Response`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TriggerResponse {
    /// `success`: whether the request was carried out.
    pub success: bool,
    /// `message`: what was done, or why not.
    pub message: String,
}

/// Encodes a `std_srvs/srv/Trigger_Request` (its one placeholder byte, 0) into `out`.
pub fn encode_trigger_request(out: &mut Vec<u8>) {
    let mut w = CdrWriter::new(out);
    w.u8(0);
}

/// Checks a `std_srvs/srv/Trigger_Request`: the encapsulation header; the placeholder byte may be absent (some
/// clients send the header alone) and its value is ignored.
pub fn decode_trigger_request(bytes: &[u8]) -> Result<(), CdrError> {
    CdrReader::new(bytes).map(|_| ())
}

/// Encodes a `std_srvs/srv/Trigger_Response` into `out` (cleared first).
pub fn encode_trigger_response(out: &mut Vec<u8>, m: &TriggerResponse) {
    let mut w = CdrWriter::new(out);
    w.bool(m.success);
    w.string(&m.message);
}

/// Decodes a `std_srvs/srv/Trigger_Response`. Never panics.
pub fn decode_trigger_response(bytes: &[u8]) -> Result<TriggerResponse, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    Ok(TriggerResponse {
        success: r.bool("success")?,
        message: r.string("message")?,
    })
}

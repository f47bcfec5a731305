#![no_main]
//! Fuzz every USB/IP decoder with the bytes a host (or anyone on the port) may send: errors, never panics; what
//! decodes encodes to bytes that decode to the same message.

use libfuzzer_sys::fuzz_target;
use usbip::protocol::{OpReply, OpRequest, UrbMessage};

fuzz_target!(|data: &[u8]| {
    if let Ok((request, _)) = OpRequest::decode(data) {
        assert_eq!(OpRequest::decode(&request.encode()).map(|r| r.0), Ok(request));
    }
    if let Ok((reply, _)) = OpReply::decode(data) {
        assert_eq!(OpReply::decode(&reply.encode()).map(|r| r.0), Ok(reply));
    }
    if let Ok(message) = UrbMessage::decode_header(data) {
        assert_eq!(UrbMessage::decode_header(&message.encode_header()), Ok(message));
    }
});

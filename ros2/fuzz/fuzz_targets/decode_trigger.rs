#![no_main]
//! Fuzz the `std_srvs/srv/Trigger` request check and response decoder (the reset service): no panic on any input;
//! a response that decodes re-encodes to bytes that decode to the same response, and the request the crate
//! encodes passes the request check.

mod common;

use libfuzzer_sys::fuzz_target;
use ros2::trigger::{
    decode_trigger_request, decode_trigger_response, encode_trigger_request,
    encode_trigger_response,
};

fuzz_target!(|data: &[u8]| {
    if decode_trigger_request(data).is_ok() {
        // Only the encapsulation header is checked (the placeholder byte may be absent).
        assert!(data.len() >= 4);
        let mut out = Vec::new();
        encode_trigger_request(&mut out);
        assert_eq!(decode_trigger_request(&out), Ok(()));
    }
    if let Ok(msg) = decode_trigger_response(data) {
        let mut out = Vec::new();
        encode_trigger_response(&mut out, &msg);
        let again = decode_trigger_response(&out);
        common::check(
            data,
            &msg,
            &out,
            again,
            encode_trigger_response,
            common::no_floats,
        );
    }
});

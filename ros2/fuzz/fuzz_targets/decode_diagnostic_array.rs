#![no_main]
//! Fuzz the CDR `diagnostic_msgs/msg/DiagnosticArray` decoder: no panic on any input, and whatever decodes
//! re-encodes to bytes that decode to the same statuses.

mod common;

use libfuzzer_sys::fuzz_target;
use ros2::diagnostic::{decode_diagnostic_array, encode_diagnostic_array};

fuzz_target!(|data: &[u8]| {
    if let Ok(msg) = decode_diagnostic_array(data) {
        let mut out = Vec::new();
        encode_diagnostic_array(&mut out, &msg);
        let again = decode_diagnostic_array(&out);
        common::check(
            data,
            &msg,
            &out,
            again,
            encode_diagnostic_array,
            common::no_floats,
        );
    }
});

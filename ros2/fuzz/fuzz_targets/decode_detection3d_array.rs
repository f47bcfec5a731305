#![no_main]
//! Fuzz the CDR `vision_msgs/msg/Detection3DArray` decoder: no panic on any input, and whatever decodes re-encodes
//! to bytes that decode to the same detections (bit for bit, NaNs included).

mod common;

use libfuzzer_sys::fuzz_target;
use ros2::vision::{decode_detection3d_array, encode_detection3d_array};

fuzz_target!(|data: &[u8]| {
    if let Ok(msg) = decode_detection3d_array(data) {
        let mut out = Vec::new();
        encode_detection3d_array(&mut out, &msg);
        let again = decode_detection3d_array(&out);
        common::check(
            data,
            &msg,
            &out,
            again,
            encode_detection3d_array,
            common::detection3d_array_floats,
        );
    }
});

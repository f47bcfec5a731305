#![no_main]
//! Fuzz the CDR `tf2_msgs/msg/TFMessage` decoder: no panic on any input, and whatever decodes re-encodes to bytes
//! that decode to the same transforms (bit for bit, NaNs included).

mod common;

use libfuzzer_sys::fuzz_target;
use ros2::tf::{TransformStamped, decode_tf_message, encode_tf_message};

fn encode(out: &mut Vec<u8>, m: &Vec<TransformStamped>) {
    encode_tf_message(out, m);
}

fuzz_target!(|data: &[u8]| {
    if let Ok(msg) = decode_tf_message(data) {
        let mut out = Vec::new();
        encode(&mut out, &msg);
        common::check(
            data,
            &msg,
            &out,
            decode_tf_message(&out),
            encode,
            common::tf_floats,
        );
    }
});

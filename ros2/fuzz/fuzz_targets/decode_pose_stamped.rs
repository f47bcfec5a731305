#![no_main]
//! Fuzz the CDR `geometry_msgs/msg/PoseStamped` decoder (what the tracker reads to re-seed an object): no panic on
//! any input, and whatever decodes re-encodes to bytes that decode to the same message (bit for bit, NaNs included).

mod common;

use libfuzzer_sys::fuzz_target;
use ros2::{PoseStampedMsg, decode_pose_stamped, encode_pose_stamped};

fn encode(out: &mut Vec<u8>, m: &PoseStampedMsg) {
    encode_pose_stamped(out, m.stamp, &m.frame_id, m.position, m.orientation_xyzw);
}

fuzz_target!(|data: &[u8]| {
    if let Ok(msg) = decode_pose_stamped(data) {
        let mut out = Vec::new();
        encode(&mut out, &msg);
        common::check(
            data,
            &msg,
            &out,
            decode_pose_stamped(&out),
            encode,
            common::pose_stamped_floats,
        );
    }
});

#![no_main]
//! Fuzz the CDR `geometry_msgs/msg/PoseStamped` decoder and the rmw_zenoh attachment parser: no panic on any
//! input, and whatever decodes re-encodes to bytes that decode to the same message (bit for bit, NaNs included).

use libfuzzer_sys::fuzz_target;

fn bits(msg: &ros2::PoseStampedMsg) -> (ros2::RosTime, &str, [u64; 7]) {
    let p = msg.position;
    let q = msg.orientation_xyzw;
    let v = [p[0], p[1], p[2], q[0], q[1], q[2], q[3]].map(f64::to_bits);
    (msg.stamp, msg.frame_id.as_str(), v)
}

fuzz_target!(|data: &[u8]| {
    if let Ok(a) = ros2::Attachment::from_bytes(data) {
        assert_eq!(a.to_bytes().as_slice(), data);
    }
    let Ok(msg) = ros2::decode_pose_stamped(data) else {
        return;
    };
    let mut out = Vec::new();
    ros2::encode_pose_stamped(&mut out, msg.stamp, &msg.frame_id, msg.position, msg.orientation_xyzw);
    assert!(out.len() <= data.len(), "the canonical encoding is never longer than what decoded");
    let again = ros2::decode_pose_stamped(&out).expect("a re-encoded message decodes");
    assert_eq!(bits(&again), bits(&msg));
});

#![no_main]
//! Fuzz the decoders of what the vendors' ROS 2 drivers publish, `event_camera_msgs/msg/EventPacket`,
//! `sensor_msgs/msg/Image` and `sensor_msgs/msg/CameraInfo`, each on every input (the first two share their
//! layout up to `encoding`): no panic, and whatever decodes re-encodes to bytes that decode to the same message
//! (bit for bit, NaNs included).

mod common;

use libfuzzer_sys::fuzz_target;
use ros2::sensor::{
    decode_camera_info, decode_event_packet, decode_image, encode_camera_info, encode_event_packet,
    encode_image,
};

fuzz_target!(|data: &[u8]| {
    if let Ok(msg) = decode_event_packet(data) {
        let mut out = Vec::new();
        encode_event_packet(&mut out, &msg);
        let again = decode_event_packet(&out);
        common::check(
            data,
            &msg,
            &out,
            again,
            encode_event_packet,
            common::no_floats,
        );
    }
    if let Ok(msg) = decode_image(data) {
        let mut out = Vec::new();
        encode_image(&mut out, &msg);
        let again = decode_image(&out);
        common::check(data, &msg, &out, again, encode_image, common::no_floats);
    }
    if let Ok(msg) = decode_camera_info(data) {
        let mut out = Vec::new();
        encode_camera_info(&mut out, &msg);
        let again = decode_camera_info(&out);
        common::check(
            data,
            &msg,
            &out,
            again,
            encode_camera_info,
            common::camera_info_floats,
        );
    }
});

//! `tf2_msgs/msg/TFMessage`: a list of `geometry_msgs/msg/TransformStamped`, what `/tf` carries.

use crate::CdrError;
use crate::header::Header;
use crate::wire::{CdrReader, CdrWriter};

/// A `geometry_msgs/msg/TransformStamped`: the pose of `child_frame_id` in `header.frame_id`.
#[derive(Debug, Clone, PartialEq)]
pub struct TransformStamped {
    /// Time and parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// `transform.translation` x, y, z, metres.
    pub translation: [f64; 3],
    /// `transform.rotation` x, y, z, w.
    pub rotation_xyzw: [f64; 4],
}

/// Smallest CDR size of one TransformStamped (empty strings): stamp 8, two strings 2 x 5, seven `f64` 56.
const MIN_TRANSFORM_BYTES: usize = 8 + 10 + 56;

/// Encodes a `tf2_msgs/msg/TFMessage` (`transforms`) into `out` (cleared first).
pub fn encode_tf_message(out: &mut Vec<u8>, transforms: &[TransformStamped]) {
    let mut w = CdrWriter::new(out);
    w.count(transforms.len());
    for t in transforms {
        t.header.write(&mut w);
        w.string(&t.child_frame_id);
        w.f64s(&t.translation);
        w.f64s(&t.rotation_xyzw);
    }
}

/// Decodes a `tf2_msgs/msg/TFMessage`. Never panics.
pub fn decode_tf_message(bytes: &[u8]) -> Result<Vec<TransformStamped>, CdrError> {
    let mut r = CdrReader::new(bytes)?;
    let n = r.count("transforms", MIN_TRANSFORM_BYTES)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        out.push(TransformStamped {
            header: Header::read(&mut r)?,
            child_frame_id: r.string("child_frame_id")?,
            translation: r.f64s("transform.translation")?,
            rotation_xyzw: r.f64s("transform.rotation")?,
        });
    }
    Ok(out)
}

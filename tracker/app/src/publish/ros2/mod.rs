//! ROS 2 wire conventions for publishing poses through zenoh so that ROS 2 nodes running `rmw_zenoh_cpp` receive
//! them unchanged. Pure functions, no zenoh: the [`super::zenoh`] sink uses them, tests and receivers decode with them.
//!
//! - [`encode_pose_stamped`] / [`decode_pose_stamped`]: `geometry_msgs/msg/PoseStamped` in plain CDR, little-endian
//!   (encapsulation header `00 01 00 00`; alignment counted from the first byte after that header).
//! - [`pose_stamped_key_expr`]: the zenoh key expression rmw_zenoh derives for a topic,
//!   `<domain>/<topic without leading/trailing '/'>/<type name>/<type hash>`.
//! - [`Attachment`]: the 33 bytes rmw_zenoh attaches to every sample (sequence number, source timestamp, GID);
//!   rmw_zenoh subscribers drop samples without it.
//! - [`node_liveliness_key_expr`] / [`publisher_liveliness_key_expr`]: the liveliness tokens through which the
//!   ROS 2 graph (`ros2 node list`, `ros2 topic list`) discovers a node and its publishers.
//!
//! Layouts follow rmw_zenoh_cpp's `attachment_helpers.cpp`, `liveliness_utils.cpp`, `rmw_node_data.cpp`,
//! `rmw_publisher_data.cpp` and `qos.cpp` (see `docs/zenoh-ros2.md`).

mod cdr;
mod graph;

#[cfg(test)]
mod tests;

pub use cdr::{
    PoseStampedMsg, RosTime, decode_pose_stamped, encode_pose_stamped,
    encode_pose_stamped_isometry, pose_fields, pose_stamped_encoded_len,
};
pub use graph::{
    Attachment, RosNodeIdentity, check_name_path, check_name_token, fully_qualified_topic,
    mangle_name, node_liveliness_key_expr, pose_stamped_key_expr, publisher_liveliness_key_expr,
    topic_key_expr,
};

/// ROS 2 type name of `geometry_msgs/msg/PoseStamped` as rmw_zenoh writes it into key expressions.
pub const POSE_STAMPED_TYPE_NAME: &str = "geometry_msgs::msg::dds_::PoseStamped_";

/// RIHS01 type hash of `geometry_msgs/msg/PoseStamped` (ROS 2 Jazzy and later), as rmw_zenoh writes it into keys.
pub const POSE_STAMPED_TYPE_HASH: &str =
    "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8";

/// CDR encapsulation header for little-endian plain CDR (`CDR_LE`, options 0).
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Size in bytes of rmw_zenoh's sample attachment.
pub const ATTACHMENT_LEN: usize = 33;

/// Size in bytes of a ROS 2 GID as rmw_zenoh stores it (`RMW_GID_STORAGE_SIZE`).
pub const GID_LEN: usize = 16;

/// Admin-space prefix of rmw_zenoh's liveliness tokens.
pub const LIVELINESS_ADMIN_SPACE: &str = "@ros2_lv";

/// QoS component of a liveliness token when every policy equals rmw_zenoh's default (reliable, volatile,
/// keep-last with depth 42, infinite deadline / lifespan / lease, automatic liveliness): each field is left empty.
pub const DEFAULT_QOS_KEY: &str = "::,:,:,:,,";

/// Bytes of a CDR-encoded PoseStamped after its frame id: 7 `f64` (position x, y, z; orientation x, y, z, w).
const POSE_BYTES: usize = 7 * 8;

/// Why bytes are not a valid CDR `PoseStamped` or rmw_zenoh attachment.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CdrError {
    /// The input ended before a field was complete.
    #[error("truncated: {field} needs {needed} bytes at offset {offset}, but the input has {len}")]
    Truncated {
        /// Field being read.
        field: &'static str,
        /// Byte offset (from the start of the input, header included) where the field starts.
        offset: usize,
        /// Bytes the field needs.
        needed: usize,
        /// Total input length.
        len: usize,
    },
    /// The encapsulation header is not little-endian plain CDR.
    #[error(
        "unsupported CDR encapsulation {0:02x?} (expected 00 01 00 00, little-endian plain CDR)"
    )]
    Encapsulation([u8; 4]),
    /// A string length of 0 (CDR strings count their terminating NUL, so the minimum is 1).
    #[error("frame_id: string length is 0 (CDR string lengths include the terminating NUL)")]
    ZeroLengthString,
    /// A string's last byte is not NUL.
    #[error("frame_id: string is not NUL-terminated")]
    MissingNul,
    /// A string contains bytes that are not UTF-8.
    #[error("frame_id: string is not valid UTF-8")]
    NotUtf8,
    /// A timestamp that does not fit ROS 2's `builtin_interfaces/Time` (`int32` seconds).
    #[error("time {nanos} ns is outside the range of builtin_interfaces/Time (int32 seconds)")]
    TimeOutOfRange {
        /// The time, nanoseconds.
        nanos: i128,
    },
    /// An attachment of the wrong size.
    #[error("attachment: {len} bytes, expected {ATTACHMENT_LEN}")]
    AttachmentLength {
        /// Length received.
        len: usize,
    },
    /// An attachment whose GID length prefix is not 16.
    #[error("attachment: GID length prefix is {0:#04x}, expected 0x10 (16 bytes)")]
    AttachmentGidLength(u8),
}

//! ROS 2 wire formats as rmw_zenoh carries them, so that this project's zenoh sessions talk to ROS 2 nodes
//! running `rmw_zenoh_cpp` with no bridge. Pure functions and types, no zenoh, no I/O; the application's sink and
//! ROS 2 source and the simulator's `ros2-play` use them. Depends on nothing of this workspace.
//!
//! - [`wire`]: plain little-endian CDR ([`CdrWriter`], [`CdrReader`]).
//! - Messages: [`encode_pose_stamped`] / [`decode_pose_stamped`] (`geometry_msgs/msg/PoseStamped`), [`tf`]
//!   (`tf2_msgs/msg/TFMessage`), [`vision`] (`vision_msgs/msg/Detection3DArray`), [`diagnostic`]
//!   (`diagnostic_msgs/msg/DiagnosticArray`), [`sensor`] (`event_camera_msgs/msg/EventPacket`,
//!   `sensor_msgs/msg/Image`, `sensor_msgs/msg/CameraInfo`), [`trigger`] (`std_srvs/srv/Trigger`).
//! - [`types`]: each type's key-expression name and RIHS01 hash.
//! - [`graph`]: the key expression of a topic or service, [`Attachment`] (the 33 bytes rmw_zenoh attaches to
//!   every sample, request and reply; its subscribers drop samples without it), and the liveliness tokens
//!   through which the ROS 2 graph (`ros2 node list`, `ros2 topic list`, `ros2 service list`) discovers a node and
//!   its entities.
//!
//! Layouts follow rmw_zenoh_cpp's `attachment_helpers.cpp`, `liveliness_utils.cpp`, `rmw_node_data.cpp`,
//! `rmw_publisher_data.cpp`, `rmw_service_data.cpp` and `qos.cpp` (see `docs/zenoh-ros2.md`).

pub mod diagnostic;
mod error;
pub mod graph;
mod header;
mod pose_stamped;
pub mod sensor;
pub mod tf;
pub mod trigger;
pub mod types;
pub mod vision;
pub mod wire;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_messages;

pub use error::CdrError;
pub use graph::{
    Attachment, EntityKind, RosNodeIdentity, check_name_path, check_name_token,
    entity_liveliness_key_expr, fully_qualified_topic, mangle_name, node_liveliness_key_expr,
    pose_stamped_key_expr, publisher_liveliness_key_expr, topic_key_expr, typed_key_expr,
};
pub use header::{Header, Pose, RosTime, pose_fields};
pub use pose_stamped::{
    PoseStampedMsg, decode_pose_stamped, encode_pose_stamped, encode_pose_stamped_isometry,
    pose_stamped_encoded_len,
};
pub use types::RosType;
pub use wire::{CdrReader, CdrWriter};

/// ROS 2 type name of `geometry_msgs/msg/PoseStamped` as rmw_zenoh writes it into key expressions.
pub const POSE_STAMPED_TYPE_NAME: &str = types::POSE_STAMPED.key_name;

/// RIHS01 type hash of `geometry_msgs/msg/PoseStamped` (ROS 2 Jazzy and later), as rmw_zenoh writes it into keys.
pub const POSE_STAMPED_TYPE_HASH: &str = types::POSE_STAMPED.hash;

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

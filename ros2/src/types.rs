//! The ROS 2 interface types this project speaks, each with the name rmw_zenoh writes into key expressions and
//! its RIHS01 type hash (ROS 2 Jazzy; Kilted has the same). The hashes are checked against an independent
//! computation (the `rosbags` Python package) by `tests/tests/ros2_interop.rs`.

/// A ROS 2 interface type on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RosType {
    /// The ROS name, `package/msg/Type` or `package/srv/Type`.
    pub name: &'static str,
    /// The DDS-style name rmw_zenoh puts into key expressions, `package::msg::dds_::Type_`.
    pub key_name: &'static str,
    /// RIHS01 type hash, `RIHS01_<64 hex digits>`.
    pub hash: &'static str,
}

/// `geometry_msgs/msg/PoseStamped`.
pub const POSE_STAMPED: RosType = RosType {
    name: "geometry_msgs/msg/PoseStamped",
    key_name: "geometry_msgs::msg::dds_::PoseStamped_",
    hash: "RIHS01_10f3786d7d40fd2b54367835614bff85d4ad3b5dab62bf8bca0cc232d73b4cd8",
};

/// `tf2_msgs/msg/TFMessage`.
pub const TF_MESSAGE: RosType = RosType {
    name: "tf2_msgs/msg/TFMessage",
    key_name: "tf2_msgs::msg::dds_::TFMessage_",
    hash: "RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087",
};

/// `vision_msgs/msg/Detection3DArray` (vision_msgs 4.x).
pub const DETECTION3D_ARRAY: RosType = RosType {
    name: "vision_msgs/msg/Detection3DArray",
    key_name: "vision_msgs::msg::dds_::Detection3DArray_",
    hash: "RIHS01_793f5eab9595ac1c0da07873cc859db42eae51f0ee76056db8562515d830e018",
};

/// `diagnostic_msgs/msg/DiagnosticArray`.
pub const DIAGNOSTIC_ARRAY: RosType = RosType {
    name: "diagnostic_msgs/msg/DiagnosticArray",
    key_name: "diagnostic_msgs::msg::dds_::DiagnosticArray_",
    hash: "RIHS01_5a8a36efb05fb25070fa0fb3810290c0e6cd4862b54a8fb975a1ee8dc55a333e",
};

/// `event_camera_msgs/msg/EventPacket` (ros-event-camera).
pub const EVENT_PACKET: RosType = RosType {
    name: "event_camera_msgs/msg/EventPacket",
    key_name: "event_camera_msgs::msg::dds_::EventPacket_",
    hash: "RIHS01_d6fa176260b1f37e5a40845305315e150a0f18191241eb64f407442aa29844aa",
};

/// `sensor_msgs/msg/Image`.
pub const IMAGE: RosType = RosType {
    name: "sensor_msgs/msg/Image",
    key_name: "sensor_msgs::msg::dds_::Image_",
    hash: "RIHS01_d31d41a9a4c4bc8eae9be757b0beed306564f7526c88ea6a4588fb9582527d47",
};

/// `sensor_msgs/msg/CameraInfo`.
pub const CAMERA_INFO: RosType = RosType {
    name: "sensor_msgs/msg/CameraInfo",
    key_name: "sensor_msgs::msg::dds_::CameraInfo_",
    hash: "RIHS01_b3dfd68ff46c9d56c80fd3bd4ed22c7a4ddce8c8348f2f59c299e73118e7e275",
};

/// `std_srvs/srv/Trigger` (the service type: its hash covers request, response and event messages).
pub const TRIGGER: RosType = RosType {
    name: "std_srvs/srv/Trigger",
    key_name: "std_srvs::srv::dds_::Trigger_",
    hash: "RIHS01_eeff2cd6fa5ad9d27cdf4dec64818317839b62f212a91e6b5304b634b2062c5f",
};

/// Every type above, for checks that cover them all.
pub const ALL: [RosType; 8] = [
    POSE_STAMPED,
    TF_MESSAGE,
    DETECTION3D_ARRAY,
    DIAGNOSTIC_ARRAY,
    EVENT_PACKET,
    IMAGE,
    CAMERA_INFO,
    TRIGGER,
];

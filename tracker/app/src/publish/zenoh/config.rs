//! The `[zenoh]` settings: session mode, endpoints, topic names and QoS, checked and turned into a zenoh session
//! configuration; and why the sink could not be set up.

use crate::publish::ros2;

/// zenoh session mode.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum SessionMode {
    /// Peer (the default, as ROS 2 nodes under rmw_zenoh): talks to peers and routers it connects to.
    #[default]
    Peer,
    /// Client: everything goes through the router it connects to (which must then be there).
    Client,
}

/// What a publisher does when the transport's queue is full.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Default,
    serde::Deserialize,
    serde::Serialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "lowercase")]
pub enum CongestionPolicy {
    /// Drop the sample (the default: never stall the tracker; what rmw_zenoh does for keep-last publishers).
    #[default]
    Drop,
    /// Block the caller until there is room (loss-free, but a slow subscriber can stall the tick loop).
    Block,
}

/// zenoh / ROS 2 publishing settings; the runtime's TOML configuration embeds this table (e.g. `[zenoh]`).
/// Every field has a default, unknown keys are rejected.
#[derive(
    Debug, Clone, PartialEq, Eq, serde::Deserialize, serde::Serialize, schemars::JsonSchema,
)]
#[serde(deny_unknown_fields, default)]
pub struct ZenohConfig {
    /// Session mode, `peer` (default) or `client`.
    pub mode: SessionMode,
    /// Endpoints to connect to. Default `["tcp/127.0.0.1:7447"]`, the local router (`ros2 run rmw_zenoh_cpp
    /// rmw_zenohd`) when one runs; in peer mode a missing router is retried in the background, never required.
    pub connect: Vec<String>,
    /// Endpoints to listen on. Default `["tcp/127.0.0.1:0"]` (loopback, a free port).
    pub listen: Vec<String>,
    /// UDP multicast scouting. Default off (loopback-only by default).
    pub multicast_scouting: bool,
    /// ROS domain id (`ROS_DOMAIN_ID`), default 0: the first component of every rmw_zenoh key.
    pub domain_id: u32,
    /// Topic prefix: poses go on `<prefix>/<object>/pose`, status on `<prefix>/status`. Default `eventtrack6d`.
    pub topic_prefix: String,
    /// `header.frame_id` of every pose. Default `eventtrack6d_camera` (the event camera, OpenCV convention).
    pub frame_id: String,
    /// ROS node name that the liveliness tokens announce. Default `eventtrack6d`.
    pub node_name: String,
    /// ROS node namespace that the liveliness tokens announce. Default `/`.
    pub node_namespace: String,
    /// Congestion control of the pose publishers, `drop` (default) or `block`.
    pub congestion_control: CongestionPolicy,
    /// Express (unbatched) pose samples: lower latency. Default true.
    pub express: bool,
    /// Answer pose queries on `<prefix>/<object>/pose_at` (`?t_us=` or `?stamp_ns=`): the pose at any time
    /// within the last 2 s, interpolated between ticks. Default true.
    pub pose_queries: bool,
    /// Publish `tf2_msgs/msg/TFMessage` on `tf_topic` every tick: the camera frame (`frame_id`) to one child frame
    /// per object that is not `lost`. Default true.
    pub tf: bool,
    /// The TF topic. Default `/tf`.
    pub tf_topic: String,
    /// Child frame of each object in TF, by object name, e.g. `{ mug = "mug_link" }`; an object not listed uses
    /// its name. Default empty.
    pub tf_child_frames: std::collections::BTreeMap<String, String>,
    /// Publish `vision_msgs/msg/Detection3DArray` on `<prefix>/detections` every tick: one detection per object,
    /// the quality as its score, the mesh's bounding box. Default true.
    pub detections: bool,
    /// Publish `diagnostic_msgs/msg/DiagnosticArray` on `<prefix>/diagnostics` every tick: one status per object
    /// (level OK tracking, WARN degraded, ERROR lost; state, quality, time and the latest control outcome as
    /// values). Default true.
    pub diagnostics: bool,
    /// Accept control: a `geometry_msgs/msg/PoseStamped` on `<prefix>/<object>/set_pose` re-seeds that object, a
    /// `std_srvs/srv/Trigger` call of the service `<prefix>/reset` resets every object to its first pose. Default
    /// true.
    pub control: bool,
    /// A set-pose whose stamp lies more than this many milliseconds before (or after) the tick it would apply at
    /// is refused (stamp 0 means now). Default 1000.
    pub control_max_age_ms: u64,
}

impl Default for ZenohConfig {
    fn default() -> Self {
        Self {
            mode: SessionMode::Peer,
            connect: vec!["tcp/127.0.0.1:7447".into()],
            listen: vec!["tcp/127.0.0.1:0".into()],
            multicast_scouting: false,
            domain_id: 0,
            topic_prefix: "eventtrack6d".into(),
            frame_id: "eventtrack6d_camera".into(),
            node_name: "eventtrack6d".into(),
            node_namespace: "/".into(),
            congestion_control: CongestionPolicy::Drop,
            express: true,
            pose_queries: true,
            tf: true,
            tf_topic: "/tf".into(),
            tf_child_frames: std::collections::BTreeMap::new(),
            detections: true,
            diagnostics: true,
            control: true,
            control_max_age_ms: 1000,
        }
    }
}

impl ZenohConfig {
    /// The ROS topic of an object's poses: `<prefix>/<object>/pose` (no leading `/`).
    pub fn pose_topic(&self, object: &str) -> String {
        join_topic(&self.topic_prefix, &format!("{object}/pose"))
    }

    /// The zenoh key of an object's pose queries: `<prefix>/<object>/pose_at`.
    pub fn pose_query_key_expr(&self, object: &str) -> String {
        join_topic(&self.topic_prefix, &format!("{object}/pose_at"))
    }

    /// The ROS topic of the detections: `<prefix>/detections`.
    pub fn detections_topic(&self) -> String {
        join_topic(&self.topic_prefix, "detections")
    }

    /// The ROS topic of the tracking state: `<prefix>/diagnostics`.
    pub fn diagnostics_topic(&self) -> String {
        join_topic(&self.topic_prefix, "diagnostics")
    }

    /// The ROS topic that re-seeds an object: `<prefix>/<object>/set_pose`.
    pub fn set_pose_topic(&self, object: &str) -> String {
        join_topic(&self.topic_prefix, &format!("{object}/set_pose"))
    }

    /// The ROS service that resets every object: `<prefix>/reset`.
    pub fn reset_service(&self) -> String {
        join_topic(&self.topic_prefix, "reset")
    }

    /// The TF child frame of `object`.
    pub fn tf_child_frame(&self, object: &str) -> String {
        self.tf_child_frames
            .get(object)
            .cloned()
            .unwrap_or_else(|| object.to_owned())
    }

    /// The zenoh key of the JSON status: `<prefix>/status`.
    pub fn status_key_expr(&self) -> String {
        join_topic(&self.topic_prefix, "status")
    }

    /// Checks names and builds the zenoh session configuration.
    pub fn to_zenoh_config(&self) -> Result<zenoh::Config, ZenohSetupError> {
        ros2::check_name_path(&self.topic_prefix).map_err(|message| ZenohSetupError::Config {
            key: "zenoh.topic_prefix",
            message,
        })?;
        ros2::check_name_path(&self.node_namespace).map_err(|message| ZenohSetupError::Config {
            key: "zenoh.node_namespace",
            message,
        })?;
        ros2::check_name_token(&self.node_name).map_err(|message| ZenohSetupError::Config {
            key: "zenoh.node_name",
            message,
        })?;
        ros2::check_name_path(&self.tf_topic).map_err(|message| ZenohSetupError::Config {
            key: "zenoh.tf_topic",
            message,
        })?;
        if let Some((object, frame)) = self
            .tf_child_frames
            .iter()
            .find(|(_, f)| f.is_empty() || f.contains('\0'))
        {
            return Err(ZenohSetupError::Config {
                key: "zenoh.tf_child_frames",
                message: format!("{object} = {frame:?}: a frame name must be non-empty text"),
            });
        }
        if self.frame_id.contains('\0') {
            return Err(ZenohSetupError::Config {
                key: "zenoh.frame_id",
                message: "contains a NUL byte".into(),
            });
        }
        let mut c = zenoh::Config::default();
        let mode = match self.mode {
            SessionMode::Peer => "\"peer\"",
            SessionMode::Client => "\"client\"",
        };
        set(&mut c, "zenoh.mode", "mode", mode)?;
        let endpoints = |v: &Vec<String>| serde_json::to_string(v).unwrap_or_else(|_| "[]".into());
        set(
            &mut c,
            "zenoh.connect",
            "connect/endpoints",
            &endpoints(&self.connect),
        )?;
        set(
            &mut c,
            "zenoh.listen",
            "listen/endpoints",
            &endpoints(&self.listen),
        )?;
        let scouting = if self.multicast_scouting {
            "true"
        } else {
            "false"
        };
        set(
            &mut c,
            "zenoh.multicast_scouting",
            "scouting/multicast/enabled",
            scouting,
        )?;
        Ok(c)
    }
}

fn join_topic(prefix: &str, rest: &str) -> String {
    let prefix = prefix.trim_matches('/');
    if prefix.is_empty() {
        rest.to_owned()
    } else {
        format!("{prefix}/{rest}")
    }
}

fn set(
    c: &mut zenoh::Config,
    key: &'static str,
    path: &str,
    json: &str,
) -> Result<(), ZenohSetupError> {
    c.insert_json5(path, json)
        .map_err(|e| ZenohSetupError::Config {
            key,
            message: e.to_string(),
        })
}

/// Why the zenoh sink could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum ZenohSetupError {
    /// A configuration value is invalid (`key` names it, e.g. `zenoh.connect`).
    #[error("{key}: {message}")]
    Config {
        /// Configuration key.
        key: &'static str,
        /// What is wrong.
        message: String,
    },
    /// An object name cannot be used in a ROS topic / zenoh key.
    #[error("zenoh: object name {name:?} cannot be used in a topic: {reason}")]
    ObjectName {
        /// The object name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// The zenoh session did not open (e.g. a listen endpoint is taken).
    #[error("zenoh: could not open the session: {0}")]
    Open(String),
    /// A publisher or liveliness token could not be declared.
    #[error("zenoh: could not declare the {what} on {key:?}: {message}")]
    Declare {
        /// `publisher` or `liveliness token`.
        what: &'static str,
        /// Key expression.
        key: String,
        /// zenoh's message.
        message: String,
    },
}

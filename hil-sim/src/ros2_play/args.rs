//! The command line of `hil-sim ros2-play`.

use super::{Pace, Ros2PlayError, Ros2PlayOptions, SessionMode, SessionOptions, Topics};
use std::path::PathBuf;
use std::time::Duration;

/// Publish a recording on ROS 2 topics over zenoh, as the vendors' ROS 2 drivers publish a live rig.
///
/// The events go out as metavision_driver sends them: `event_camera_msgs/msg/EventPacket` with encoding `evt3`,
/// whose `events` are consecutive pieces of RECORDING/events.raw after its text header, byte for byte, cut at word
/// boundaries before a time word into about --slice-us of stream time each (`seq` 0, 1, 2, ...; `header.stamp` the
/// time of the packet's first CD event or trigger edge, or where its window opens if it has none: at its first
/// word that is not a time word). Each depth frame goes out as realsense-ros sends it: a `sensor_msgs/msg/Image`
/// (`16UC1`, millimetres, little-endian: the stored frame unchanged, or rounded to millimetres if camera.json's
/// depth_scale_m is not 0.001) and a `sensor_msgs/msg/CameraInfo` (the depth camera of camera.json), both stamped with the frame's
/// exposure: the rising edge of its phase-coded trigger pulse in events.raw, or the trigger schedule's time where
/// that pulse is missing. A frame is published when the stream reaches its exposure plus --depth-latency-ms,
/// before the event packet holding that time. Every stamp is --stamp-offset-ns + 1000 x the stream time in
/// microseconds. Samples are on rmw_zenoh's keys with its attachment, and liveliness tokens announce the node
/// `hil_sim_ros2_play` and its three publishers, so ROS 2 nodes using rmw_zenoh_cpp (and the tracker's ROS 2
/// source) receive them directly, and `ros2 topic list` shows them. Publishers are reliable and block rather than
/// drop. Progress on stderr once a second; a summary at the end. The facts: docs/zenoh-ros2.md.
#[derive(Debug, clap::Args)]
pub struct Ros2PlayArgs {
    /// Recording directory (events.raw in EVT 3.0, depth/, camera.json, meta.json).
    #[arg(value_name = "RECORDING")]
    pub recording: PathBuf,
    /// realtime: each message at its stream time on the wall clock, counted from the start of publishing (an
    /// event packet when the stream reaches its end, a depth frame at its exposure plus the latency); fast: as fast
    /// as zenoh takes them.
    #[arg(long, value_name = "PACE", default_value = "realtime", value_parser = ["realtime", "fast"])]
    pub pace: String,
    /// Stream time per event packet, microseconds, in [1, 10000000].
    #[arg(long, value_name = "US", default_value_t = 1000)]
    pub slice_us: u32,
    /// Delay from a depth frame's exposure to its publication, in stream time, milliseconds, in [0, 10000]. With
    /// 0 a receiver has the frame before the end of its trigger pulse.
    #[arg(long, value_name = "MS", default_value_t = 0.0)]
    pub depth_latency_ms: f64,
    /// zenoh endpoint to connect to (`none`: none). The default is the local zenoh router
    /// (`ros2 run rmw_zenoh_cpp rmw_zenohd`), as for ROS 2 nodes; in peer mode a missing router is retried in the
    /// background. Only TCP is built in.
    #[arg(long, value_name = "ENDPOINT", default_value = "tcp/127.0.0.1:7447")]
    pub connect: Vec<String>,
    /// zenoh endpoint to listen on (`none`: none). The default, a free loopback port, lets peers
    /// that the router tells about this one connect directly. With no router running, listen on
    /// `tcp/127.0.0.1:7447` so that nodes connecting to the router's port reach this one.
    #[arg(long, value_name = "ENDPOINT", default_value = "tcp/127.0.0.1:0")]
    pub listen: Vec<String>,
    /// zenoh session mode: peer (as ROS 2 nodes under rmw_zenoh) or client (everything through the router, which
    /// must then be running). Multicast scouting is off either way.
    #[arg(long, value_name = "MODE", default_value = "peer", value_parser = ["peer", "client"])]
    pub mode: String,
    /// ROS domain id, the first component of every key (default: the ROS_DOMAIN_ID environment variable, else 0).
    #[arg(long, value_name = "ID")]
    pub domain_id: Option<u32>,
    /// Topic of the event packets (metavision_driver's default).
    #[arg(long, value_name = "TOPIC", default_value = "/event_camera/events")]
    pub events_topic: String,
    /// Topic of the depth images (realsense-ros's default).
    #[arg(
        long,
        value_name = "TOPIC",
        default_value = "/camera/camera/depth/image_rect_raw"
    )]
    pub depth_topic: String,
    /// Topic of the depth camera infos (realsense-ros's default).
    #[arg(
        long,
        value_name = "TOPIC",
        default_value = "/camera/camera/depth/camera_info"
    )]
    pub camera_info_topic: String,
    /// `header.frame_id` of the event packets.
    #[arg(
        long,
        value_name = "FRAME",
        default_value = "event_camera_optical_frame"
    )]
    pub event_frame_id: String,
    /// `header.frame_id` of the depth images and camera infos (realsense-ros's).
    #[arg(
        long,
        value_name = "FRAME",
        default_value = "camera_depth_optical_frame"
    )]
    pub depth_frame_id: String,
    /// Every `header.stamp` is this + 1000 x the stream time in microseconds (may be negative). Default: the
    /// system time when publishing starts minus the first event's time, so that stamps look like ROS time and,
    /// at real-time pace, lie close to the moment each message goes out.
    #[arg(long, value_name = "NS", allow_negative_numbers = true)]
    pub stamp_offset_ns: Option<i64>,
    /// Before publishing, wait up to this many seconds until a subscription to the events topic is in the ROS
    /// graph (its rmw_zenoh liveliness token in this domain); then fail, naming the topic and domain. 0: do not
    /// wait.
    #[arg(long, value_name = "S", default_value_t = 10.0)]
    pub wait_for_subscriber: f64,
}

fn bad(option: &'static str, problem: String) -> Ros2PlayError {
    Ros2PlayError::Option { option, problem }
}

/// The endpoints of a repeatable endpoint option, checked: `proto/host:port` with proto `tcp`; `none` alone is none.
fn endpoints(option: &'static str, values: &[String]) -> Result<Vec<String>, Ros2PlayError> {
    if values.len() == 1 && values[0] == "none" {
        return Ok(Vec::new());
    }
    for v in values {
        let endpoint: zenoh::config::EndPoint = v.parse().map_err(|_| {
            bad(
                option,
                format!(
                    "`{v}` is not a zenoh endpoint (PROTOCOL/HOST:PORT, e.g. tcp/127.0.0.1:7447)"
                ),
            )
        })?;
        if endpoint.protocol().as_str() != "tcp" {
            return Err(bad(
                option,
                format!("`{v}`: only tcp endpoints are built in (e.g. tcp/127.0.0.1:7447)"),
            ));
        }
        let port = endpoint.address().as_str().rsplit_once(':').map(|(_, p)| p);
        if port.is_none_or(|p| p.parse::<u16>().is_err()) {
            return Err(bad(
                option,
                format!("`{v}`: the address needs a port (tcp/HOST:PORT)"),
            ));
        }
    }
    Ok(values.to_vec())
}

fn topic(option: &'static str, name: &str) -> Result<String, Ros2PlayError> {
    if name.trim_matches('/').is_empty() {
        return Err(bad(option, "is empty".into()));
    }
    ros2::check_name_path(name).map_err(|p| bad(option, format!("`{name}`: {p}")))?;
    Ok(ros2::fully_qualified_topic(name))
}

fn frame_id(option: &'static str, id: &str) -> Result<String, Ros2PlayError> {
    if id.contains('\0') {
        return Err(bad(option, "contains a NUL byte".into()));
    }
    Ok(id.to_owned())
}

fn domain_id(given: Option<u32>) -> Result<u32, Ros2PlayError> {
    if let Some(id) = given {
        return Ok(id);
    }
    match std::env::var("ROS_DOMAIN_ID") {
        Ok(v) if !v.trim().is_empty() => v.trim().parse().map_err(|_| {
            bad(
                "ROS_DOMAIN_ID",
                format!("`{v}` is not a domain id (a whole number)"),
            )
        }),
        _ => Ok(0),
    }
}

impl Ros2PlayArgs {
    /// The options these arguments ask for, or an error naming the bad argument.
    pub fn options(&self) -> Result<Ros2PlayOptions, Ros2PlayError> {
        if !(1..=10_000_000).contains(&self.slice_us) {
            return Err(bad(
                "--slice-us",
                format!("{} is not in [1, 10000000]", self.slice_us),
            ));
        }
        let latency = self.depth_latency_ms;
        if !(latency.is_finite() && (0.0..=10_000.0).contains(&latency)) {
            return Err(bad(
                "--depth-latency-ms",
                format!("{latency} is not in [0, 10000]"),
            ));
        }
        let wait = Duration::try_from_secs_f64(self.wait_for_subscriber).map_err(|_| {
            bad(
                "--wait-for-subscriber",
                format!("{} is not a number of seconds", self.wait_for_subscriber),
            )
        })?;
        Ok(Ros2PlayOptions {
            recording: self.recording.clone(),
            pace: if self.pace == "fast" {
                Pace::Fast
            } else {
                Pace::Realtime
            },
            slice_us: i64::from(self.slice_us),
            depth_latency_us: (latency * 1000.0).round() as i64,
            session: SessionOptions {
                mode: if self.mode == "client" {
                    SessionMode::Client
                } else {
                    SessionMode::Peer
                },
                connect: endpoints("--connect", &self.connect)?,
                listen: endpoints("--listen", &self.listen)?,
            },
            domain_id: domain_id(self.domain_id)?,
            topics: Topics {
                events: topic("--events-topic", &self.events_topic)?,
                depth_image: topic("--depth-topic", &self.depth_topic)?,
                camera_info: topic("--camera-info-topic", &self.camera_info_topic)?,
                event_frame_id: frame_id("--event-frame-id", &self.event_frame_id)?,
                depth_frame_id: frame_id("--depth-frame-id", &self.depth_frame_id)?,
            },
            stamp_offset_ns: self.stamp_offset_ns,
            wait_for_subscriber: wait,
            progress: true,
        })
    }
}

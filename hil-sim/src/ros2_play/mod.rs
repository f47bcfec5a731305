//! `hil-sim ros2-play`: a recording published on ROS 2 topics over zenoh, as the vendors' ROS 2 drivers publish
//! a live rig (metavision_driver's `event_camera_msgs/msg/EventPacket`, realsense-ros's depth `sensor_msgs/msg/Image`
//! and `CameraInfo`), in rmw_zenoh's wire form, so that ROS 2 nodes and the tracker's ROS 2 source receive them
//! with no hardware and no bridge.
//!
//! [`slicer`] cuts `events.raw` into packets, [`exposure`] finds each depth frame's exposure on the event camera's
//! clock, [`messages`] fills and encodes the messages, [`node`] is the zenoh side, and [`player`] interleaves and
//! paces them. [`args`] is the command line.

pub mod args;
pub mod exposure;
pub mod messages;
pub mod node;
pub mod player;
pub mod slicer;

pub use player::{PlaySummary, play};

use drivers::recording::RecordingError;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How fast messages go out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pace {
    /// Each message at its stream time on the wall clock, counted from the start of publishing.
    Realtime,
    /// As fast as zenoh takes them.
    Fast,
}

/// Sleeps until a stream time's wall-clock time, counted from the first stream time given (real-time pace only).
struct Pacer {
    pace: Pace,
    origin: Option<(i64, Instant)>,
}

impl Pacer {
    fn new(pace: Pace) -> Self {
        Self { pace, origin: None }
    }

    fn until(&mut self, t_us: i64) {
        if self.pace == Pace::Fast {
            return;
        }
        let (t0, w0) = *self.origin.get_or_insert((t_us, Instant::now()));
        let target = w0 + Duration::from_micros(u64::try_from(t_us - t0).unwrap_or(0));
        let now = Instant::now();
        if target > now {
            std::thread::sleep(target - now);
        }
    }
}

/// zenoh session mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SessionMode {
    /// A peer, as ROS 2 nodes under rmw_zenoh are.
    Peer,
    /// A client of the router it connects to.
    Client,
}

/// The zenoh session `ros2-play` opens (multicast scouting is always off).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SessionOptions {
    /// Peer or client.
    pub mode: SessionMode,
    /// Endpoints to connect to, e.g. `tcp/127.0.0.1:7447`.
    pub connect: Vec<String>,
    /// Endpoints to listen on.
    pub listen: Vec<String>,
}

/// The three topics and two frames of the published messages.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topics {
    /// `EventPacket` topic (metavision_driver: `/event_camera/events`).
    pub events: String,
    /// Depth `Image` topic (realsense-ros: `/camera/camera/depth/image_rect_raw`).
    pub depth_image: String,
    /// Depth `CameraInfo` topic (realsense-ros: `/camera/camera/depth/camera_info`).
    pub camera_info: String,
    /// `header.frame_id` of the event packets.
    pub event_frame_id: String,
    /// `header.frame_id` of the depth images and camera infos.
    pub depth_frame_id: String,
}

/// Everything `hil-sim ros2-play` is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub struct Ros2PlayOptions {
    /// The recording directory.
    pub recording: PathBuf,
    /// Message pace.
    pub pace: Pace,
    /// Stream time per event packet, microseconds (at least 1).
    pub slice_us: i64,
    /// A depth frame goes out when the stream reaches its exposure plus this, microseconds (at least 0).
    pub depth_latency_us: i64,
    /// The zenoh session.
    pub session: SessionOptions,
    /// ROS domain id.
    pub domain_id: u32,
    /// Topic names and frame ids.
    pub topics: Topics,
    /// `header.stamp` = this + 1000 x stream time (µs); `None`: the system time at the start of publishing minus
    /// the first event's time.
    pub stamp_offset_ns: Option<i64>,
    /// How long to wait for a subscription to the events topic before publishing (zero: do not wait).
    pub wait_for_subscriber: Duration,
    /// Print a progress line on stderr once a second.
    pub progress: bool,
}

/// Why `ros2-play` could not publish the recording.
#[derive(Debug, thiserror::Error)]
pub enum Ros2PlayError {
    /// An option's value is unusable.
    #[error("{option}: {problem}")]
    Option {
        /// The option, e.g. `--connect`.
        option: &'static str,
        /// What is wrong.
        problem: String,
    },
    /// The recording cannot be opened or a file of it read.
    #[error(transparent)]
    Recording(#[from] RecordingError),
    /// zenoh refused something.
    #[error("{what}: {message}")]
    Zenoh {
        /// What was being done.
        what: String,
        /// zenoh's message.
        message: String,
    },
    /// No subscription to the events topic appeared in time.
    #[error(
        "no subscription to {topic} (domain {domain_id}) appeared in the ROS graph within {seconds} s: start the \
         subscriber first, check ROS_DOMAIN_ID / --domain-id and the zenoh endpoints, or pass --wait-for-subscriber 0"
    )]
    NoSubscriber {
        /// The events topic.
        topic: String,
        /// ROS domain id.
        domain_id: u32,
        /// How long was waited, seconds.
        seconds: f64,
    },
    /// A stamp does not fit a ROS time.
    #[error(
        "stamp of stream time {t_us} us with --stamp-offset-ns {offset_ns} is outside ROS time (i32 seconds)"
    )]
    Stamp {
        /// Stream time, microseconds.
        t_us: i64,
        /// The offset, nanoseconds.
        offset_ns: i64,
    },
}

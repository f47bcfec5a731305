//! `[ros2]`: the ROS 2 source's settings (`source.kind = "ros2"`): the vendors' driver topics over rmw_zenoh, the
//! calibration, the trigger schedule, and the zenoh endpoints it reads from.

use super::ConfigError;
use drivers::recording::TriggerSchedule;
use drivers::timeline::TimelineConfig;
use serde::Deserialize;
use std::path::PathBuf;

/// `[ros2]` (the sensors through ROS 2: docs/zenoh-ros2.md, "Input").
#[derive(Debug, Clone, PartialEq, Deserialize, serde::Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Ros2SourceConfig {
    /// Both cameras' calibration in `camera.json` format (event camera intrinsics and size, depth camera, and
    /// `T_event_depth`, the depth/event extrinsic). Required. The depth camera's `CameraInfo` must agree with it.
    pub calibration: PathBuf,
    /// `event_camera_msgs/msg/EventPacket` topic (encoding `evt3`). Default `/event_camera/events`
    /// (metavision_driver's).
    pub events_topic: String,
    /// `sensor_msgs/msg/Image` depth topic (`16UC1` millimetres or `32FC1` metres). Default
    /// `/camera/camera/depth/image_rect_raw` (realsense-ros's).
    pub depth_topic: String,
    /// `sensor_msgs/msg/CameraInfo` of the depth images. Default `/camera/camera/depth/camera_info`.
    pub camera_info_topic: String,
    /// Trigger input channel of the event camera carrying the MCU's pulse train. Default 0.
    pub trigger_channel: u8,
    /// Tick (trigger pulse) rate, Hz. Default 120.
    pub tick_rate_hz: f64,
    /// Ticks per depth exposure (the phase-coded pulse's period). Default 4.
    pub ticks_per_depth: u32,
    /// Width of an ordinary pulse, microseconds. Default the firmware's.
    pub narrow_width_us: i64,
    /// Width of a phase-coded (depth exposure) pulse, microseconds. Default the firmware's.
    pub wide_width_us: i64,
    /// zenoh endpoints to connect to (the rmw_zenoh router, or a driver's session). Default
    /// `["tcp/127.0.0.1:7447"]`. The mode, scouting and domain id are `[zenoh]`'s.
    pub connect: Vec<String>,
    /// zenoh endpoints to listen on. Default none.
    pub listen: Vec<String>,
    /// How long to wait at start for the first trigger pulse in the events and the first `CameraInfo`, seconds
    /// (0.1 to 600). Default 10.
    pub wait_for_data_s: f64,
    /// End the run when no event packet has arrived for this many seconds (a finished playback); 0 = never
    /// (run until stopped or `source.max_seconds`). Default 0.
    pub end_after_idle_s: f64,
}

impl Default for Ros2SourceConfig {
    fn default() -> Self {
        let t = TimelineConfig::default();
        Self {
            calibration: PathBuf::new(),
            events_topic: "/event_camera/events".into(),
            depth_topic: "/camera/camera/depth/image_rect_raw".into(),
            camera_info_topic: "/camera/camera/depth/camera_info".into(),
            trigger_channel: t.channel,
            tick_rate_hz: t.tick_rate_hz,
            ticks_per_depth: t.ticks_per_depth,
            narrow_width_us: t.narrow_width_us,
            wide_width_us: t.wide_width_us,
            connect: vec!["tcp/127.0.0.1:7447".into()],
            listen: Vec::new(),
            wait_for_data_s: 10.0,
            end_after_idle_s: 0.0,
        }
    }
}

impl Ros2SourceConfig {
    /// The trigger schedule the events carry.
    pub fn schedule(&self) -> TriggerSchedule {
        TriggerSchedule {
            channel: self.trigger_channel,
            tick_rate_hz: self.tick_rate_hz,
            ticks_per_depth: self.ticks_per_depth,
            narrow_width_us: self.narrow_width_us,
            wide_width_us: self.wide_width_us,
        }
    }

    /// Range and name checks.
    pub fn validate(&self, origin: &str) -> Result<(), ConfigError> {
        let bad = |key: &str, message: String| ConfigError::Invalid {
            origin: origin.into(),
            key: format!("ros2.{key}"),
            message,
        };
        if self.calibration.as_os_str().is_empty() {
            return Err(bad(
                "calibration",
                "is required: the cameras' camera.json (intrinsics and T_event_depth)".into(),
            ));
        }
        for (key, topic) in [
            ("events_topic", &self.events_topic),
            ("depth_topic", &self.depth_topic),
            ("camera_info_topic", &self.camera_info_topic),
        ] {
            ros2::check_name_path(topic).map_err(|m| bad(key, m))?;
            if topic.trim_matches('/').is_empty() {
                return Err(bad(key, "is empty".into()));
            }
        }
        if self.trigger_channel > 15 {
            return Err(bad(
                "trigger_channel",
                format!(
                    "{} is out of range: EVT 3.0 carries channels 0..15",
                    self.trigger_channel
                ),
            ));
        }
        if !(self.tick_rate_hz.is_finite() && (1.0..=2000.0).contains(&self.tick_rate_hz)) {
            return Err(bad(
                "tick_rate_hz",
                format!("{} is out of range: 1 to 2000 Hz", self.tick_rate_hz),
            ));
        }
        if !(1..=64).contains(&self.ticks_per_depth) {
            return Err(bad(
                "ticks_per_depth",
                format!("{} is out of range: 1 to 64", self.ticks_per_depth),
            ));
        }
        let period_us = 1e6 / self.tick_rate_hz;
        if !(self.narrow_width_us > 0 && self.narrow_width_us < self.wide_width_us)
            || self.wide_width_us as f64 >= period_us
        {
            return Err(bad(
                "wide_width_us",
                format!(
                    "pulse widths {} us (narrow) and {} us (wide) must satisfy 0 < narrow < wide < one tick \
                     period ({period_us:.0} us)",
                    self.narrow_width_us, self.wide_width_us
                ),
            ));
        }
        if !(self.wait_for_data_s.is_finite() && (0.1..=600.0).contains(&self.wait_for_data_s)) {
            return Err(bad(
                "wait_for_data_s",
                format!("{} is out of range: 0.1 to 600 s", self.wait_for_data_s),
            ));
        }
        if !(self.end_after_idle_s.is_finite() && (0.0..=3600.0).contains(&self.end_after_idle_s)) {
            return Err(bad(
                "end_after_idle_s",
                format!(
                    "{} is out of range: 0 (never) to 3600 s",
                    self.end_after_idle_s
                ),
            ));
        }
        Ok(())
    }
}

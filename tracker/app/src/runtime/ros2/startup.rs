//! Connecting the ROS 2 source: the zenoh session and subscriptions, then waiting for the first trigger pulse in
//! the events (the first tick, where the objects' first poses stand) and the depth camera's `CameraInfo`, which
//! must agree with the calibration. What arrives meanwhile is kept and delivered first.

use super::Ros2Source;
use super::inputs::{
    Expected, INPUT_QUEUE_LEN, Ros2Input, Topics, camera_info_mismatch, subscribe,
};
use crate::publish::ros2::{self, RosNodeIdentity};
use crate::runtime::config::{Config, Ros2SourceConfig};
use crate::runtime::error::RuntimeError;
use crate::runtime::scene::{SceneObject, TrackerScene, pose_of};
use crate::runtime::source::{Source, SourceError};
use drivers::event::{CdEvent, EventSink, Geometry, TriggerEdge};
use drivers::formats::evt3::Evt3Decoder;
use drivers::recording::{CameraRig, ModelInfo, parse_models_info};
use drivers::timeline::TimelineConfig;
use std::collections::VecDeque;
use std::sync::mpsc::sync_channel;
use std::time::{Duration, Instant};
use zenoh::Wait;

/// Samples kept while waiting for the first pulse at most (then the wait fails: the events carry no pulse).
const MAX_PREBUFFER: usize = 200_000;

fn input_error(message: String) -> RuntimeError {
    RuntimeError::Source(SourceError::Input(message))
}

/// Reads and checks `camera.json`.
fn read_calibration(r: &Ros2SourceConfig) -> Result<CameraRig, RuntimeError> {
    let path = r.calibration.display();
    let text = std::fs::read_to_string(&r.calibration)
        .map_err(|e| input_error(format!("ros2.calibration {path}: cannot read: {e}")))?;
    let rig: CameraRig = serde_json::from_str(&text)
        .map_err(|e| input_error(format!("ros2.calibration {path}: not a camera.json: {e}")))?;
    rig.validate()
        .map_err(|e| input_error(format!("ros2.calibration {path}: {e}")))?;
    Ok(rig)
}

/// The model information of `name` in a `models_info.json`, if one is given.
fn model_info(
    path: Option<&std::path::Path>,
    name: &str,
) -> Result<Option<ModelInfo>, RuntimeError> {
    let Some(path) = path else {
        return Ok(None);
    };
    let text = std::fs::read_to_string(path)
        .map_err(|e| input_error(format!("{}: cannot read: {e}", path.display())))?;
    let models =
        parse_models_info(&text).map_err(|e| input_error(format!("{}: {e}", path.display())))?;
    models
        .into_iter()
        .find(|m| m.name == name)
        .map(Some)
        .ok_or_else(|| input_error(format!("{}: no entry for object `{name}`", path.display())))
}

/// Finds the first rising edge on the tick channel.
struct FirstRise {
    channel: u8,
    t: Option<i64>,
}

impl EventSink for FirstRise {
    fn cd(&mut self, _: CdEvent) {}
    fn cd_vector(&mut self, _: i64, _: u16, _: u16, _: u32, _: bool) {}
    fn trigger(&mut self, e: TriggerEdge) {
        if self.t.is_none() && e.rising && e.channel == self.channel {
            self.t = Some(e.t_us);
        }
    }
}

/// Connects to the ROS 2 topics of `config`'s `[ros2]` table and waits for the first tick pulse and `CameraInfo`;
/// returns the source, its scene (the configured objects at their first poses, at that tick) and its timeline.
pub fn connect(
    config: &Config,
) -> Result<(Box<dyn Source>, TrackerScene, TimelineConfig), RuntimeError> {
    let r = config.ros2.as_ref().ok_or_else(|| {
        RuntimeError::Tracker("source.kind = \"ros2\" needs a [ros2] table".into())
    })?;
    let rig = read_calibration(r)?;
    let mut zenoh_config = config.zenoh.clone();
    zenoh_config.connect = r.connect.clone();
    zenoh_config.listen = r.listen.clone();
    let session = zenoh::open(
        zenoh_config
            .to_zenoh_config()
            .map_err(|e| input_error(e.to_string()))?,
    )
    .wait()
    .map_err(|e| input_error(format!("ros2: could not open the zenoh session: {e}")))?;
    let node = RosNodeIdentity {
        domain_id: config.zenoh.domain_id,
        zid: session.zid().to_string(),
        node_id: 0,
        enclave: "/".into(),
        namespace: ros2::fully_qualified_topic(&config.zenoh.node_namespace),
        name: format!("{}_input", config.zenoh.node_name),
    };
    let node_token = session
        .liveliness()
        .declare_token(ros2::node_liveliness_key_expr(&node))
        .wait()
        .map_err(|e| {
            input_error(format!(
                "ros2: could not declare the node's liveliness token: {e}"
            ))
        })?;
    let (tx, rx) = sync_channel(INPUT_QUEUE_LEN);
    let geometry = Geometry {
        width: u16::try_from(rig.event_camera.width).unwrap_or(u16::MAX),
        height: u16::try_from(rig.event_camera.height).unwrap_or(u16::MAX),
    };
    let expected = Expected {
        events: (rig.event_camera.width, rig.event_camera.height),
        depth: (rig.depth_camera.width, rig.depth_camera.height),
    };
    let topics = Topics {
        events: &r.events_topic,
        depth: &r.depth_topic,
        camera_info: &r.camera_info_topic,
    };
    let subscriptions = subscribe(&session, &node, &topics, expected, tx).map_err(input_error)?;
    eprintln!(
        "ros2: waiting for {} (a trigger pulse on channel {}) and {} in ROS domain {} ...",
        r.events_topic, r.trigger_channel, r.camera_info_topic, config.zenoh.domain_id
    );
    let deadline = Instant::now() + Duration::from_secs_f64(r.wait_for_data_s);
    let mut prebuffer = VecDeque::new();
    let mut scan = Evt3Decoder::new(Some(geometry));
    let mut first = FirstRise {
        channel: r.trigger_channel,
        t: None,
    };
    let (mut packets, mut info_seen) = (0u64, false);
    while first.t.is_none() || !info_seen {
        let left = deadline.saturating_duration_since(Instant::now());
        let item = match rx.recv_timeout(left.max(Duration::from_millis(1))) {
            Ok(item) => item,
            Err(_) if Instant::now() < deadline => continue,
            Err(_) => {
                return Err(nothing_arrived(
                    r,
                    config.zenoh.domain_id,
                    packets,
                    first.t,
                    info_seen,
                ));
            }
        };
        match &item {
            Ros2Input::Events { bytes, .. } => {
                packets += 1;
                if first.t.is_none() {
                    scan.decode(bytes, &mut first);
                }
            }
            Ros2Input::Info(info) => {
                if let Some(why) = camera_info_mismatch(info, &rig.depth_camera) {
                    return Err(input_error(format!(
                        "ros2: {}: {why} (ros2.calibration {})",
                        r.camera_info_topic,
                        r.calibration.display()
                    )));
                }
                info_seen = true;
            }
            _ => {}
        }
        prebuffer.push_back(item);
        if prebuffer.len() > MAX_PREBUFFER {
            return Err(nothing_arrived(
                r,
                config.zenoh.domain_id,
                packets,
                first.t,
                info_seen,
            ));
        }
    }
    let t0 = first.t.unwrap_or(0);
    let mut objects = Vec::with_capacity(config.objects.len());
    for o in &config.objects {
        objects.push(SceneObject {
            name: o.name.clone(),
            mesh: o.mesh.clone(),
            info: model_info(o.models_info.as_deref(), &o.name)?,
            first_pose: (t0, pose_of(o)),
        });
    }
    let schedule = r.schedule();
    let source = Ros2Source {
        describe: format!(
            "ROS 2: {} and {} over zenoh ({})",
            r.events_topic,
            r.depth_topic,
            r.connect.join(", ")
        ),
        session: Some(session),
        _subscriptions: subscriptions,
        _node_token: node_token,
        rx,
        prebuffer,
        schedule,
        batch: (config.queue.batch_events, config.queue.batch_us),
        max_seconds: config.source.max_seconds,
        end_after_idle: (r.end_after_idle_s > 0.0)
            .then(|| Duration::from_secs_f64(r.end_after_idle_s)),
        geometry,
        depth_camera: rig.depth_camera.clone(),
    };
    let scene = TrackerScene {
        rig,
        objects,
        recording: None,
    };
    Ok((Box::new(source), scene, schedule.timeline_config()))
}

/// Why the wait for the first pulse and `CameraInfo` failed, with what did arrive.
fn nothing_arrived(
    r: &Ros2SourceConfig,
    domain: u32,
    packets: u64,
    first: Option<i64>,
    info: bool,
) -> RuntimeError {
    let what = if packets == 0 {
        format!(
            "no EventPacket arrived on {} (is metavision_driver running under rmw_zenoh in ROS domain {domain}, \
             and can this session reach it through {:?}? `ros2 topic list` should show the topic)",
            r.events_topic, r.connect
        )
    } else if first.is_none() {
        format!(
            "{packets} EventPackets arrived on {} but no trigger pulse on channel {} (is the trigger MCU connected \
             and the camera's trigger input enabled? ros2.trigger_channel)",
            r.events_topic, r.trigger_channel
        )
    } else {
        debug_assert!(!info);
        format!("no CameraInfo arrived on {}", r.camera_info_topic)
    };
    input_error(format!(
        "ros2: within {} s (ros2.wait_for_data_s): {what}",
        r.wait_for_data_s
    ))
}

//! The zenoh sink: every object's pose as `geometry_msgs/msg/PoseStamped` on its rmw_zenoh key, so that ROS 2 nodes
//! using `rmw_zenoh_cpp` receive it unchanged, plus a JSON status key and the liveliness tokens that make the
//! publishers visible in the ROS 2 graph. Wire formats are in [`super::ros2`]; `docs/zenoh-ros2.md` explains them.
//!
//! The sink uses zenoh's synchronous API (`.wait()`), so it is called from a plain thread (zenoh runs its own tokio
//! runtime inside). A transport failure is counted and returned as [`PublishError`], never a panic.

mod commands;
mod config;
mod entity;
mod outputs;
mod pose_query;
mod query_parameters;
#[cfg(test)]
mod tests;

pub use config::{CongestionPolicy, SessionMode, ZenohConfig, ZenohSetupError};
pub use outputs::ObjectOutput;
pub use pose_query::{
    MAX_EXTRAPOLATION_US, PoseQueryCounters, PoseQueryError, RECENT_TICKS, RecentPoses,
    requested_time,
};

use super::control::ControlSender;
use super::ros2::{self, RosNodeIdentity, types};
use super::{PoseSink, PublishError, SinkCounters, TickPoses};
use commands::ControlEntities;
use entity::{RosPublisher, SendOptions, declare_token};
use outputs::{OutputContent, stamp_of};
use std::sync::{Arc, Mutex};
use zenoh::Wait;
use zenoh::bytes::Encoding;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;
use zenoh::qos::{CongestionControl, Priority};

/// Sink name used in errors, logs and the status topic.
pub const SINK_NAME: &str = "zenoh";

/// The per-tick outputs beside the poses (each `None` when turned off).
struct TickOutputs {
    content: OutputContent,
    tf: Option<RosPublisher>,
    detections: Option<RosPublisher>,
    diagnostics: Option<RosPublisher>,
}

/// Publishes poses over zenoh in rmw_zenoh's format, with TF, detections and diagnostics, and takes control
/// commands; see the module documentation.
///
/// Header stamps: `header.stamp = t_us * 1000 + ros_time_offset_ns` nanoseconds, i.e. the pose's time on the event
/// camera's clock shifted into ROS time by an offset fixed at construction. With offset 0 the stamp is the camera
/// clock itself; to stamp in ROS (system) time, the runtime passes `system_time_ns - camera_time_ns` measured at one
/// instant (e.g. when the first trigger edge is decoded).
pub struct ZenohPosePublisher {
    session: zenoh::Session,
    objects: Vec<RosPublisher>,
    outputs: TickOutputs,
    control: Option<ControlEntities>,
    status: Publisher<'static>,
    status_key_expr: String,
    node_liveliness_key_expr: String,
    tokens: Vec<LivelinessToken>,
    frame_id: String,
    ros_time_offset_ns: i64,
    buffer: Vec<u8>,
    counters: SinkCounters,
    status_counters: SinkCounters,
    /// The poses published lately, for the pose queries.
    recent: Arc<Mutex<RecentPoses>>,
    /// One pose-query queryable per object (none with `pose_queries = false`); undeclared on drop.
    queryables: Vec<(String, zenoh::query::Queryable<()>)>,
    query_counters: Arc<PoseQueryCounters>,
}

fn check_object_names(objects: &[ObjectOutput]) -> Result<(), ZenohSetupError> {
    for (i, o) in objects.iter().enumerate() {
        ros2::check_name_token(&o.name).map_err(|reason| ZenohSetupError::ObjectName {
            name: o.name.clone(),
            reason,
        })?;
        if objects[..i].iter().any(|p| p.name == o.name) {
            return Err(ZenohSetupError::ObjectName {
                name: o.name.clone(),
                reason: "appears twice".into(),
            });
        }
    }
    Ok(())
}

impl ZenohPosePublisher {
    /// Opens a zenoh session from `config`, declares one pose publisher per object (in `objects` order, matching
    /// [`tracker::track::PoseEstimate::object`]), the status publisher, and the node and publisher liveliness tokens.
    /// Returns promptly when no router is reachable (peer mode retries in the background). The objects' bounding
    /// boxes are unknown (zero-sized) and control is off; see [`Self::with_outputs`].
    pub fn new(
        config: &ZenohConfig,
        objects: &[String],
        ros_time_offset_ns: i64,
    ) -> Result<Self, ZenohSetupError> {
        let objects: Vec<ObjectOutput> = objects.iter().map(|n| ObjectOutput::named(n)).collect();
        Self::with_outputs(config, &objects, ros_time_offset_ns, None)
    }

    /// Like [`Self::new`], with the objects' bounding boxes for the detections, and, with `control`, the
    /// set-pose subscriptions and reset service (when `config.control`) sending their commands there.
    pub fn with_outputs(
        config: &ZenohConfig,
        objects: &[ObjectOutput],
        ros_time_offset_ns: i64,
        control: Option<ControlSender>,
    ) -> Result<Self, ZenohSetupError> {
        check_object_names(objects)?;
        let names: Vec<String> = objects.iter().map(|o| o.name.clone()).collect();
        let zconfig = config.to_zenoh_config()?;
        let session = zenoh::open(zconfig)
            .wait()
            .map_err(|e| ZenohSetupError::Open(e.to_string()))?;
        let node = RosNodeIdentity {
            domain_id: config.domain_id,
            zid: session.zid().to_string(),
            node_id: 0,
            enclave: "/".into(),
            namespace: ros2::fully_qualified_topic(&config.node_namespace),
            name: config.node_name.clone(),
        };
        let options = SendOptions {
            priority: Priority::RealTime,
            express: config.express,
            congestion: match config.congestion_control {
                CongestionPolicy::Drop => CongestionControl::Drop,
                CongestionPolicy::Block => CongestionControl::Block,
            },
        };
        let node_liveliness_key_expr = ros2::node_liveliness_key_expr(&node);
        let mut tokens = vec![declare_token(&session, &node_liveliness_key_expr)?];
        let mut entity = 0u64;
        let mut next_entity = || {
            entity += 1;
            entity
        };
        let mut pubs = Vec::with_capacity(objects.len());
        for name in &names {
            let topic = config.pose_topic(name);
            pubs.push(RosPublisher::declare(
                &session,
                &node,
                next_entity(),
                &topic,
                &types::POSE_STAMPED,
                options,
                &mut tokens,
            )?);
        }
        let mut optional =
            |on: bool, topic: String, ty| -> Result<Option<RosPublisher>, ZenohSetupError> {
                on.then(|| {
                    RosPublisher::declare(
                        &session,
                        &node,
                        next_entity(),
                        &topic,
                        ty,
                        options,
                        &mut tokens,
                    )
                })
                .transpose()
            };
        let tf = optional(config.tf, config.tf_topic.clone(), &types::TF_MESSAGE)?;
        let detections = optional(
            config.detections,
            config.detections_topic(),
            &types::DETECTION3D_ARRAY,
        )?;
        let diagnostics = optional(
            config.diagnostics,
            config.diagnostics_topic(),
            &types::DIAGNOSTIC_ARRAY,
        )?;
        let last_control = Arc::new(Mutex::new(vec![None; objects.len()]));
        let control = match control.filter(|_| config.control) {
            Some(sender) => Some(commands::declare(
                &session,
                &node,
                next_entity(),
                config,
                &names,
                (sender, last_control.clone()),
                &mut tokens,
            )?),
            None => None,
        };
        let outputs = TickOutputs {
            content: OutputContent {
                objects: objects.to_vec(),
                child_frames: names.iter().map(|n| config.tf_child_frame(n)).collect(),
                frame_id: config.frame_id.clone(),
                node_name: config.node_name.clone(),
                last_control,
            },
            tf,
            detections,
            diagnostics,
        };

        let status_key_expr = config.status_key_expr();
        let status = session
            .declare_publisher(status_key_expr.clone())
            .encoding(Encoding::APPLICATION_JSON)
            .congestion_control(CongestionControl::Drop)
            .wait()
            .map_err(|e| ZenohSetupError::Declare {
                what: "publisher",
                key: status_key_expr.clone(),
                message: e.to_string(),
            })?;

        let recent = Arc::new(Mutex::new(RecentPoses::new(objects.len())));
        let query_counters = Arc::new(PoseQueryCounters::default());
        let mut queryables = Vec::new();
        if config.pose_queries {
            for (object, name) in names.iter().enumerate() {
                let key = config.pose_query_key_expr(name);
                let context = pose_query::QueryContext {
                    name: name.clone(),
                    object,
                    recent: Arc::clone(&recent),
                    counters: Arc::clone(&query_counters),
                    ros_time_offset_ns,
                };
                let queryable = session
                    .declare_queryable(key.clone())
                    .callback(move |query| context.reply(&query))
                    .wait()
                    .map_err(|e| ZenohSetupError::Declare {
                        what: "queryable",
                        key: key.clone(),
                        message: e.to_string(),
                    })?;
                queryables.push((key, queryable));
            }
        }

        let buffer = Vec::with_capacity(ros2::pose_stamped_encoded_len(config.frame_id.len()));
        Ok(Self {
            session,
            objects: pubs,
            outputs,
            control,
            status,
            status_key_expr,
            node_liveliness_key_expr,
            tokens,
            frame_id: config.frame_id.clone(),
            ros_time_offset_ns,
            buffer,
            counters: SinkCounters::default(),
            status_counters: SinkCounters::default(),
            recent,
            queryables,
            query_counters,
        })
    }

    /// The zenoh session id, as it appears in the liveliness tokens.
    pub fn zid(&self) -> String {
        self.session.zid().to_string()
    }

    /// The rmw_zenoh data key expression of object `object` (index into the constructor's `objects`).
    pub fn pose_key_expr(&self, object: usize) -> Option<&str> {
        self.objects.get(object).map(|p| p.key_expr.as_str())
    }

    /// The GID that object `object`'s samples carry in their attachment.
    pub fn gid(&self, object: usize) -> Option<[u8; ros2::GID_LEN]> {
        self.objects.get(object).map(|p| p.gid)
    }

    /// The key expression of object `object`'s pose queries, if they are on.
    pub fn pose_query_key_expr(&self, object: usize) -> Option<&str> {
        self.queryables.get(object).map(|(key, _)| key.as_str())
    }

    /// Pose queries answered and refused so far: (answered, refused).
    pub fn pose_query_counts(&self) -> (u64, u64) {
        self.query_counters.get()
    }

    /// The key expression of the JSON status.
    pub fn status_key_expr(&self) -> &str {
        &self.status_key_expr
    }

    /// The liveliness tokens declared while the sink lives: the node's first, then one per pose publisher, then
    /// TF, detections and diagnostics (those on), then the control subscriptions and the reset service.
    pub fn liveliness_key_exprs(&self) -> Vec<&str> {
        let o = &self.outputs;
        std::iter::once(self.node_liveliness_key_expr.as_str())
            .chain(self.objects.iter().map(|p| p.token_key.as_str()))
            .chain(
                [&o.tf, &o.detections, &o.diagnostics]
                    .into_iter()
                    .flatten()
                    .map(|p| p.token_key.as_str()),
            )
            .chain(
                self.control
                    .iter()
                    .flat_map(|c| c.token_keys.iter().map(String::as_str)),
            )
            .collect()
    }

    /// The data key expressions of TF, detections and diagnostics (`None` when off).
    pub fn output_key_exprs(&self) -> [Option<&str>; 3] {
        let o = &self.outputs;
        [&o.tf, &o.detections, &o.diagnostics].map(|p| p.as_ref().map(|p| p.key_expr.as_str()))
    }

    /// Puts a status document (JSON bytes, built by the runtime) on the status key. Failures are counted in
    /// [`Self::status_counters`] and returned.
    pub fn put_status(&mut self, json: &[u8]) -> Result<(), PublishError> {
        match self.status.put(json).wait() {
            Ok(()) => {
                self.status_counters.published += 1;
                Ok(())
            }
            Err(e) => {
                self.status_counters.failed += 1;
                Err(transport(format!(
                    "status put on {:?}: {e}",
                    self.status_key_expr
                )))
            }
        }
    }

    /// Status puts done and failed so far.
    pub fn status_counters(&self) -> SinkCounters {
        self.status_counters
    }

    /// Undeclares the liveliness tokens and closes the session (also done, without reporting errors, on drop).
    pub fn close(mut self) -> Result<(), PublishError> {
        let mut first_err = None;
        for token in self.tokens.drain(..) {
            if let Err(e) = token.undeclare().wait() {
                first_err.get_or_insert(format!("undeclaring a liveliness token: {e}"));
            }
        }
        if let Err(e) = self.session.close().wait() {
            first_err.get_or_insert(format!("closing the session: {e}"));
        }
        first_err.map_or(Ok(()), |m| Err(transport(m)))
    }

    fn publish_one(&mut self, estimate: &tracker::track::PoseEstimate) -> Result<(), String> {
        let stamp = stamp_of(estimate.t_us, self.ros_time_offset_ns)?;
        let n_objects = self.objects.len();
        let p = self.objects.get_mut(estimate.object).ok_or_else(|| {
            format!(
                "object index {} but only {n_objects} publishers",
                estimate.object
            )
        })?;
        ros2::encode_pose_stamped_isometry(&mut self.buffer, stamp, &self.frame_id, &estimate.pose);
        p.put(&self.buffer)
    }

    /// TF, detections and diagnostics of a tick; returns the first failure.
    fn publish_outputs(&mut self, poses: &TickPoses<'_>) -> Option<String> {
        let o = &mut self.outputs;
        let offset = self.ros_time_offset_ns;
        let mut first_err = None;
        type Encode = fn(&OutputContent, &TickPoses<'_>, i64, &mut Vec<u8>) -> Result<(), String>;
        let jobs: [(&mut Option<RosPublisher>, Encode); 3] = [
            (&mut o.tf, OutputContent::tf),
            (&mut o.detections, OutputContent::detections),
            (&mut o.diagnostics, OutputContent::diagnostics),
        ];
        for (publisher, encode) in jobs {
            let Some(publisher) = publisher else {
                continue;
            };
            if let Err(e) = encode(&o.content, poses, offset, &mut self.buffer)
                .and_then(|()| publisher.put(&self.buffer))
            {
                first_err.get_or_insert(e);
            }
        }
        first_err
    }
}

impl PoseSink for ZenohPosePublisher {
    fn name(&self) -> &str {
        SINK_NAME
    }

    /// Publishes every estimate on its object's key; a failure is counted and the other objects are still published.
    fn publish(&mut self, poses: &TickPoses<'_>) -> Result<(), PublishError> {
        if !self.queryables.is_empty()
            && let Ok(mut recent) = self.recent.lock()
        {
            for estimate in poses.estimates {
                recent.record(estimate);
            }
        }
        let mut first_err = None;
        for estimate in poses.estimates {
            match self.publish_one(estimate) {
                Ok(()) => self.counters.published += 1,
                Err(message) => {
                    self.counters.failed += 1;
                    first_err.get_or_insert(message);
                }
            }
        }
        if let Some(e) = self.publish_outputs(poses) {
            self.counters.failed += 1;
            first_err.get_or_insert(e);
        }
        first_err.map_or(Ok(()), |m| Err(transport(m)))
    }

    /// Takes the tracker's revised poses into the poses queries answer from (the topic keeps what it sent).
    fn revise(&mut self, revised: &[tracker::track::PoseEstimate]) {
        if !self.queryables.is_empty()
            && let Ok(mut recent) = self.recent.lock()
        {
            for estimate in revised {
                recent.revise(estimate);
            }
        }
    }

    fn counters(&self) -> SinkCounters {
        self.counters
    }
}

fn transport(message: String) -> PublishError {
    PublishError::Transport {
        sink: SINK_NAME.into(),
        message,
    }
}

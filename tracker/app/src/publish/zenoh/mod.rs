//! The zenoh sink: every object's pose as `geometry_msgs/msg/PoseStamped` on its rmw_zenoh key, so that ROS 2 nodes
//! using `rmw_zenoh_cpp` receive it unchanged, plus a JSON status key and the liveliness tokens that make the
//! publishers visible in the ROS 2 graph. Wire formats are in [`super::ros2`]; `docs/zenoh-ros2.md` explains them.
//!
//! The sink uses zenoh's synchronous API (`.wait()`), so it is called from a plain thread (zenoh runs its own tokio
//! runtime inside). A transport failure is counted and returned as [`PublishError`], never a panic.

mod config;
mod pose_query;
mod query_parameters;
#[cfg(test)]
mod tests;

pub use config::{CongestionPolicy, SessionMode, ZenohConfig, ZenohSetupError};
pub use pose_query::{
    MAX_EXTRAPOLATION_US, PoseQueryCounters, PoseQueryError, RECENT_TICKS, RecentPoses,
    requested_time,
};

use super::ros2::{self, Attachment, RosNodeIdentity, RosTime};
use super::{PoseSink, PublishError, SinkCounters, TickPoses};
use std::hash::{BuildHasher, Hasher};
use std::sync::{Arc, Mutex};
use std::time::{SystemTime, UNIX_EPOCH};
use zenoh::Wait;
use zenoh::bytes::Encoding;
use zenoh::liveliness::LivelinessToken;
use zenoh::pubsub::Publisher;
use zenoh::qos::{CongestionControl, Priority};

/// Sink name used in errors, logs and the status topic.
pub const SINK_NAME: &str = "zenoh";

/// One object's publisher and its rmw_zenoh bookkeeping.
struct ObjectPublisher {
    publisher: Publisher<'static>,
    key_expr: String,
    liveliness_key_expr: String,
    gid: [u8; ros2::GID_LEN],
    next_sequence: i64,
}

/// Publishes poses over zenoh in rmw_zenoh's format; see the module documentation.
///
/// Header stamps: `header.stamp = t_us * 1000 + ros_time_offset_ns` nanoseconds, i.e. the pose's time on the event
/// camera's clock shifted into ROS time by an offset fixed at construction. With offset 0 the stamp is the camera
/// clock itself; to stamp in ROS (system) time, the runtime passes `system_time_ns - camera_time_ns` measured at one
/// instant (e.g. when the first trigger edge is decoded).
pub struct ZenohPosePublisher {
    session: zenoh::Session,
    objects: Vec<ObjectPublisher>,
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

impl ZenohPosePublisher {
    /// Opens a zenoh session from `config`, declares one pose publisher per object (in `objects` order, matching
    /// [`tracker::track::PoseEstimate::object`]), the status publisher, and the node and publisher liveliness tokens.
    /// Returns promptly when no router is reachable (peer mode retries in the background).
    pub fn new(
        config: &ZenohConfig,
        objects: &[String],
        ros_time_offset_ns: i64,
    ) -> Result<Self, ZenohSetupError> {
        for (i, name) in objects.iter().enumerate() {
            ros2::check_name_token(name).map_err(|reason| ZenohSetupError::ObjectName {
                name: name.clone(),
                reason,
            })?;
            if objects[..i].contains(name) {
                return Err(ZenohSetupError::ObjectName {
                    name: name.clone(),
                    reason: "appears twice".into(),
                });
            }
        }
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
        let congestion = match config.congestion_control {
            CongestionPolicy::Drop => CongestionControl::Drop,
            CongestionPolicy::Block => CongestionControl::Block,
        };

        let declare_token = |key: &str| {
            session
                .liveliness()
                .declare_token(key.to_owned())
                .wait()
                .map_err(|e| ZenohSetupError::Declare {
                    what: "liveliness token",
                    key: key.to_owned(),
                    message: e.to_string(),
                })
        };
        let node_liveliness_key_expr = ros2::node_liveliness_key_expr(&node);
        let mut tokens = vec![declare_token(&node_liveliness_key_expr)?];

        let mut pubs = Vec::with_capacity(objects.len());
        for (i, name) in objects.iter().enumerate() {
            let topic = config.pose_topic(name);
            let key_expr = ros2::pose_stamped_key_expr(config.domain_id, &topic);
            let publisher = session
                .declare_publisher(key_expr.clone())
                .priority(Priority::RealTime)
                .express(config.express)
                .congestion_control(congestion)
                .wait()
                .map_err(|e| ZenohSetupError::Declare {
                    what: "publisher",
                    key: key_expr.clone(),
                    message: e.to_string(),
                })?;
            let entity_id = i as u64 + 1;
            let liveliness_key_expr = ros2::publisher_liveliness_key_expr(
                &node,
                entity_id,
                &topic,
                ros2::POSE_STAMPED_TYPE_NAME,
                ros2::POSE_STAMPED_TYPE_HASH,
                ros2::DEFAULT_QOS_KEY,
            );
            tokens.push(declare_token(&liveliness_key_expr)?);
            pubs.push(ObjectPublisher {
                publisher,
                key_expr,
                liveliness_key_expr,
                gid: random_gid(&node.zid, entity_id),
                next_sequence: 1,
            });
        }

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
            for (object, name) in objects.iter().enumerate() {
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

    /// The liveliness tokens declared while the sink lives: the node's first, then one per pose publisher.
    pub fn liveliness_key_exprs(&self) -> Vec<&str> {
        std::iter::once(self.node_liveliness_key_expr.as_str())
            .chain(self.objects.iter().map(|p| p.liveliness_key_expr.as_str()))
            .collect()
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
        let stamp_ns = estimate
            .t_us
            .checked_mul(1000)
            .and_then(|ns| ns.checked_add(self.ros_time_offset_ns))
            .ok_or_else(|| {
                format!(
                    "pose time {} us + offset overflows i64 nanoseconds",
                    estimate.t_us
                )
            })?;
        let stamp = RosTime::from_nanos(stamp_ns).map_err(|e| e.to_string())?;
        let n_objects = self.objects.len();
        let p = self.objects.get_mut(estimate.object).ok_or_else(|| {
            format!(
                "object index {} but only {n_objects} publishers",
                estimate.object
            )
        })?;
        ros2::encode_pose_stamped_isometry(&mut self.buffer, stamp, &self.frame_id, &estimate.pose);
        let attachment = Attachment {
            sequence_number: p.next_sequence,
            source_timestamp_ns: system_time_ns(),
            gid: p.gid,
        }
        .to_bytes();
        p.next_sequence += 1;
        p.publisher
            .put(self.buffer.as_slice())
            .attachment(attachment)
            .wait()
            .map_err(|e| format!("put on {:?}: {e}", p.key_expr))
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

/// Nanoseconds since the Unix epoch on the system clock (0 if the clock is before 1970, saturated past 2262).
fn system_time_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| i64::try_from(d.as_nanos()).unwrap_or(i64::MAX))
}

/// A random 16-byte GID: std's randomly keyed SipHash (keys seeded from the OS) over the session id, the entity id
/// and the time, as rmw_zenoh's publishers draw theirs at random.
fn random_gid(zid: &str, entity_id: u64) -> [u8; ros2::GID_LEN] {
    let mut gid = [0u8; ros2::GID_LEN];
    for (half, chunk) in gid.chunks_mut(8).enumerate() {
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write(zid.as_bytes());
        h.write_u64(entity_id);
        h.write_usize(half);
        h.write_i64(system_time_ns());
        chunk.copy_from_slice(&h.finish().to_le_bytes());
    }
    gid
}
